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

    Mat3L R = F;
    for (int l = 0; l < kLanes; ++l)
        if (bad[l])
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) R.m[i][j][l] = i == j ? 1.0 : 0.0;  // keeps Newton finite; SVD below

    for (int iteration = 0; iteration < 20; ++iteration) {
        const Mat3L C = cofactor(R);  // R^-T = C / det R
        const Lanes dr = det(R);
        const Lanes inv_det = 1.0 / dr;
        const Lanes rr = ddot(R, R), cc = ddot(C, C) * inv_det * inv_det;
        Lanes gamma = splat(1.0);  // Frobenius scaling speeds up the first iterations
        if (iteration < 6)
            for (int l = 0; l < kLanes; ++l) gamma[l] = std::sqrt(std::sqrt(cc[l] / rr[l]));
        Mat3L next;
        Lanes change = Lanes{};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                next.m[i][j] = 0.5 * (gamma * R.m[i][j] + C.m[i][j] * inv_det / gamma);
                const Lanes diff = next.m[i][j] - R.m[i][j];
                change += diff * diff;
            }
        R = next;
        double worst = 0.0;
        for (int l = 0; l < kLanes; ++l) worst = change[l] > worst ? change[l] : worst;
        if (worst < 1e-28) break;
    }

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
