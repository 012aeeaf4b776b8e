// Small 3-vector helpers over plain double[3] arrays.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace sh {

/// The 3 coordinates of node `node` in an array of 3 doubles per node.
inline double* at(double* x, int32_t node) { return x + 3 * static_cast<size_t>(node); }
inline const double* at(const double* x, int32_t node) { return x + 3 * static_cast<size_t>(node); }

/// out = a - b.
inline void sub3(const double* a, const double* b, double* out) {
    for (int k = 0; k < 3; ++k) out[k] = a[k] - b[k];
}

/// a . b
inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// out = a x b (out must not alias a or b).
inline void cross3(const double* a, const double* b, double* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/// |a|
inline double norm3(const double* a) { return std::sqrt(dot3(a, a)); }

/// The Frobenius norm of the 3x3 block whose entry (r, s) is m[r * row + s * column].
inline double block_norm(const double* m, size_t row, size_t column) {
    double squares = 0.0;
    for (size_t r = 0; r < 3; ++r)
        for (size_t s = 0; s < 3; ++s) squares += m[r * row + s * column] * m[r * row + s * column];
    return std::sqrt(squares);
}

/// The largest |a_i| of n values (0 for none).
inline double largest_magnitude(const double* a, size_t n) {
    double largest = 0.0;
    for (size_t i = 0; i < n; ++i) largest = std::max(largest, std::fabs(a[i]));
    return largest;
}

/// True if every component is finite.
inline bool finite3(const double* a) { return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]); }

}  // namespace sh
