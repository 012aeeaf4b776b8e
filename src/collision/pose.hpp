// Pose: a rigid placement (position and unit quaternion) and the maps it makes.
#pragma once

#include <cmath>

namespace sh {

/// A rigid placement: world = q * local + p, q = (w, x, y, z) a unit quaternion.
struct Pose {
    double p[3] = {0.0, 0.0, 0.0};
    double q[4] = {1.0, 0.0, 0.0, 0.0};

    /// out = R in (rotation only).
    void rotate(const double in[3], double out[3]) const {
        const double w = q[0], x = q[1], y = q[2], z = q[3];
        // t = 2 (q_v x in); out = in + w t + q_v x t
        const double t0 = 2.0 * (y * in[2] - z * in[1]);
        const double t1 = 2.0 * (z * in[0] - x * in[2]);
        const double t2 = 2.0 * (x * in[1] - y * in[0]);
        out[0] = in[0] + w * t0 + (y * t2 - z * t1);
        out[1] = in[1] + w * t1 + (z * t0 - x * t2);
        out[2] = in[2] + w * t2 + (x * t1 - y * t0);
    }

    /// out = R^T in.
    void unrotate(const double in[3], double out[3]) const {
        const Pose inverse{{0.0, 0.0, 0.0}, {q[0], -q[1], -q[2], -q[3]}};
        inverse.rotate(in, out);
    }

    /// World point of a local point.
    void to_world(const double local[3], double out[3]) const {
        rotate(local, out);
        for (int k = 0; k < 3; ++k) out[k] += p[k];
    }

    /// Local point of a world point.
    void to_local(const double world[3], double out[3]) const {
        const double d[3] = {world[0] - p[0], world[1] - p[1], world[2] - p[2]};
        unrotate(d, out);
    }

    /// The rotation as a matrix: R[i][j] = (R e_j)_i, its columns the local axes in the world.
    void rotation_matrix(double R[3][3]) const {
        for (int j = 0; j < 3; ++j) {
            double e[3] = {0.0, 0.0, 0.0};
            e[j] = 1.0;
            double c[3];
            rotate(e, c);
            for (int i = 0; i < 3; ++i) R[i][j] = c[i];
        }
    }
};

/// out = the pose (position, orientation normalised); false, out untouched, if a pointer is
/// null, the position is not finite or the quaternion is zero or not finite. Never throws.
inline bool read_pose(const double position[3], const double orientation[4], Pose& out) noexcept {
    if (!position || !orientation) return false;
    double norm2 = 0.0;
    for (int k = 0; k < 4; ++k) norm2 += orientation[k] * orientation[k];
    if (!(std::isfinite(position[0] + position[1] + position[2]) && std::isfinite(norm2) && norm2 > 0.0)) return false;
    const double inverse = 1.0 / std::sqrt(norm2);
    for (int k = 0; k < 3; ++k) out.p[k] = position[k];
    for (int k = 0; k < 4; ++k) out.q[k] = orientation[k] * inverse;
    return true;
}

/// The quaternion product a b (w, x, y, z): the rotation b, then a.
inline void quaternion_product(const double a[4], const double b[4], double out[4]) {
    out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/// The pose a fraction s in [0, 1] of the way from a to b: positions linearly, orientations
/// by normalised linear interpolation along the shorter arc (exact at s = 0 and 1).
inline Pose interpolate(const Pose& a, const Pose& b, double s) {
    Pose out;
    for (int k = 0; k < 3; ++k) out.p[k] = a.p[k] + s * (b.p[k] - a.p[k]);
    double dot = 0.0;
    for (int k = 0; k < 4; ++k) dot += a.q[k] * b.q[k];
    const double sign = dot < 0.0 ? -1.0 : 1.0;
    double norm = 0.0;
    for (int k = 0; k < 4; ++k) {
        out.q[k] = (1.0 - s) * a.q[k] + s * sign * b.q[k];
        norm += out.q[k] * out.q[k];
    }
    norm = std::sqrt(norm);
    for (int k = 0; k < 4; ++k) out.q[k] /= norm;
    return out;
}

}  // namespace sh
