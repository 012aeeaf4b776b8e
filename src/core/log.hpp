// The library's log: messages for the host's sh_log_fn (sh_set_log_callback), formatted on the
// stack (no allocation). Only sim-side code logs; the haptic step never does.
#pragma once

#include <softhap/softhap.h>

namespace sh {

/// Installs callback (NULL: none) with its user pointer. The C API allows it only while no
/// object is alive, so that no step can be logging meanwhile.
void set_log_callback(sh_log_fn callback, void* user);

/// True if a callback is installed (callers may skip building a message otherwise).
bool logging();

/// Formats a message (printf-style, at most 511 characters) and hands it to the callback, if
/// any.
void log_message(sh_log_level level, const char* format, ...) __attribute__((format(printf, 2, 3)));

}  // namespace sh
