// VTK XML UnstructuredGrid reader (.vtu) for ascii DataArrays: Points, and the connectivity,
// offsets and types of Cells. The Piece's NumberOfPoints and NumberOfCells must match the data.
// Binary, base64 and appended data are refused with SH_ERR_UNSUPPORTED.
#include "mesh/io/mesh_io.hpp"
#include "mesh/io/text_reader.hpp"
#include "mesh/io/vtk_cells.hpp"
#include "mesh/io/xml_scanner.hpp"

#include <string>

namespace sh {
namespace {

class VtuReader {
public:
    VtuReader(const std::string& path, std::string_view text) : r_(path, text), xml_(r_, text) {}

    MeshData read() {
        scan();
        check();
        mesh_.nodes = std::move(points_);
        append_vtk_tets(cells_, r_, mesh_);
        return std::move(mesh_);
    }

private:
    // Which array the current <DataArray> fills.
    enum class Target { None, Points, Connectivity, Offsets, Types };

    // Walks the XML, collecting the four arrays and the Piece's counts.
    void scan() {
        for (;;) {
            const XmlEvent e = xml_.next();
            if (e.kind == XmlEvent::End) {
                last_line_ = e.line;
                break;
            }
            if (e.kind == XmlEvent::Text) {
                on_text(e);
            } else if (e.kind == XmlEvent::Close) {
                on_close(e);
                if (stack_.empty()) return;  // </VTKFile>: ignore what follows
            } else if (e.name == "AppendedData") {
                return;  // raw bytes follow; any array we need in there was already refused
            } else {
                on_open(e);
            }
        }
        if (!stack_.empty())
            r_.fail_at(last_line_, format("unexpected end of file: <%s> opened on line %d is not closed",
                                          printable(stack_.back().name).c_str(), stack_.back().line));
        if (!seen_root_) r_.fail_at(1, "not a VTK XML file: no <VTKFile> element");
    }

    void on_text(const XmlEvent& e) {
        last_line_ = e.line;
        if (stack_.empty()) {
            if (e.text.find_first_not_of(" \t\r\n") != std::string_view::npos)
                r_.fail_at(e.line, "not a VTK XML file: text outside the <VTKFile> element");
            return;
        }
        if (target_ == Target::None || stack_.back().name != "DataArray") return;
        TextReader data(r_.path(), e.text, e.line);
        if (target_ == Target::Points) {
            for (std::string_view t = data.next_token(); !t.empty(); t = data.next_token())
                points_.push_back(data.to_double(t, "a point coordinate"));
            return;
        }
        vec<int64_t>& out = target_ == Target::Connectivity ? cells_.connectivity
                            : target_ == Target::Offsets    ? cells_.offsets
                                                            : cells_.types;
        for (std::string_view t = data.next_token(); !t.empty(); t = data.next_token()) {
            out.push_back(data.to_int(t, "an integer"));
            if (target_ == Target::Connectivity) cells_.connectivity_lines.push_back(data.line());
        }
    }

    void on_close(const XmlEvent& e) {
        last_line_ = e.line;
        if (stack_.empty() || stack_.back().name != e.name)
            r_.fail_at(e.line, stack_.empty()
                                   ? format("</%s> closes nothing", printable(e.name).c_str())
                                   : format("</%s> does not close <%s> opened on line %d", printable(e.name).c_str(),
                                            printable(stack_.back().name).c_str(), stack_.back().line));
        stack_.pop_back();
        if (e.name == "DataArray") target_ = Target::None;
    }

    void on_open(const XmlEvent& e) {
        last_line_ = e.line;
        if (stack_.empty()) open_root(e);
        else if (e.name == "Piece") open_piece(e);
        else if (e.name == "DataArray") open_data_array(e);
        if (!e.self_closing) stack_.push_back({e.name, e.line});
        else if (e.name == "DataArray") target_ = Target::None;  // <DataArray .../> holds no data
    }

    void open_root(const XmlEvent& e) {
        if (seen_root_ || e.name != "VTKFile")
            r_.fail_at(e.line, format("not a VTK XML file: expected <VTKFile>, got <%s>", printable(e.name).c_str()));
        seen_root_ = true;
        std::string_view type;
        if (!xml_attribute(e.attributes, "type", type)) r_.fail_at(e.line, "<VTKFile> has no type attribute");
        if (type != "UnstructuredGrid")
            r_.unsupported_at(e.line, format("VTKFile type '%s' is not supported: only UnstructuredGrid holds tetrahedra",
                                          printable(type).c_str()));
    }

    void open_piece(const XmlEvent& e) {
        if (piece_line_ != 0) r_.unsupported_at(e.line, "more than one <Piece> is not supported");
        piece_line_ = e.line;
        header_points_ = count_attribute(e, "NumberOfPoints");
        header_cells_ = count_attribute(e, "NumberOfCells");
    }

    int64_t count_attribute(const XmlEvent& e, const char* key) {
        std::string_view value;
        int64_t count = 0;
        if (!xml_attribute(e.attributes, key, value)) r_.fail_at(e.line, format("<Piece> has no %s attribute", key));
        if (!parse_int(value, count) || count < 0)
            r_.fail_at(e.line, format("%s is '%s', not a count", key, printable(value).c_str()));
        return count;
    }

    void open_data_array(const XmlEvent& e) {
        const std::string_view parent = stack_.back().name;
        std::string_view name;
        xml_attribute(e.attributes, "Name", name);
        target_ = Target::None;
        if (parent == "Points" && !have(Target::Points)) target_ = Target::Points;
        else if (parent == "Cells" && name == "connectivity") target_ = Target::Connectivity;
        else if (parent == "Cells" && name == "offsets") target_ = Target::Offsets;
        else if (parent == "Cells" && name == "types") target_ = Target::Types;
        if (target_ == Target::None) return;
        if (have(target_))
            r_.fail_at(e.line, format("second '%s' data array", printable(name.empty() ? "Points" : name).c_str()));
        seen_[static_cast<int>(target_)] = e.line;
        const std::string label = name.empty() ? std::string("Points") : printable(name);
        std::string_view data_format;
        if (!xml_attribute(e.attributes, "format", data_format))
            r_.fail_at(e.line, format("DataArray '%s' has no format attribute", label.c_str()));
        if (data_format == "binary" || data_format == "appended")
            r_.unsupported_at(e.line, format("DataArray '%s' has format=\"%s\": only ascii data is supported "
                                          "(save the file with ascii data)",
                                          label.c_str(), printable(data_format).c_str()));
        if (data_format != "ascii")
            r_.fail_at(e.line, format("DataArray '%s' has unknown format \"%s\"", label.c_str(),
                                      printable(data_format).c_str()));
        if (target_ == Target::Points) {
            std::string_view components;
            if (!xml_attribute(e.attributes, "NumberOfComponents", components) || components != "3")
                r_.fail_at(e.line, "the Points DataArray must have NumberOfComponents=\"3\"");
        }
    }

    bool have(Target t) const { return seen_[static_cast<int>(t)] != 0; }

    // The arrays are all there and agree with the Piece's header.
    void check() {
        if (piece_line_ == 0) r_.fail_at(last_line_, "no <Piece> element");
        static const char* const kNames[] = {"", "Points", "connectivity", "offsets", "types"};
        for (int t = 1; t <= 4; ++t)
            if (seen_[t] == 0) r_.fail_at(last_line_, format("no '%s' DataArray in the file", kNames[t]));
        if (points_.size() % 3 != 0)
            r_.fail_at(seen_[static_cast<int>(Target::Points)],
                       format("the Points array holds %zu values, not a multiple of 3", points_.size()));
        const int64_t points = static_cast<int64_t>(points_.size() / 3);
        const int64_t cells = static_cast<int64_t>(cells_.offsets.size());
        std::string contradictions;
        if (points != header_points_)
            contradictions += format("header says %lld points but the data has %lld",
                                     static_cast<long long>(header_points_), static_cast<long long>(points));
        const int64_t types = static_cast<int64_t>(cells_.types.size());
        if (cells != header_cells_ || types != header_cells_) {
            if (!contradictions.empty()) contradictions += "; ";
            contradictions += format("header says %lld cells but the data has %lld", static_cast<long long>(header_cells_),
                                     static_cast<long long>(cells));
            if (types != cells) contradictions += format(" offsets and %lld types", static_cast<long long>(types));
        }
        if (!contradictions.empty()) r_.fail_at(piece_line_, contradictions);
        cells_.offsets_line = seen_[static_cast<int>(Target::Offsets)];
        cells_.types_line = seen_[static_cast<int>(Target::Types)];
    }

    struct Open {
        std::string_view name;
        int line;
    };

    TextReader r_;
    XmlScanner xml_;
    MeshData mesh_;
    vec<double> points_;
    VtkCells cells_;
    vec<Open> stack_;
    Target target_ = Target::None;
    int seen_[5] = {0, 0, 0, 0, 0};  // line of each Target's DataArray, 0 if not seen
    bool seen_root_ = false;
    int piece_line_ = 0;
    int last_line_ = 1;
    int64_t header_points_ = 0;
    int64_t header_cells_ = 0;
};

}  // namespace

MeshData read_vtu(const std::string& path, std::string_view text) { return VtuReader(path, text).read(); }

}  // namespace sh
