// Per-node checks shared by the time-stepping loops: the runaway test (too fast or not
// finite), its conservative eight-node AVX-512 pre-test, and a walk over kinematic nodes.
#pragma once

#include "core/memory.hpp"

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace sh {

#if defined(__AVX512F__)
// The runaway test as a conservative per-component bound: |v_k| <= 0.57 limit gives
// speed^2 <= 0.975 limit^2, |x_k| <= DBL_MAX/4 keeps x0 + x1 + x2 finite. A chunk that fails it
// gets the exact per-node test.
inline __mmask8 outside_bounds(__m512d x, __m512d v, __m512d v_bound) {
    return _mm512_cmp_pd_mask(_mm512_abs_pd(v), v_bound, _CMP_NLE_UQ) |
           _mm512_cmp_pd_mask(_mm512_abs_pd(x), _mm512_set1_pd(0.25 * DBL_MAX), _CMP_NLE_UQ);
}
#endif

// The runaway test of node i: too fast or not finite.
inline bool node_insane(const double* x, const double* v, size_t i, double limit2) {
    const double* xi = &x[3 * i];
    const double* vi = &v[3 * i];
    const double speed2 = vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2];
    // NaN fails every comparison, so !(a <= b) also catches it.
    return !(speed2 <= limit2 && std::isfinite(xi[0] + xi[1] + xi[2]));
}

// Calls visit(i) for every node i with kinematic[i] set; skips eight clear bytes at a time.
template <class Visit>
void for_each_kinematic(const vec<uint8_t>& kinematic, Visit&& visit) {
    const size_t n = kinematic.size();
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t word;
        std::memcpy(&word, &kinematic[i], sizeof word);
        if (!word) continue;
        for (size_t k = i; k < i + 8; ++k)
            if (kinematic[k]) visit(k);
    }
    for (; i < n; ++i)
        if (kinematic[i]) visit(i);
}

}  // namespace sh
