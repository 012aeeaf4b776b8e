// Reads a C enum field from the host as a plain int. A C host may store any int in an enum
// field; loading it as a C++ enum whose range it exceeds would be undefined behaviour.
#pragma once

#include <cstring>

namespace sh {

/// The integer stored in an enum field, whatever it is.
template <class Enum>
int enum_value(const Enum& field) {
    static_assert(sizeof(Enum) == sizeof(int), "C enums are int-sized");
    int value;
    std::memcpy(&value, &field, sizeof value);
    return value;
}

}  // namespace sh
