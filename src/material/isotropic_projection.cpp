#include "material/isotropic_projection.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace sh {
namespace {

using Vector9 = Eigen::Matrix<double, 9, 1>;

// The basis vector u_k v_l^T, as c's rows and columns are indexed (3 i + j).
Vector9 frame_direction(const Eigen::Matrix3d& u, const Eigen::Matrix3d& v, int k, int l) {
    Vector9 q;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) q(3 * i + j) = u(i, k) * v(j, l);
    return q;
}

// Removes eigenpair (lambda, q) from c if lambda < 0; counts it.
void remove_if_negative(StressDerivative& c, double lambda, const Vector9& q, int& removed) {
    if (!(lambda < 0.0)) return;
    c.noalias() -= lambda * q * q.transpose();
    ++removed;
}

}  // namespace

int project_isotropic_tangent(StressDerivative& c, const Eigen::Matrix3d& f) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d& u = svd.matrixU();
    const Eigen::Matrix3d& v = svd.matrixV();
    int removed = 0;
    // The stretches' 3x3 block.
    Vector9 stretch[3];
    for (int k = 0; k < 3; ++k) stretch[k] = frame_direction(u, v, k, k);
    Eigen::Matrix3d block;
    for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) block(a, b) = block(b, a) = stretch[a].dot(c * stretch[b]);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(block);
    for (int m = 0; m < 3; ++m) {
        if (!(eigen.eigenvalues()(m) < 0.0)) continue;
        const Eigen::Vector3d w = eigen.eigenvectors().col(m);
        remove_if_negative(c, eigen.eigenvalues()(m), w(0) * stretch[0] + w(1) * stretch[1] + w(2) * stretch[2],
                           removed);
    }
    // Each pair's 2x2 block [[a, b], [b, d]]: eigenvectors (1, +-1) / sqrt 2 when a = d, as
    // isotropy makes it; its general closed form otherwise (round-off).
    for (int k = 0; k < 3; ++k)
        for (int l = k + 1; l < 3; ++l) {
            const Vector9 p = frame_direction(u, v, k, l), q = frame_direction(u, v, l, k);
            const Vector9 cp = c * p, cq = c * q;
            const double a = p.dot(cp), b = p.dot(cq), d = q.dot(cq);
            const double mean = 0.5 * (a + d), half_gap = std::hypot(0.5 * (a - d), b);
            const double low = mean - half_gap, high = mean + half_gap;
            // The eigenvector of `high`: (b, high - a) or (high - d, b), whichever is longer.
            double x = b, y = high - a;
            if (std::hypot(high - d, b) > std::hypot(x, y)) x = high - d, y = b;
            const double length = std::hypot(x, y);
            if (!(length > 0.0)) x = 1.0, y = 0.0;  // a = d, b = 0: any pair is an eigenbasis
            else x /= length, y /= length;
            remove_if_negative(c, high, x * p + y * q, removed);
            remove_if_negative(c, low, -y * p + x * q, removed);
        }
    return removed;
}

}  // namespace sh
