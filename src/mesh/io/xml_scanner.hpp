// A minimal pull scanner for the XML that VTK writes: start and end tags with their
// attributes, and the text between tags. Comments, processing instructions and DOCTYPE are
// skipped; CDATA is returned as text. No entities, no namespaces, no validation.
#pragma once

#include "mesh/io/text_reader.hpp"

#include <string_view>

namespace sh {

/// One thing the scanner found.
struct XmlEvent {
    enum Kind { Text, Open, Close, End } kind = End;
    std::string_view name;        ///< Open, Close: the tag name
    std::string_view attributes;  ///< Open: the raw text after the name
    std::string_view text;        ///< Text: the characters between two tags
    bool self_closing = false;    ///< Open: written <name ... />
    int line = 0;                 ///< 1-based line where the event starts
};

/// Scans text from its start; errors go through reader (its path names the file).
class XmlScanner {
public:
    XmlScanner(const TextReader& reader, std::string_view text) : reader_(reader), text_(text) {}

    /// The next event; End once the text is used up. Fails (SH_ERR_PARSE) on an unterminated
    /// tag or comment.
    XmlEvent next();

private:
    void advance(size_t n);                   // moves forward, counting lines
    bool skip_past(std::string_view needle);  // false (at the end) if needle is missing
    bool starts_with(std::string_view prefix) const { return text_.substr(pos_, prefix.size()) == prefix; }

    const TextReader& reader_;
    std::string_view text_;
    size_t pos_ = 0;
    int line_ = 1;
};

/// Finds attribute key in a tag's attribute text; returns false if it is absent.
bool xml_attribute(std::string_view attributes, std::string_view key, std::string_view& value);

}  // namespace sh
