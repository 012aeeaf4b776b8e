#include "core/log.hpp"

#include <cstdarg>
#include <cstdio>

namespace sh {
namespace {

sh_log_fn g_callback = nullptr;
void* g_user = nullptr;

}  // namespace

void set_log_callback(sh_log_fn callback, void* user) {
    g_callback = callback;
    g_user = user;
}

bool logging() { return g_callback != nullptr; }

void log_message(sh_log_level level, const char* format, ...) {
    if (!g_callback) return;
    char line[512];
    va_list args;
    va_start(args, format);
    std::vsnprintf(line, sizeof line, format, args);
    va_end(args);
    g_callback(level, line, g_user);
}

}  // namespace sh
