// Shared tokenizer and line reader for the text mesh formats: a cursor over a file's bytes
// that counts lines, parses numbers without iostreams and reports "path:line: what" errors.
#pragma once

#include "core/error.hpp"
#include "core/memory.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace sh {

/// Whitespace-separated fields of one line (views into the reader's text).
using Fields = vec<std::string_view>;

/// Reads a whole file into memory. Throws SH_ERR_IO naming the file if it cannot be read.
vec<char> read_text_file(const std::string& path);

/// A token made safe for an error message: at most 40 characters, non-printable bytes as '?'.
std::string printable(std::string_view token);

/// printable(token) in single quotes.
std::string quoted(std::string_view token);

/// Parses the whole of token as a double (accepts a leading '+', "nan", "inf"); false if not.
bool parse_double(std::string_view token, double& out);

/// Parses the whole of token as a decimal integer (accepts a leading '+'); false if not.
bool parse_int(std::string_view token, int64_t& out);

/// True if text begins with prefix, comparing ASCII letters case-insensitively.
bool starts_with_nocase(std::string_view text, std::string_view prefix);

/// True if a equals b, comparing ASCII letters case-insensitively.
bool equals_nocase(std::string_view a, std::string_view b);

/// A forward cursor over text. Reads either tokens (whitespace-separated, across lines) or
/// whole lines. line() is the 1-based file line of the last token or line returned; at the end
/// of the text it stays on the last one, so "unexpected end of file" names the last line read.
class TextReader {
public:
    /// Reads text (owned by the caller, must outlive the reader); path and first_line locate
    /// it in messages (first_line > 1 for a slice of a larger file).
    TextReader(std::string path, std::string_view text, int first_line = 1);

    /// The file name used in messages.
    const std::string& path() const { return path_; }

    /// 1-based line of the last token or line returned.
    int line() const { return line_; }

    /// Bytes not yet consumed (an upper bound for what is left to parse).
    size_t remaining() const { return text_.size() - pos_; }

    /// Upper bound on how many records of tokens_per_record tokens fit in the rest of the
    /// text; clamp header counts with it before reserving memory.
    size_t max_records(int tokens_per_record) const;

    /// Next whitespace-separated token, or an empty view at the end of the text.
    std::string_view next_token();

    /// Next token; fails with "unexpected end of file while reading <what>" at the end.
    std::string_view expect_token(const char* what);

    /// Next token as a double / integer; fails naming what (e.g. "x of node 12").
    double read_double(const char* what);
    int64_t read_int(const char* what);

    /// Converts a token already read (e.g. one of a line's fields) at the current line.
    double to_double(std::string_view token, const char* what) const;
    int64_t to_int(std::string_view token, const char* what) const;

    /// Converts a token to a count in [0, 2^31 - 1] (counts index int32 arrays).
    int32_t to_count(std::string_view token, const char* what) const;

    /// Converts a value to a node index that fits in int32 (range checks are validation's).
    int32_t to_index(int64_t value, const char* what) const;

    /// The rest of the current line (without the end of line) and moves to the next line;
    /// empty view at the end of the text. Use at_end() to tell an empty line from the end.
    std::string_view next_raw_line();

    /// Next line holding at least one field, split into fields (text from `comment` on is
    /// ignored when comment is not '\0'); false at the end of the text.
    bool next_line(Fields& fields, char comment = '\0');

    /// Like next_line, but fails with "unexpected end of file while reading <what>".
    void expect_line(Fields& fields, const char* what, char comment = '\0');

    /// True when only whitespace is left.
    bool at_end();

    /// Throws SH_ERR_PARSE "path:line: what" at the current line / at a given line.
    [[noreturn]] void fail(const std::string& what) const;
    [[noreturn]] void fail_at(int line, const std::string& what) const;

    /// Throws SH_ERR_UNSUPPORTED "path:line: what" at the current line / at a given line.
    [[noreturn]] void unsupported(const std::string& what) const;
    [[noreturn]] void unsupported_at(int line, const std::string& what) const;

private:
    void skip_whitespace();

    std::string path_;
    std::string_view text_;
    size_t pos_ = 0;
    int cursor_line_;  // line of text_[pos_]
    int line_;         // line of the last token or line returned
};

}  // namespace sh
