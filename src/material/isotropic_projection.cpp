#include "material/isotropic_projection.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace sh {
namespace {

using Vector9 = Eigen::Matrix<double, 9, 1>;

// The basis vector u_k v_l^T, as dP/dF's rows and columns are indexed (3 i + j).
Vector9 frame_direction(const SingularFrame& frame, int k, int l) {
    Vector9 q;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) q(3 * i + j) = frame.u(i, k) * frame.v(j, l);
    return q;
}

// c += max(lambda, 0) q q^T.
void add_mode(StressDerivative& c, double lambda, const Vector9& q) {
    if (lambda > 0.0) c.noalias() += lambda * q * q.transpose();
}

// s = v diag(d) v^T with v orthonormal, to round-off. The direct 3x3 solve's eigenvectors of
// nearly equal eigenvalues are only good to about 1e-10 (enough to leave negative eigenvalues
// of that size after a projection) and orthonormal only as well: they are made orthonormal
// (Gram-Schmidt), and one cyclic Jacobi sweep on the nearly diagonal v^T s v, which converges
// quadratically from there, makes them accurate.
void symmetric_eigen(const Eigen::Matrix3d& s, Eigen::Matrix3d& v, Eigen::Vector3d& d) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(s);
    v = eigen.eigenvectors();
    v.col(0).normalize();
    v.col(1) = (v.col(1) - v.col(0).dot(v.col(1)) * v.col(0)).normalized();
    v.col(2) = v.col(0).cross(v.col(1));
    Eigen::Matrix3d a = v.transpose() * s * v;
    for (int p = 0; p < 2; ++p)
        for (int q = p + 1; q < 3; ++q) {
            // Separated eigenvalues come out of the direct solve accurate: nothing to turn.
            if (std::abs(a(p, q)) <= 1e-15 * (std::abs(a(p, p)) + std::abs(a(q, q)))) continue;
            // The rotation by t = tan(theta) in plane (p, q) that zeroes a(p, q).
            const double tau = (a(q, q) - a(p, p)) / (2.0 * a(p, q));
            const double t = (tau >= 0.0 ? 1.0 : -1.0) / (std::abs(tau) + std::sqrt(1.0 + tau * tau));
            const double c = 1.0 / std::sqrt(1.0 + t * t), sn = t * c;
            for (int k = 0; k < 3; ++k) {  // a <- a J (columns p, q)
                const double ap = a(k, p), aq = a(k, q);
                a(k, p) = c * ap - sn * aq, a(k, q) = sn * ap + c * aq;
            }
            for (int k = 0; k < 3; ++k) {  // a <- J^T a (rows p, q)
                const double ap = a(p, k), aq = a(q, k);
                a(p, k) = c * ap - sn * aq, a(q, k) = sn * ap + c * aq;
            }
            for (int k = 0; k < 3; ++k) {  // v <- v J
                const double vp = v(k, p), vq = v(k, q);
                v(k, p) = c * vp - sn * vq, v(k, q) = sn * vp + c * vq;
            }
        }
    d = a.diagonal();
}

// Whether symmetric k is positive definite (its leading minors are positive).
bool positive_definite(const Eigen::Matrix3d& k) {
    const double minor2 = k(0, 0) * k(1, 1) - k(0, 1) * k(0, 1);
    return k(0, 0) > 0.0 && minor2 > 0.0 && k.determinant() > 0.0;
}

}  // namespace

SingularFrame singular_frame(const Eigen::Matrix3d& f, const Eigen::Matrix3d& r) {
    const Eigen::Matrix3d m = r.transpose() * f;
    SingularFrame frame;
    symmetric_eigen(0.5 * (m + m.transpose()), frame.v, frame.s);
    frame.u = r * frame.v;
    return frame;
}

StressDerivative projected_stress_derivative(const PrincipalStiffness& stiffness, const SingularFrame& frame) {
    // The stretches: c = E K E^T with E's columns the modes u_a v_a^T and K the block,
    // projected first unless it is positive definite (as it is for all but strongly compressed
    // elements, where its eigendecomposition is then saved).
    Eigen::Matrix<double, 9, 3> e;
    for (int a = 0; a < 3; ++a) e.col(a) = frame_direction(frame, a, a);
    Eigen::Matrix3d k = stiffness.stretch;
    if (!positive_definite(k)) {
        Eigen::Matrix3d w;
        Eigen::Vector3d lambda;
        symmetric_eigen(k, w, lambda);
        k = w * lambda.cwiseMax(0.0).asDiagonal() * w.transpose();
    }
    StressDerivative c;
    c.noalias() = (e * k).lazyProduct(e.transpose());  // coefficient-wise: no blocked GEMM for 9x9
    for (int m = 0; m < 3; ++m) {
        const int i = m == 0 ? 1 : 0, j = m == 2 ? 1 : 2;
        const Vector9 ij = frame_direction(frame, i, j), ji = frame_direction(frame, j, i);
        add_mode(c, stiffness.shear(m), std::sqrt(0.5) * (ij + ji));
        add_mode(c, stiffness.turn(m), std::sqrt(0.5) * (ij - ji));
    }
    return c;
}

}  // namespace sh
