// Gmsh .msh reader: version 1 ($NOD/$ELM), 2.x ASCII and 4.1 ASCII. Node tags (arbitrary,
// possibly sparse) map to zero-based indices in file order; only 4-node tets are kept.
#include "mesh/io/mesh_io.hpp"
#include "mesh/io/text_reader.hpp"

#include <algorithm>

namespace sh {
namespace {

constexpr int64_t kGmshTet = 4;

// Nodes of the Gmsh element types this reader knows (0: unknown, not checked).
int gmsh_element_nodes(int64_t type) {
    static const int kNodes[] = {0, 2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1, 8, 20, 15,
                                 13, 9, 10, 12, 15, 15, 21, 4, 5, 6, 20, 35, 56};
    if (type >= 0 && type < static_cast<int64_t>(sizeof kNodes / sizeof kNodes[0]))
        return kNodes[type];
    if (type == 92) return 64;
    if (type == 93) return 125;
    return 0;
}

// Node tags in file order -> zero-based indices, looked up by binary search.
class NodeTags {
public:
    void add(int64_t tag, int32_t index, int line) { entries_.push_back({tag, index, line}); }

    // Sorts the tags; fails naming both lines if a tag appears twice.
    void finish(const TextReader& reader) {
        std::sort(entries_.begin(), entries_.end(),
                  [](const Entry& a, const Entry& b) { return a.tag < b.tag; });
        for (size_t i = 1; i < entries_.size(); ++i)
            if (entries_[i].tag == entries_[i - 1].tag) {
                const int first = std::min(entries_[i].line, entries_[i - 1].line);
                const int second = std::max(entries_[i].line, entries_[i - 1].line);
                reader.fail_at(second, format("node tag %lld already defined on line %d",
                                              static_cast<long long>(entries_[i].tag), first));
            }
    }

    // Index of tag, or -1 if no node has it.
    int32_t find(int64_t tag) const {
        const auto it = std::lower_bound(entries_.begin(), entries_.end(), tag,
                                         [](const Entry& e, int64_t t) { return e.tag < t; });
        return (it != entries_.end() && it->tag == tag) ? it->index : -1;
    }

private:
    struct Entry {
        int64_t tag;
        int32_t index;
        int line;
    };
    vec<Entry> entries_;
};

class GmshReader {
public:
    GmshReader(const std::string& path, std::string_view text) : r_(path, text) {}

    MeshData read() {
        while (r_.next_line(f_)) {
            const std::string_view head = f_[0];
            if (head.empty() || head[0] != '$')
                r_.fail(format("expected a section such as $MeshFormat, $Nodes or $Elements, got %s",
                               quoted(head).c_str()));
            if (head == "$MeshFormat") {
                read_format();
            } else if (head == "$NOD") {
                read_nodes_v1_v2("$NOD", "$ENDNOD");
            } else if (head == "$ELM") {
                read_elements_v1_v2("$ELM", "$ENDELM", 1);
            } else if (head == "$Nodes") {
                require_format("$Nodes");
                if (version_ == 4) read_nodes_v4();
                else read_nodes_v1_v2("$Nodes", "$EndNodes");
            } else if (head == "$Elements") {
                require_format("$Elements");
                if (version_ == 4) read_elements_v4();
                else read_elements_v1_v2("$Elements", "$EndElements", 2);
            } else {
                skip_section(head);
            }
        }
        if (!have_nodes_) r_.fail("no node section ($Nodes or $NOD) in the file");
        if (!have_elements_) r_.fail("no element section ($Elements or $ELM) in the file");
        return std::move(mesh_);
    }

private:
    // "$MeshFormat": version file-type data-size, then "$EndMeshFormat".
    void read_format() {
        r_.expect_line(f_, "the $MeshFormat line");
        if (f_.size() < 3) r_.fail(format("expected 3 fields (version file-type data-size), got %zu", f_.size()));
        const double version = r_.to_double(f_[0], "the format version");
        const int64_t file_type = r_.to_int(f_[1], "the file type");
        if (file_type != 0) r_.unsupported("binary Gmsh files are not supported: save the mesh as ASCII");
        if (version >= 2.0 && version < 3.0) version_ = 2;
        else if (f_[0] == "4.1") version_ = 4;
        else
            r_.unsupported(format("Gmsh format version %s is not supported (use 1, 2.2 or 4.1)",
                                  quoted(f_[0]).c_str()));
        expect_end("$EndMeshFormat", "the format line");
    }

    void require_format(const char* section) {
        if (version_ == 0) r_.fail(format("%s before $MeshFormat", section));
    }

    // Skips an unknown section "$Name" up to its "$EndName" (any letter case).
    void skip_section(std::string_view head) {
        const int start = r_.line();
        const std::string end = "$End" + std::string(head.substr(1));
        while (r_.next_line(f_))
            if (equals_nocase(f_[0], end)) return;
        r_.fail(format("unexpected end of file: section %s opened on line %d has no %s",
                       std::string(head).c_str(), start, end.c_str()));
    }

    // Reads the next line, which must be `marker`.
    void expect_end(const char* marker, const char* after) {
        if (!r_.next_line(f_)) r_.fail(format("unexpected end of file: expected %s after %s", marker, after));
        if (f_[0] != marker)
            r_.fail(format("expected %s after %s, got %s (does the count match the data?)", marker, after,
                           quoted(f_[0]).c_str()));
    }

    // Reads record i of count of a section into f_; fails if the file or section ends first.
    void expect_record(const char* section, int64_t i, int64_t count, const char* what) {
        if (!r_.next_line(f_))
            r_.fail(format("unexpected end of file in %s after %lld of %lld %s", section,
                           static_cast<long long>(i), static_cast<long long>(count), what));
        if (f_[0][0] == '$')
            r_.fail(format("%s ended after %lld of the %lld %s its header announces", section,
                           static_cast<long long>(i), static_cast<long long>(count), what));
    }

    // Reads a line holding one count.
    int32_t read_count_line(const char* what) {
        r_.expect_line(f_, what);
        if (f_.size() != 1) r_.fail(format("expected 1 field for %s, got %zu", what, f_.size()));
        return r_.to_count(f_[0], what);
    }

    // Appends the node whose tag token and x, y, z tokens are given.
    void add_node(std::string_view tag, const std::string_view* xyz) {
        const int32_t index = static_cast<int32_t>(mesh_.nodes.size() / 3);
        tags_.add(r_.to_int(tag, "a node tag"), index, r_.line());
        for (int k = 0; k < 3; ++k) mesh_.nodes.push_back(r_.to_double(xyz[k], "a node coordinate"));
    }

    void begin_nodes(const char* section) {
        if (have_nodes_) r_.fail(format("second node section %s", section));
        have_nodes_ = true;
    }

    void begin_elements(const char* section) {
        if (!have_nodes_) r_.fail(format("%s before the node section", section));
        if (have_elements_) r_.fail(format("second element section %s", section));
        have_elements_ = true;
        tags_.finish(r_);
    }

    // Version 1 and 2 nodes: a count, then "tag x y z" lines.
    void read_nodes_v1_v2(const char* section, const char* end) {
        begin_nodes(section);
        const int32_t count = read_count_line("the node count");
        reserve_nodes(count);
        for (int32_t i = 0; i < count; ++i) {
            expect_record(section, i, count, "nodes");
            if (f_.size() != 4) r_.fail(format("expected 4 fields for node (tag x y z), got %zu", f_.size()));
            add_node(f_[0], &f_[1]);
        }
        expect_end(end, format("%d nodes", count).c_str());
    }

    // Version 1 element: number type physical elementary node-count nodes...
    // Version 2 element: number type tag-count tags... nodes...
    void read_elements_v1_v2(const char* section, const char* end, int version) {
        begin_elements(section);
        const int32_t count = read_count_line("the element count");
        reserve_elements(count, 7);
        for (int32_t i = 0; i < count; ++i) {
            expect_record(section, i, count, "elements");
            size_t first_node = 0;
            if (version == 1) {
                if (f_.size() < 5) r_.fail(format("expected at least 5 fields for element, got %zu", f_.size()));
                const int64_t nodes = r_.to_int(f_[4], "the element's node count");
                if (nodes < 0 || static_cast<size_t>(nodes) != f_.size() - 5)
                    r_.fail(format("element %s says it has %lld nodes but the line lists %zu",
                                   printable(f_[0]).c_str(), static_cast<long long>(nodes), f_.size() - 5));
                first_node = 5;
            } else {
                if (f_.size() < 3) r_.fail(format("expected at least 3 fields for element, got %zu", f_.size()));
                const int64_t tag_count = r_.to_int(f_[2], "the element's tag count");
                if (tag_count < 0 || static_cast<size_t>(tag_count) > f_.size() - 3)
                    r_.fail(format("element %s says it has %lld tags but the line has %zu fields",
                                   printable(f_[0]).c_str(), static_cast<long long>(tag_count), f_.size()));
                first_node = 3 + static_cast<size_t>(tag_count);
            }
            add_element(f_[0], r_.to_int(f_[1], "the element type"), first_node);
        }
        expect_end(end, format("%d elements", count).c_str());
    }

    // Version 4.1 nodes: entity blocks, each a header, the tags, then the coordinates.
    void read_nodes_v4() {
        begin_nodes("$Nodes");
        vec<std::string_view> block_tags;
        read_blocks_v4("$Nodes", "nodes", "entityDim entityTag parametric numNodes",
                       [&](int32_t total) { reserve_nodes(total); },
                       [&](int32_t read, int32_t block, int32_t total) {
                           const int64_t dim = r_.to_int(f_[0], "the entity dimension");
                           const bool parametric = r_.to_int(f_[2], "the parametric flag") != 0;
                           const size_t fields = 3 + ((parametric && dim > 0) ? static_cast<size_t>(dim) : 0);
                           block_tags.clear();
                           for (int32_t i = 0; i < block; ++i) {
                               expect_record("$Nodes", read + i, total, "node tags");
                               if (f_.size() != 1) r_.fail(format("expected 1 field for a node tag, got %zu", f_.size()));
                               block_tags.push_back(f_[0]);
                           }
                           for (int32_t i = 0; i < block; ++i) {
                               expect_record("$Nodes", read + i, total, "node coordinates");
                               if (f_.size() != fields)
                                   r_.fail(format("expected %zu fields for node coordinates, got %zu", fields, f_.size()));
                               add_node(block_tags[static_cast<size_t>(i)], &f_[0]);
                           }
                       });
        expect_end("$EndNodes", "the node blocks");
    }

    // Version 4.1 elements: entity blocks, each a header with the type, then "tag nodes..." lines.
    void read_elements_v4() {
        begin_elements("$Elements");
        read_blocks_v4("$Elements", "elements", "entityDim entityTag elementType numElements",
                       [&](int32_t total) { reserve_elements(total, 5); },
                       [&](int32_t read, int32_t block, int32_t total) {
                           const int64_t type = r_.to_int(f_[2], "the element type");
                           for (int32_t i = 0; i < block; ++i) {
                               expect_record("$Elements", read + i, total, "elements");
                               add_element(f_[0], type, 1);
                           }
                       });
        expect_end("$EndElements", "the element blocks");
    }

    // A 4.1 section: "numEntityBlocks total minTag maxTag" (reserve(total) is called), then
    // blocks whose 4-field header (layout names the fields) ends with the block size;
    // read_block(read, size, total) reads a block's records with its header in f_. The blocks
    // must add up to the total.
    template <class Reserve, class ReadBlock>
    void read_blocks_v4(const char* section, const char* what, const char* layout, Reserve&& reserve,
                        ReadBlock&& read_block) {
        r_.expect_line(f_, "the section header");
        if (f_.size() != 4)
            r_.fail(format("expected 4 fields for the %s header (numEntityBlocks num%s minTag maxTag), got %zu",
                           section, section + 1, f_.size()));
        const int32_t blocks = r_.to_count(f_[0], "the entity block count");
        const int32_t total = r_.to_count(f_[1], "the total count");
        reserve(total);
        int32_t read = 0;
        for (int32_t b = 0; b < blocks; ++b) {
            expect_record(section, read, total, what);
            if (f_.size() != 4)
                r_.fail(format("expected 4 fields for a block header (%s), got %zu", layout, f_.size()));
            const int32_t block = r_.to_count(f_[3], "the block size");
            if (block > total - read)
                r_.fail(format("block of %d %s exceeds the %d left of the header's total", block, what, total - read));
            read_block(read, block, total);
            read += block;
        }
        if (read != total) r_.fail(format("the blocks hold %d %s but the header announces %d", read, what, total));
    }

    // Reserves for count nodes (of at least 4 tokens), no more than the rest of the file can hold.
    void reserve_nodes(int32_t count) { mesh_.nodes.reserve(3 * std::min<size_t>(count, r_.max_records(4))); }

    // Reserves for count elements, no more than the rest of the file can hold.
    void reserve_elements(int32_t count, int tokens_per_element) {
        const size_t cap = std::min<size_t>(count, r_.max_records(tokens_per_element));
        mesh_.tets.reserve(4 * cap);
        mesh_.tet_lines.reserve(cap);
    }

    // Keeps the element on the current line if it is a linear tet (its nodes are the fields from
    // first_node on); otherwise counts it as skipped.
    void add_element(std::string_view number, int64_t type, size_t first_node) {
        const size_t nodes = f_.size() - first_node;
        const int expected = gmsh_element_nodes(type);
        if (expected > 0 && nodes != static_cast<size_t>(expected))
            r_.fail(format("element %s of type %lld needs %d nodes, got %zu", printable(number).c_str(),
                           static_cast<long long>(type), expected, nodes));
        if (nodes == 0) r_.fail(format("element %s lists no nodes", printable(number).c_str()));
        if (type != kGmshTet) {
            ++mesh_.skipped_elements;
            return;
        }
        for (size_t a = first_node; a < f_.size(); ++a) {
            const int64_t tag = r_.to_int(f_[a], "a node tag");
            const int32_t index = tags_.find(tag);
            if (index < 0)
                r_.fail(format("element %s references unknown node tag %lld", printable(number).c_str(),
                               static_cast<long long>(tag)));
            mesh_.tets.push_back(index);
        }
        mesh_.tet_lines.push_back(r_.line());
    }

    TextReader r_;
    Fields f_;
    MeshData mesh_;
    NodeTags tags_;
    int version_ = 0;  // 2 or 4 once $MeshFormat is read (version 1 files have none)
    bool have_nodes_ = false;
    bool have_elements_ = false;
};

}  // namespace

MeshData read_gmsh(const std::string& path, std::string_view text) { return GmshReader(path, text).read(); }

}  // namespace sh
