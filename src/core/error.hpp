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

/// Throws Error(status, message) when condition is false (for fixed messages; see SH_REQUIRE).
inline void require(bool condition, sh_status status, const std::string& message) {
    if (!condition) throw Error(status, message);
}

/// Formats like printf into a std::string (for error messages).
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

}  // namespace sh

/// Throws sh::Error(status, printf-formatted message) when condition is false; the message is
/// only formatted on failure, so checks in loops cost a comparison.
#define SH_REQUIRE(condition, status, ...) \
    do {                                   \
        if (!(condition)) throw ::sh::Error((status), ::sh::format(__VA_ARGS__)); \
    } while (0)
