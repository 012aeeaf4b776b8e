// SIMD lanes: kLanes doubles processed together (one tet per lane), via GCC vector extensions
// so the same source compiles to AVX-512, AVX2 or SSE2 as the target allows.
#pragma once

#include <cmath>

#if defined(__AVX512F__) || defined(__AVX__)
#include <immintrin.h>
#endif

namespace sh {

/// Tets processed together by the element kernels: one vector register's worth of doubles
/// where the target has AVX-512, half a register pair elsewhere (AVX2 has 16 registers of 4
/// doubles: 8-double lanes take two each and the kernels' 3x3 and 9x9 matrices spill).
#if defined(__AVX512F__)
constexpr int kLanes = 8;
#else
constexpr int kLanes = 4;
#endif

/// kLanes doubles; arithmetic is element-wise.
typedef double Lanes __attribute__((vector_size(kLanes * sizeof(double))));

/// kLanes 64-bit integers (comparison results).
typedef long long LaneMask __attribute__((vector_size(kLanes * sizeof(long long))));

#define SH_INLINE inline __attribute__((always_inline))

/// All lanes set to s.
SH_INLINE Lanes splat(double s) { return Lanes{} + s; }

/// Element-wise select: mask ? a : b.
SH_INLINE Lanes select(LaneMask mask, Lanes a, Lanes b) { return mask ? a : b; }

/// |a| per lane.
SH_INLINE Lanes abs_lane(Lanes a) { return select(a < 0.0, -a, a); }

/// max(a, b) per lane.
SH_INLINE Lanes max_lane(Lanes a, Lanes b) { return select(a > b, a, b); }

/// Element-wise square root (vectorised where the target has it).
SH_INLINE Lanes lanes_sqrt(Lanes a) {
#if defined(__AVX512F__)
    static_assert(kLanes == 8, "AVX-512 path assumes 8 double lanes");
    return _mm512_sqrt_pd(a);
#elif defined(__AVX__)
    static_assert(kLanes == 4, "AVX path assumes 4 double lanes");
    return _mm256_sqrt_pd(a);
#else
    for (int l = 0; l < kLanes; ++l) a[l] = std::sqrt(a[l]);
    return a;
#endif
}

/// True if any lane of mask is set.
SH_INLINE bool any_lane(LaneMask mask) {
    for (int l = 0; l < kLanes; ++l)
        if (mask[l]) return true;
    return false;
}

/// Element-wise 1 / sqrt(a), to about an ulp. With AVX-512 a 14-bit estimate refined by two
/// Newton steps (y <- y (3 - a y^2) / 2, each doubling the bits), which the vector units finish
/// sooner than a square root and a division in a row (each of those holds its unit for many
/// cycles); where a lane is below 1e-290 (0, denormal: a / 2 loses bits there) or not a
/// number, and without AVX-512, that square root and division.
SH_INLINE Lanes lanes_rsqrt(Lanes a) {
#if defined(__AVX512F__)
    if (_mm512_cmp_pd_mask(a, _mm512_set1_pd(1e-290), _CMP_NGE_UQ) == 0) {
        Lanes y = _mm512_rsqrt14_pd(a);
        const Lanes half = 0.5 * a;
        y = y * (1.5 - (half * y) * y);  // (half y) y: y^2 alone overflows for a below 1e-308
        return y * (1.5 - (half * y) * y);
    }
#endif
    return 1.0 / lanes_sqrt(a);
}

/// Sum of the lanes.
SH_INLINE double lane_sum(Lanes a) {
    double s = 0.0;
    for (int l = 0; l < kLanes; ++l) s += a[l];
    return s;
}

/// A 3x3 matrix per lane, row-major: m[row][col].
struct Mat3L {
    Lanes m[3][3];
};

SH_INLINE Mat3L identity_lanes() {
    Mat3L r{};
    for (int i = 0; i < 3; ++i) r.m[i][i] = splat(1.0);
    return r;
}

/// A B
SH_INLINE Mat3L mul(const Mat3L& a, const Mat3L& b) {
    Mat3L r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
    return r;
}

/// A^T B
SH_INLINE Mat3L mul_tn(const Mat3L& a, const Mat3L& b) {
    Mat3L r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[0][i] * b.m[0][j] + a.m[1][i] * b.m[1][j] + a.m[2][i] * b.m[2][j];
    return r;
}

/// A B^T
SH_INLINE Mat3L mul_nt(const Mat3L& a, const Mat3L& b) {
    Mat3L r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[j][0] + a.m[i][1] * b.m[j][1] + a.m[i][2] * b.m[j][2];
    return r;
}

SH_INLINE Mat3L transpose(const Mat3L& a) {
    Mat3L r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
    return r;
}

/// (A + A^T) / 2
SH_INLINE Mat3L sym(const Mat3L& a) {
    Mat3L r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = 0.5 * (a.m[i][j] + a.m[j][i]);
    return r;
}

SH_INLINE Lanes trace(const Mat3L& a) { return a.m[0][0] + a.m[1][1] + a.m[2][2]; }

/// A : B (Frobenius inner product)
SH_INLINE Lanes ddot(const Mat3L& a, const Mat3L& b) {
    Lanes s = a.m[0][0] * b.m[0][0];
    for (int k = 1; k < 9; ++k) s += a.m[k / 3][k % 3] * b.m[k / 3][k % 3];
    return s;
}

/// Cofactor matrix: d det(A) / dA.
SH_INLINE Mat3L cofactor(const Mat3L& a) {
    Mat3L c;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            c.m[i][j] = a.m[i1][j1] * a.m[i2][j2] - a.m[i1][j2] * a.m[i2][j1];
        }
    return c;
}

SH_INLINE Lanes det(const Mat3L& a) {
    return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
           a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0]) +
           a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}

/// s A + t B
SH_INLINE Mat3L combine(Lanes s, const Mat3L& a, Lanes t, const Mat3L& b) {
    Mat3L r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = s * a.m[i][j] + t * b.m[i][j];
    return r;
}

/// A + s I
SH_INLINE Mat3L add_diagonal(Mat3L a, Lanes s) {
    for (int i = 0; i < 3; ++i) a.m[i][i] += s;
    return a;
}

}  // namespace sh
