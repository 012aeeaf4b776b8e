#include "material/polar_decomposition.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace sh {
namespace {

// det F below this (relative to |F|^3) goes through the SVD path.
constexpr double kSvdThreshold = 1e-3;

// The iteration converges quadratically: an update that changes R by d (Frobenius) leaves it
// about d^2 / 2 from the polar factor, so a squared change below 1e-16 (d < 1e-8) returns R
// to about 5e-17, round-off, without one more update to confirm it.
constexpr double kConvergedChange2 = 1e-16;

// A warm start's Newton iterations: past this, a lane still moving takes the cold path.
constexpr int kMaxNearIterations = 4;

// True if no lane's value reaches limit (NaN lanes count as reaching it).
SH_INLINE bool all_below(Lanes value, double limit) {
    bool below = true;
    for (int l = 0; l < kLanes; ++l) below &= value[l] < limit;
    return below;
}

// rotation_update, inlined into polar_rotation_near's loop.
SH_INLINE Lanes update_rotation(const Mat3L& F, Mat3L& R) {
    const Mat3L M = mul_tn(R, F);
    const Lanes w[3] = {M.m[2][1] - M.m[1][2], M.m[0][2] - M.m[2][0], M.m[1][0] - M.m[0][1]};
    Mat3L A;  // tr(S) I - S, symmetric
    const Lanes tr = trace(M);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) A.m[i][j] = -0.5 * (M.m[i][j] + M.m[j][i]);
    for (int i = 0; i < 3; ++i) A.m[i][i] += tr;
    const Mat3L C = cofactor(A);  // A^-1 = C^T / det A = C / det A (symmetric)
    const Lanes det_a = A.m[0][0] * C.m[0][0] + A.m[0][1] * C.m[0][1] + A.m[0][2] * C.m[0][2];
    const LaneMask definite = A.m[0][0] > 0.0 && C.m[2][2] > 0.0 && det_a > 0.0;  // leading minors
    const Lanes inv_det = 1.0 / det_a;
    Lanes c[3];  // omega / 2, the Cayley vector
    for (int i = 0; i < 3; ++i) c[i] = 0.5 * inv_det * (C.m[i][0] * w[0] + C.m[i][1] * w[1] + C.m[i][2] * w[2]);
    const Lanes c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    const Lanes k = 2.0 / (1.0 + c2);
    // Q = I + k ([c] + [c]^2), [c]^2 = c c^T - |c|^2 I.
    Mat3L Q;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Q.m[i][j] = k * c[i] * c[j];
    for (int i = 0; i < 3; ++i) Q.m[i][i] += 1.0 - k * c2;
    Q.m[0][1] -= k * c[2], Q.m[1][0] += k * c[2];
    Q.m[0][2] += k * c[1], Q.m[2][0] -= k * c[1];
    Q.m[1][2] -= k * c[0], Q.m[2][1] += k * c[0];
    R = mul(R, Q);
    return select(definite, 4.0 * c2, splat(NAN));
}

// Lanes whose F is nearly flat or inverted: det F small against |F|^3 ((|F|^2 / 3)^(3/2) is 1
// for a rotation), or not positive. The polar iteration cannot serve them: they take the SVD.
SH_INLINE LaneMask ill_conditioned(const Mat3L& F) {
    const Lanes d = det(F);
    const Lanes norm2 = ddot(F, F);
    const Lanes scale3 = norm2 * norm2 * norm2 / 27.0;
    return d * d < kSvdThreshold * kSvdThreshold * scale3 || d <= 0.0;
}

Eigen::Matrix3d rotation_by_svd(const Eigen::Matrix3d& f) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU();
    const Eigen::Matrix3d v = svd.matrixV();
    if ((u * v.transpose()).determinant() < 0) u.col(2) = -u.col(2);  // flip the smallest
    return u * v.transpose();
}

}  // namespace

Mat3L polar_rotation(const Mat3L& F) {
    const LaneMask bad = ill_conditioned(F);
    const bool any_bad = any_lane(bad);

    // Bad lanes start from I (keeps Newton finite; the SVD below replaces them).
    Mat3L R = F;
    if (any_bad) {
        const Mat3L I = identity_lanes();
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) R.m[i][j] = select(bad, I.m[i][j], F.m[i][j]);
    }

    for (int iteration = 0; iteration < 20; ++iteration) {
        const Mat3L C = cofactor(R);  // R^-T = C / det R
        const Lanes dr = R.m[0][0] * C.m[0][0] + R.m[0][1] * C.m[0][1] + R.m[0][2] * C.m[0][2];
        Lanes gamma = splat(1.0);  // Frobenius scaling speeds up the first iterations
        Lanes c_scale;
        if (iteration < 6) {
            // gamma = (|R^-T| / |R|)^(1/2) = (|C|^2 / (|R|^2 det^2))^(1/4); C scales by 1/(det gamma).
            gamma = lanes_sqrt(lanes_sqrt(ddot(C, C) / (ddot(R, R) * dr * dr)));
            c_scale = 1.0 / (dr * gamma);
        } else {
            c_scale = 1.0 / dr;
        }
        Mat3L next;
        Lanes change = Lanes{};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                next.m[i][j] = 0.5 * (gamma * R.m[i][j] + C.m[i][j] * c_scale);
                const Lanes diff = next.m[i][j] - R.m[i][j];
                change += diff * diff;
            }
        R = next;
        // Converged when no lane's squared change reaches kConvergedChange2 (NaN lanes do not
        // hold the others up).
        bool moving = false;
#if defined(__AVX512F__)
        moving = _mm512_cmp_pd_mask(change, _mm512_set1_pd(kConvergedChange2), _CMP_GE_OQ) != 0;
#else
        for (int l = 0; l < kLanes; ++l) moving |= change[l] >= kConvergedChange2;
#endif
        if (!moving) break;
    }

    if (any_bad)
        for (int l = 0; l < kLanes; ++l) {
            if (!bad[l]) continue;
            Eigen::Matrix3d f;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) f(i, j) = F.m[i][j][l];
            const Eigen::Matrix3d r = rotation_by_svd(f);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) R.m[i][j][l] = r(i, j);
        }
    return R;
}

Lanes rotation_update(const Mat3L& F, Mat3L& R) { return update_rotation(F, R); }

Mat3L polar_rotation_near(const Mat3L& F, const Mat3L& near, double settled2) {
    // Nearly flat or inverted lanes are the cold path's (its SVD branch): the warm start
    // would converge to a rotation of the wrong sign there.
    const LaneMask bad = ill_conditioned(F);
    if (any_lane(bad)) return polar_rotation(F);
    Mat3L R = near;
    for (int iteration = 0; iteration < kMaxNearIterations; ++iteration)
        if (all_below(update_rotation(F, R), settled2)) return R;
    return polar_rotation(F);
}

}  // namespace sh
