#include "mesh/io/text_reader.hpp"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <limits>

#include <sys/stat.h>

namespace sh {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

// Drops one leading '+' (std::from_chars does not accept it) unless it stands alone or comes
// before a '-', which from_chars would then take as the sign: "+-1" is not a number.
std::string_view without_plus(std::string_view token) {
    if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
    return token;
}

// Splits line into whitespace-separated fields, dropping everything from `comment` on.
void split_fields(std::string_view line, char comment, Fields& fields) {
    fields.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        if (i == line.size() || (comment != '\0' && line[i] == comment)) return;
        const size_t start = i;
        while (i < line.size() && !is_space(line[i]) && !(comment != '\0' && line[i] == comment)) ++i;
        fields.push_back(line.substr(start, i - start));
    }
}

}  // namespace

vec<char> read_text_file(const std::string& path) {
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) throw Error(SH_ERR_IO, format("cannot open '%s': %s", path.c_str(), std::strerror(errno)));
    struct stat info;
    if (fstat(fileno(file), &info) == 0 && !S_ISREG(info.st_mode)) {  // a directory, a device, a pipe
        std::fclose(file);
        throw Error(SH_ERR_IO, format("cannot read '%s': not a regular file", path.c_str()));
    }
    vec<char> bytes;
    char chunk[1 << 16];
    size_t got = 0;
    while ((got = std::fread(chunk, 1, sizeof chunk, file)) > 0) bytes.insert(bytes.end(), chunk, chunk + got);
    const bool failed = std::ferror(file) != 0;
    const int error = errno;
    std::fclose(file);
    if (failed) throw Error(SH_ERR_IO, format("cannot read '%s': %s", path.c_str(), std::strerror(error)));
    return bytes;
}

std::string printable(std::string_view token) {
    constexpr size_t kMax = 40;
    std::string out;
    for (size_t i = 0; i < token.size() && i < kMax; ++i) {
        const unsigned char c = static_cast<unsigned char>(token[i]);
        out += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
    }
    if (token.size() > kMax) out += "...";
    return out;
}

std::string quoted(std::string_view token) { return "'" + printable(token) + "'"; }

bool parse_double(std::string_view token, double& out) {
    token = without_plus(token);
    if (token.empty()) return false;
    const auto result = std::from_chars(token.data(), token.data() + token.size(), out);
    return result.ec == std::errc() && result.ptr == token.data() + token.size();
}

bool parse_int(std::string_view token, int64_t& out) {
    token = without_plus(token);
    if (token.empty()) return false;
    const auto result = std::from_chars(token.data(), token.data() + token.size(), out);
    return result.ec == std::errc() && result.ptr == token.data() + token.size();
}

bool starts_with_nocase(std::string_view text, std::string_view prefix) {
    return text.size() >= prefix.size() && equals_nocase(text.substr(0, prefix.size()), prefix);
}

bool equals_nocase(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
        if (lower(a[i]) != lower(b[i])) return false;
    return true;
}

TextReader::TextReader(std::string path, std::string_view text, int first_line)
    : path_(std::move(path)), text_(text), cursor_line_(first_line), line_(first_line) {}

size_t TextReader::max_records(int tokens_per_record) const {
    // Every token takes at least one character and one separator (the last may lack it).
    return (remaining() + 1) / (2 * static_cast<size_t>(tokens_per_record > 0 ? tokens_per_record : 1));
}

void TextReader::skip_whitespace() {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
        if (text_[pos_] == '\n') ++cursor_line_;
        ++pos_;
    }
}

bool TextReader::at_end() {
    skip_whitespace();
    return pos_ == text_.size();
}

std::string_view TextReader::next_token() {
    skip_whitespace();
    if (pos_ == text_.size()) return {};
    const size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    line_ = cursor_line_;
    return text_.substr(start, pos_ - start);
}

std::string_view TextReader::expect_token(const char* what) {
    const std::string_view token = next_token();
    if (token.empty()) fail(format("unexpected end of file while reading %s", what));
    return token;
}

double TextReader::read_double(const char* what) { return to_double(expect_token(what), what); }

int64_t TextReader::read_int(const char* what) { return to_int(expect_token(what), what); }

double TextReader::to_double(std::string_view token, const char* what) const {
    double value = 0.0;
    if (!parse_double(token, value))
        fail(format("expected a number for %s, got %s", what, quoted(token).c_str()));
    return value;
}

int64_t TextReader::to_int(std::string_view token, const char* what) const {
    int64_t value = 0;
    if (!parse_int(token, value))
        fail(format("expected an integer for %s, got %s", what, quoted(token).c_str()));
    return value;
}

int32_t TextReader::to_count(std::string_view token, const char* what) const {
    const int64_t value = to_int(token, what);
    if (value < 0 || value > std::numeric_limits<int32_t>::max())
        fail(format("%s is %lld, must be in [0, %d]", what, static_cast<long long>(value),
                    std::numeric_limits<int32_t>::max()));
    return static_cast<int32_t>(value);
}

int32_t TextReader::to_index(int64_t value, const char* what) const {
    if (value < std::numeric_limits<int32_t>::min() || value > std::numeric_limits<int32_t>::max())
        fail(format("%s %lld does not fit in 32 bits", what, static_cast<long long>(value)));
    return static_cast<int32_t>(value);
}

std::string_view TextReader::next_raw_line() {
    if (pos_ == text_.size()) return {};
    const size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    std::string_view line = text_.substr(start, pos_ - start);
    line_ = cursor_line_;
    if (pos_ < text_.size()) {
        ++pos_;
        ++cursor_line_;
    }
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
}

bool TextReader::next_line(Fields& fields, char comment) {
    fields.clear();
    const int last_line = line_;
    while (pos_ < text_.size()) {
        split_fields(next_raw_line(), comment, fields);
        if (!fields.empty()) return true;
    }
    line_ = last_line;  // only blank lines were left: stay on the last line that had content
    return false;
}

void TextReader::expect_line(Fields& fields, const char* what, char comment) {
    if (!next_line(fields, comment)) fail(format("unexpected end of file while reading %s", what));
}

void TextReader::fail(const std::string& what) const { fail_at(line_, what); }

void TextReader::fail_at(int line, const std::string& what) const {
    throw Error(SH_ERR_PARSE, format("%s:%d: %s", path_.c_str(), line, what.c_str()));
}

void TextReader::unsupported(const std::string& what) const { unsupported_at(line_, what); }

void TextReader::unsupported_at(int line, const std::string& what) const {
    throw Error(SH_ERR_UNSUPPORTED, format("%s:%d: %s", path_.c_str(), line, what.c_str()));
}

}  // namespace sh
