// TetGen reader: a .node file (points) and a .ele file (tetrahedra) with the same stem. Indices
// start at 0 or 1 (the first node decides); attributes and boundary markers are read past;
// '#' starts a comment. 10-node (quadratic) tets are skipped and counted.
#include "mesh/io/mesh_io.hpp"
#include "mesh/io/text_reader.hpp"

#include <algorithm>

namespace sh {
namespace {

// Reads record i of count (a line with `fields` fields) into f.
void read_record(TextReader& r, Fields& f, int32_t i, int32_t count, const char* what, size_t fields) {
    if (!r.next_line(f, '#'))
        r.fail(format("unexpected end of file after %d of the %d %s the header announces", i, count, what));
    if (f.size() != fields) r.fail(format("expected %zu fields for one of the %s, got %zu", fields, what, f.size()));
}

// Fails if anything but comments follows the last record.
void expect_no_more(TextReader& r, Fields& f, int32_t count, const char* what) {
    if (r.next_line(f, '#'))
        r.fail(format("more lines than the %d %s the header announces", count, what));
}

// Reads a header line "<count> [optional...]": returns the count (named count_name in
// messages) and overwrites each of the optional values (which hold their defaults) the line gives.
int32_t read_header(TextReader& r, Fields& f, const char* what, const char* count_name, int64_t* optional,
                    size_t optional_count) {
    r.expect_line(f, what, '#');
    if (f.size() > 1 + optional_count)
        r.fail(format("expected at most %zu fields for %s, got %zu", 1 + optional_count, what, f.size()));
    const int32_t count = r.to_count(f[0], count_name);
    for (size_t i = 1; i < f.size(); ++i) optional[i - 1] = r.to_int(f[i], what);
    return count;
}

class TetgenReader {
public:
    MeshData read(const std::string& path, std::string_view text) {
        const size_t dot = path.find_last_of('.');
        const std::string stem = path.substr(0, dot);
        if (equals_nocase(std::string_view(path).substr(dot + 1), "node")) {
            read_nodes(TextReader(path, text));
            read_elements(TextReader(stem + ".ele", read_beside(stem + ".ele")));
        } else {
            read_nodes(TextReader(stem + ".node", read_beside(stem + ".node")));
            read_elements(TextReader(path, text));
        }
        return std::move(mesh_);
    }

private:
    // "<points> <dimension> <attributes> <boundary markers>", then "<index> x y z [attributes] [marker]".
    void read_nodes(TextReader r) {
        int64_t header[3] = {3, 0, 0};  // dimension, attributes, boundary markers
        const int32_t count = read_header(r, f_, "the .node header", "the node count", header, 3);
        const int64_t dimension = header[0], attributes = header[1], markers = header[2];
        if (dimension != 3)
            r.unsupported(format("dimension %lld: only 3D TetGen meshes are supported", static_cast<long long>(dimension)));
        if (attributes < 0 || attributes > 1000 || (markers != 0 && markers != 1))
            r.fail("the attribute count must be in [0, 1000] and the boundary marker count 0 or 1");
        const size_t fields = 4 + static_cast<size_t>(attributes + markers);
        mesh_.nodes.reserve(3 * std::min<size_t>(count, r.max_records(static_cast<int>(fields))));
        for (int32_t i = 0; i < count; ++i) {
            read_record(r, f_, i, count, "nodes", fields);
            const int64_t index = r.to_int(f_[0], "the node index");
            if (i == 0) {
                if (index != 0 && index != 1)
                    r.fail(format("the first node index is %lld, must be 0 or 1", static_cast<long long>(index)));
                base_ = index;
            } else if (index != base_ + i) {
                r.fail(format("node index %lld out of sequence, expected %lld", static_cast<long long>(index),
                              static_cast<long long>(base_ + i)));
            }
            for (int k = 1; k <= 3; ++k) mesh_.nodes.push_back(r.to_double(f_[static_cast<size_t>(k)], "a node coordinate"));
        }
        expect_no_more(r, f_, count, "nodes");
    }

    // "<tets> <nodes per tet (4 or 10)> <region attribute (0 or 1)>", then "<index> nodes... [attribute]".
    void read_elements(TextReader r) {
        int64_t header[2] = {4, 0};  // nodes per tet, region attributes
        const int32_t count = read_header(r, f_, "the .ele header", "the tet count", header, 2);
        const int64_t nodes = header[0], attributes = header[1];
        if (nodes != 4 && nodes != 10) r.fail(format("nodes per tet is %lld, must be 4 or 10", static_cast<long long>(nodes)));
        if (attributes < 0 || attributes > 1000) r.fail("the region attribute count must be in [0, 1000]");
        const size_t fields = 1 + static_cast<size_t>(nodes + attributes);
        const size_t cap = std::min<size_t>(count, r.max_records(static_cast<int>(fields)));
        mesh_.tets.reserve(4 * cap);
        mesh_.tet_lines.reserve(cap);
        for (int32_t i = 0; i < count; ++i) {
            read_record(r, f_, i, count, "tets", fields);
            if (nodes != 4) {
                ++mesh_.skipped_elements;
                continue;
            }
            for (size_t a = 1; a <= 4; ++a) {
                const int32_t index = r.to_index(r.to_int(f_[a], "a node index"), "node index");
                mesh_.tets.push_back(r.to_index(index - base_, "node index"));  // zero-based
            }
            mesh_.tet_lines.push_back(r.line());
        }
        expect_no_more(r, f_, count, "tets");
    }

    // Reads the companion file (kept alive in other_text_ while it is parsed).
    std::string_view read_beside(const std::string& other) {
        try {
            other_text_ = read_text_file(other);
        } catch (const Error& e) {
            throw Error(e.status(), e.message() + " (TetGen needs the .node and .ele files side by side)");
        }
        return std::string_view(other_text_.data(), other_text_.size());
    }

    vec<char> other_text_;  // the file found beside the given one
    Fields f_;
    MeshData mesh_;
    int64_t base_ = 0;  // index of the first node: 0 or 1
};

}  // namespace

MeshData read_tetgen(const std::string& path, std::string_view text) { return TetgenReader().read(path, text); }

}  // namespace sh
