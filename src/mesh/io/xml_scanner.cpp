#include "mesh/io/xml_scanner.hpp"

namespace sh {
namespace {

bool is_xml_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

bool ends_name(char c) { return is_xml_space(c) || c == '>' || c == '/' || c == '='; }

}  // namespace

void XmlScanner::advance(size_t n) {
    const size_t end = pos_ + n < text_.size() ? pos_ + n : text_.size();
    for (; pos_ < end; ++pos_)
        if (text_[pos_] == '\n') ++line_;
}

bool XmlScanner::skip_past(std::string_view needle) {
    const size_t at = text_.find(needle, pos_);
    if (at == std::string_view::npos) {
        advance(text_.size() - pos_);
        return false;
    }
    advance(at + needle.size() - pos_);
    return true;
}

XmlEvent XmlScanner::next() {
    for (;;) {
        XmlEvent event;
        event.line = line_;
        if (pos_ == text_.size()) {  // End, on the last line that has text
            if (!text_.empty() && text_.back() == '\n') event.line = line_ - 1;
            return event;
        }
        if (text_[pos_] != '<') {
            const size_t at = text_.find('<', pos_);
            const size_t end = at == std::string_view::npos ? text_.size() : at;
            event.kind = XmlEvent::Text;
            event.text = text_.substr(pos_, end - pos_);
            advance(end - pos_);
            return event;
        }
        if (starts_with("<!--")) {
            if (!skip_past("-->")) reader_.fail_at(event.line, "unterminated XML comment");
            continue;
        }
        if (starts_with("<![CDATA[")) {
            advance(9);
            const size_t at = text_.find("]]>", pos_);
            if (at == std::string_view::npos) reader_.fail_at(event.line, "unterminated CDATA section");
            event.kind = XmlEvent::Text;
            event.text = text_.substr(pos_, at - pos_);
            advance(at + 3 - pos_);
            return event;
        }
        if (starts_with("<?") || starts_with("<!")) {
            if (!skip_past(">")) reader_.fail_at(event.line, "unterminated XML declaration");
            continue;
        }
        advance(1);
        event.kind = XmlEvent::Open;
        if (starts_with("/")) {
            event.kind = XmlEvent::Close;
            advance(1);
        }
        const size_t name_start = pos_;
        while (pos_ < text_.size() && !ends_name(text_[pos_])) advance(1);
        event.name = text_.substr(name_start, pos_ - name_start);
        if (event.name.empty()) reader_.fail_at(event.line, "'<' not followed by a tag name");
        // Attributes run to the first '>' outside quotes.
        const size_t attributes_start = pos_;
        char quote = '\0';
        while (pos_ < text_.size() && (quote != '\0' || text_[pos_] != '>')) {
            if (quote == '\0' && (text_[pos_] == '"' || text_[pos_] == '\'')) quote = text_[pos_];
            else if (text_[pos_] == quote) quote = '\0';
            advance(1);
        }
        if (pos_ == text_.size())
            reader_.fail_at(event.line, format("unterminated tag <%s", printable(event.name).c_str()));
        event.attributes = text_.substr(attributes_start, pos_ - attributes_start);
        if (!event.attributes.empty() && event.attributes.back() == '/') {
            event.self_closing = true;
            event.attributes.remove_suffix(1);
        }
        advance(1);  // '>'
        return event;
    }
}

bool xml_attribute(std::string_view attributes, std::string_view key, std::string_view& value) {
    size_t i = 0;
    while (i < attributes.size()) {
        while (i < attributes.size() && is_xml_space(attributes[i])) ++i;
        const size_t name_start = i;
        while (i < attributes.size() && !ends_name(attributes[i])) ++i;
        const std::string_view name = attributes.substr(name_start, i - name_start);
        while (i < attributes.size() && is_xml_space(attributes[i])) ++i;
        if (i == attributes.size() || attributes[i] != '=') {
            if (name.empty()) ++i;  // a stray character: step over it
            continue;
        }
        ++i;  // '='
        while (i < attributes.size() && is_xml_space(attributes[i])) ++i;
        if (i == attributes.size() || (attributes[i] != '"' && attributes[i] != '\'')) continue;
        const char quote = attributes[i++];
        const size_t value_start = i;
        while (i < attributes.size() && attributes[i] != quote) ++i;
        if (name == key) {
            value = attributes.substr(value_start, i - value_start);
            return true;
        }
        if (i < attributes.size()) ++i;  // closing quote
    }
    return false;
}

}  // namespace sh
