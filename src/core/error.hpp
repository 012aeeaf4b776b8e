// Internal error type: core code throws sh::Error; src/capi turns it into a status code.
#pragma once

#include <softhap/softhap.h>

#include <string>

namespace sh {

/// A failure with its public status code and a message naming the culprit.
class Error {
public:
    Error(sh_status status, std::string message) : status_(status), message_(std::move(message)) {}
    sh_status status() const { return status_; }
    const std::string& message() const { return message_; }

private:
    sh_status status_;
    std::string message_;
};

/// Throws Error(status, message) when condition is false.
inline void require(bool condition, sh_status status, const std::string& message) {
    if (!condition) throw Error(status, message);
}

/// Formats like printf into a std::string (for error messages).
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

}  // namespace sh
