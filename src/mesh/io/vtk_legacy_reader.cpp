// Legacy VTK reader: ASCII UNSTRUCTURED_GRID with POINTS, CELLS (classic "n i0 i1 ..." records
// or the 5.1 OFFSETS/CONNECTIVITY arrays) and CELL_TYPES. Point and cell data are ignored.
#include "mesh/io/mesh_io.hpp"
#include "mesh/io/text_reader.hpp"
#include "mesh/io/vtk_cells.hpp"

#include <algorithm>

namespace sh {
namespace {

class VtkLegacyReader {
public:
    VtkLegacyReader(const std::string& path, std::string_view text) : r_(path, text) {}

    MeshData read() {
        read_header();
        for (std::string_view key = r_.next_token(); !key.empty(); key = r_.next_token()) {
            if (equals_nocase(key, "POINTS")) {
                read_points();
            } else if (equals_nocase(key, "CELLS")) {
                read_cells();
            } else if (equals_nocase(key, "CELL_TYPES")) {
                read_types();
            } else if (equals_nocase(key, "METADATA")) {
                skip_metadata();
            } else if (equals_nocase(key, "POINT_DATA") || equals_nocase(key, "CELL_DATA") ||
                       equals_nocase(key, "FIELD")) {
                break;  // attributes follow the geometry: nothing more is needed
            } else {
                r_.fail(format("expected POINTS, CELLS or CELL_TYPES, got %s (does the count of the "
                               "previous section match its data?)", quoted(key).c_str()));
            }
        }
        if (!have_points_) r_.fail("no POINTS section in the file");
        if (!have_cells_) r_.fail("no CELLS section in the file");
        if (!have_types_) r_.fail("no CELL_TYPES section in the file");
        append_vtk_tets(cells_, r_, mesh_);
        return std::move(mesh_);
    }

private:
    // "# vtk DataFile Version x.y", a title line, ASCII, "DATASET UNSTRUCTURED_GRID".
    void read_header() {
        if (!starts_with_nocase(r_.next_raw_line(), "# vtk DataFile Version"))
            r_.fail("not a legacy VTK file: the first line must be '# vtk DataFile Version x.y'");
        if (r_.remaining() == 0) r_.fail("unexpected end of file after the version line");
        r_.next_raw_line();  // the title: free text
        const std::string_view encoding = r_.expect_token("the file type (ASCII or BINARY)");
        if (equals_nocase(encoding, "BINARY"))
            r_.unsupported("binary legacy VTK files are not supported: save the mesh as ASCII");
        if (!equals_nocase(encoding, "ASCII"))
            r_.fail(format("expected ASCII or BINARY, got %s", quoted(encoding).c_str()));
        const std::string_view dataset = r_.expect_token("DATASET");
        if (!equals_nocase(dataset, "DATASET")) r_.fail(format("expected DATASET, got %s", quoted(dataset).c_str()));
        const std::string_view kind = r_.expect_token("the dataset type");
        if (!equals_nocase(kind, "UNSTRUCTURED_GRID"))
            r_.unsupported(format("DATASET %s is not supported: only UNSTRUCTURED_GRID holds tetrahedra",
                                  printable(kind).c_str()));
    }

    // "POINTS n type" and 3n coordinates.
    void read_points() {
        if (have_points_) r_.fail("second POINTS section");
        have_points_ = true;
        const int32_t count = r_.to_count(r_.expect_token("the point count"), "the point count");
        r_.expect_token("the point data type");
        mesh_.nodes.reserve(3 * std::min<size_t>(count, r_.max_records(3)));
        for (int64_t i = 0; i < 3 * static_cast<int64_t>(count); ++i)
            mesh_.nodes.push_back(r_.read_double("a point coordinate"));
    }

    // "CELLS n size" then n records "k i0 .. ik-1" (size values in all), or, from VTK 5.1,
    // "CELLS offset-count connectivity-size", "OFFSETS type" values, "CONNECTIVITY type" values.
    void read_cells() {
        if (have_cells_) r_.fail("second CELLS section");
        have_cells_ = true;
        const int32_t first = r_.to_count(r_.expect_token("the cell count"), "the cell count");
        const int32_t second = r_.to_count(r_.expect_token("the cell list size"), "the cell list size");
        const std::string_view next = r_.expect_token("the cells");
        if (equals_nocase(next, "OFFSETS")) read_cells_5_1(first, second);
        else read_cells_classic(first, second, next);
    }

    void read_cells_classic(int32_t count, int32_t size, std::string_view first_token) {
        cells_.offsets_line = r_.line();
        cells_.offsets.reserve(std::min<size_t>(count, r_.max_records(2)));
        cells_.connectivity.reserve(std::min<size_t>(size, r_.max_records(1)));
        cells_.connectivity_lines.reserve(cells_.connectivity.capacity());
        int64_t values = 0;
        std::string_view token = first_token;
        for (int32_t c = 0; c < count; ++c) {
            if (c > 0) token = r_.expect_token("a cell's node count");
            const int64_t nodes = r_.to_int(token, "a cell's node count");
            if (nodes < 0) r_.fail(format("cell %d has a negative node count %lld", c, static_cast<long long>(nodes)));
            if (nodes > size - values - 1)  // compared before adding: nodes may be absurdly large
                r_.fail(format("CELLS header says the list holds %d values but cell %d goes past it", size, c));
            values += 1 + nodes;
            const int line = r_.line();
            for (int64_t a = 0; a < nodes; ++a) {
                cells_.connectivity.push_back(r_.read_int("a cell's node index"));
                cells_.connectivity_lines.push_back(line);
            }
            cells_.offsets.push_back(static_cast<int64_t>(cells_.connectivity.size()));
        }
        if (values != size)
            r_.fail(format("CELLS header says the list holds %d values but the %d cells hold %lld", size, count,
                           static_cast<long long>(values)));
    }

    void read_cells_5_1(int32_t offset_count, int32_t size) {
        r_.expect_token("the offsets data type");
        cells_.offsets_line = r_.line();
        read_int_array(offset_count, cells_.offsets, nullptr, "an offset");
        if (!cells_.offsets.empty()) {
            if (cells_.offsets.front() != 0) r_.fail_at(cells_.offsets_line, "the first offset must be 0");
            cells_.offsets.erase(cells_.offsets.begin());
        }
        const std::string_view key = r_.expect_token("CONNECTIVITY");
        if (!equals_nocase(key, "CONNECTIVITY")) r_.fail(format("expected CONNECTIVITY, got %s", quoted(key).c_str()));
        r_.expect_token("the connectivity data type");
        read_int_array(size, cells_.connectivity, &cells_.connectivity_lines, "a node index");
    }

    // "CELL_TYPES n" and n types.
    void read_types() {
        if (have_types_) r_.fail("second CELL_TYPES section");
        have_types_ = true;
        const int32_t count = r_.to_count(r_.expect_token("the cell type count"), "the cell type count");
        cells_.types_line = r_.line();
        read_int_array(count, cells_.types, nullptr, "a cell type");
    }

    // Reads count integers into out (and each one's line into lines if given).
    void read_int_array(int32_t count, vec<int64_t>& out, vec<int32_t>* lines, const char* what) {
        out.reserve(std::min<size_t>(count, r_.max_records(1)));
        for (int32_t i = 0; i < count; ++i) {
            out.push_back(r_.read_int(what));
            if (lines) lines->push_back(r_.line());
        }
    }

    // "METADATA" blocks (VTK 5.1) run up to the next empty line.
    void skip_metadata() {
        r_.next_raw_line();  // the rest of the METADATA line
        while (r_.remaining() > 0) {
            const std::string_view line = r_.next_raw_line();
            if (line.find_first_not_of(" \t\r") == std::string_view::npos) return;
        }
    }

    TextReader r_;
    MeshData mesh_;
    VtkCells cells_;
    bool have_points_ = false;
    bool have_cells_ = false;
    bool have_types_ = false;
};

}  // namespace

MeshData read_vtk_legacy(const std::string& path, std::string_view text) {
    return VtkLegacyReader(path, text).read();
}

}  // namespace sh
