#include "material/polar_decomposition.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace sh {
namespace {

// det F below this (relative to |F|^3) goes through the SVD path.
constexpr double kSvdThreshold = 1e-3;

Eigen::Matrix3d rotation_by_svd(const Eigen::Matrix3d& f) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU();
    const Eigen::Matrix3d v = svd.matrixV();
    if ((u * v.transpose()).determinant() < 0) u.col(2) = -u.col(2);  // flip the smallest
    return u * v.transpose();
}

}  // namespace

Mat3L polar_rotation(const Mat3L& F) {
    const Lanes d = det(F);
    const Lanes norm2 = ddot(F, F);
    // |det| vs (|F|^2/3)^(3/2): 1 for a scaled rotation, small when nearly flat.
    const Lanes scale3 = norm2 * norm2 * norm2 / 27.0;
    const LaneMask bad = d * d < kSvdThreshold * kSvdThreshold * scale3 || d <= 0.0;
    bool any_bad = false;
    for (int l = 0; l < kLanes; ++l) any_bad |= bad[l] != 0;

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
        const Lanes inv_det = 1.0 / dr;
        Lanes gamma = splat(1.0);  // Frobenius scaling speeds up the first iterations
        Lanes c_scale = inv_det;
        if (iteration < 6) {
            const Lanes rr = ddot(R, R), cc = ddot(C, C) * inv_det * inv_det;
            gamma = lanes_sqrt(lanes_sqrt(cc / rr));
            c_scale = inv_det / gamma;
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
        double worst = 0.0;
        for (int l = 0; l < kLanes; ++l) worst = change[l] > worst ? change[l] : worst;
        if (worst < 1e-28) break;
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

}  // namespace sh
