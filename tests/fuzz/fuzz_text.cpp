// libFuzzer target: the text layer every reader stands on (src/mesh/io/text_reader.cpp: fields,
// integers, reals), differentially against the C library. The input is one field of a Gmsh 2.2
// file around a valid tet: the tag of an extra, unused node, then (second load) that node's x.
// Each load is checked as fuzz_check.hpp says, and when the input is one field (no '\n', no
// whitespace inside once trimmed):
// - a loaded tag is an integer strtoll reads whole; a loaded x is a real strtod reads whole, to
//   the same double (strtod and strtoll are the reference for what a number is);
// - a plain decimal integer in range (other than the tet's tags 1-4) loads as a tag, and a plain
//   decimal real that strtod reads without overflow or underflow loads as x.
// Seeds: corpus/text/ (one field each).
#include "fuzz_check.hpp"

#include <cerrno>
#include <cstring>

namespace {

using namespace softhap_fuzz;

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

// True if input is one field of a line (what sh_mesh_load would split off as one): then field is
// input without its surrounding whitespace.
bool one_field(std::string_view input, std::string& field) {
    if (input.find('\n') != std::string_view::npos) return false;  // would start a new line
    size_t begin = 0, end = input.size();
    while (begin < end && is_space(input[begin])) ++begin;
    while (end > begin && is_space(input[end - 1])) --end;
    field.assign(input.substr(begin, end - begin));
    for (const char c : field)
        if (is_space(c) || c == '\0') return false;
    return !field.empty();
}

// [+-]digits, optionally with a fraction (decimal) and an exponent (real): what every format
// writes, and what the readers must accept.
bool plain_decimal(const std::string& s, bool real) {
    size_t i = (s[0] == '+' || s[0] == '-') ? 1 : 0;
    const size_t digits = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    if (!real) return i > digits && i == s.size();
    size_t mantissa = i - digits;
    if (i < s.size() && s[i] == '.')
        for (++i; i < s.size() && s[i] >= '0' && s[i] <= '9'; ++i) ++mantissa;
    if (mantissa == 0) return false;
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        if (++i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
        const size_t exponent = i;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
        if (i == exponent) return false;
    }
    return i == s.size();
}

// A Gmsh 2.2 file: the unit tet (tags 1-4) and a fifth node "tag x 0 0" that no tet uses.
std::string mesh_with_extra_node(std::string_view tag, std::string_view x) {
    std::string text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    text.append(tag).append(" ").append(x).append(" 0 0\n$EndNodes\n");
    return text + "$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n";
}

void check_tag(std::string_view input) {
    const std::string text = mesh_with_extra_node(input, "0.5");
    const File file = write_input("tag.msh", text);
    const bool loaded = check_load(file.path, {file}) != nullptr;
    std::string field;
    if (!one_field(input, field)) return;
    char* end = nullptr;
    errno = 0;
    const long long value = std::strtoll(field.c_str(), &end, 10);
    const bool whole = errno == 0 && end == field.c_str() + field.size();
    if (loaded && !whole) violated("a tag strtoll does not read whole was accepted", field);
    if (!loaded && whole && plain_decimal(field, false) && (value < 1 || value > 4))
        violated("a plain integer tag was refused", field + ": " + sh_last_error_message());
}

void check_x(std::string_view input) {
    const std::string text = mesh_with_extra_node("5", input);
    const File file = write_input("x.msh", text);
    const MeshPtr mesh = check_load(file.path, {file});
    std::string field;
    if (!one_field(input, field)) return;
    char* end = nullptr;
    errno = 0;
    const double expected = std::strtod(field.c_str(), &end);
    const bool whole = end == field.c_str() + field.size();
    if (!mesh) {
        if (whole && errno == 0 && plain_decimal(field, true))
            violated("a plain real x was refused", field + ": " + sh_last_error_message());
        return;
    }
    double nodes[15];
    if (sh_mesh_get_nodes(mesh.get(), nodes, 5) != SH_OK) violated("cannot read the nodes", sh_last_error_message());
    if (!whole || std::memcmp(&nodes[12], &expected, sizeof expected) != 0)
        violated("an x strtod reads otherwise was accepted", field);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view input = as_text(data, size);
    check_tag(input);
    check_x(input);
    return 0;
}
