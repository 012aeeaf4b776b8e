#include "material/isotropic_projection.hpp"

#include "material/polar_decomposition.hpp"

namespace sh {
namespace {

// Cyclic Jacobi sweeps stop once every lane's off-diagonal part is below this fraction of its
// matrix (squared): round-off, reached in two to four sweeps (convergence is quadratic).
constexpr double kOffDiagonal2 = 1e-30;
constexpr int kMaxSweeps = 8;

SH_INLINE Lanes positive_part(Lanes x) { return select(x > 0.0, x, Lanes{}); }

// 1 / size per lane, 1 where size is 0: the factor that brings a matrix of that size to unit
// size (a zero one stays as it is).
SH_INLINE Lanes unit_scale(Lanes size) {
    return select(size > 0.0, 1.0 / select(size > 0.0, size, splat(1.0)), splat(1.0));
}

// One Jacobi rotation per lane in plane (p, q) of the symmetric a, zeroing a[p][q]
// (Golub and Van Loan's symmetric Schur step, written without dividing by a[p][q]);
// v <- v J gathers the rotations. With d = a_qq - a_pp and r = sqrt(d^2 + 4 a_pq^2) the
// rotation's tangent is t = 2 a_pq sign(d) / (|d| + r), and with k = 1 / sqrt(2 r (|d| + r))
// its cosine and sine are (|d| + r) k and 2 a_pq sign(d) k (c^2 + s^2 = 1 by r's definition):
// a square root and an inverse square root in a row (lanes_rsqrt), where 1 / sqrt(1 + t^2)
// after t takes two of each of a square root and a division (the turns' latency is most of
// the frames' time).
SH_INLINE void jacobi_turn(Lanes (&a)[3][3], Mat3L& v, int p, int q) {
    const Lanes apq = a[p][q], d = a[q][q] - a[p][p];
    const Lanes r = lanes_sqrt(d * d + 4.0 * apq * apq), magnitude = abs_lane(d) + r;
    const Lanes sign = select(d < 0.0, splat(-1.0), splat(1.0));
    const LaneMask turns = magnitude > 0.0;
    const Lanes k = lanes_rsqrt(select(turns, 2.0 * r * magnitude, splat(1.0)));
    const Lanes c = select(turns, magnitude * k, splat(1.0)), s = select(turns, 2.0 * apq * sign * k, Lanes{});
    for (int k = 0; k < 3; ++k) {
        const Lanes kp = a[k][p], kq = a[k][q];
        a[k][p] = c * kp - s * kq;
        a[k][q] = s * kp + c * kq;
    }
    for (int k = 0; k < 3; ++k) {
        const Lanes pk = a[p][k], qk = a[q][k];
        a[p][k] = c * pk - s * qk;
        a[q][k] = s * pk + c * qk;
    }
    for (int k = 0; k < 3; ++k) {
        const Lanes kp = v.m[k][p], kq = v.m[k][q];
        v.m[k][p] = c * kp - s * kq;
        v.m[k][q] = s * kp + c * kq;
    }
}

// a[n] = v[n] diag v[n]^T per lane, for N matrices at once: each a[n] is turned diagonal in
// place (its eigenvalues on the diagonal) and v[n] gets the orthonormal eigenvectors as
// columns. The N problems' turns alternate, so that one's chain of square roots and divisions
// runs while another's waits on its own (a turn's latency, not its arithmetic, bounds one).
template <int N>
void symmetric_eigen(Lanes (&a)[N][3][3], Mat3L (&v)[N]) {
    bool open[N];
    Lanes pair_floor[N];
    for (int n = 0; n < N; ++n) v[n] = identity_lanes();
    for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
        bool any_open = false;
        for (int n = 0; n < N; ++n) {
            const Lanes off = a[n][0][1] * a[n][0][1] + a[n][0][2] * a[n][0][2] + a[n][1][2] * a[n][1][2];
            const Lanes size = a[n][0][0] * a[n][0][0] + a[n][1][1] * a[n][1][1] + a[n][2][2] * a[n][2][2] + 2.0 * off;
            open[n] = any_lane(off > kOffDiagonal2 * size);  // NaN lanes do not hold the others up
            any_open |= open[n];
            // A pair already below a third of the tolerance in every lane is not turned in
            // this sweep (one turn in eight over the raptor's swing); the test above still
            // decides when the sweeps end, so the frames are as accurate (size, the squared
            // Frobenius norm, is the same under every turn).
            pair_floor[n] = (kOffDiagonal2 / 3.0) * size;
        }
        if (!any_open) return;
        static constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (const auto& pq : kPairs)
            for (int n = 0; n < N; ++n)
                if (open[n] && any_lane(a[n][pq[0]][pq[1]] * a[n][pq[0]][pq[1]] > pair_floor[n]))
                    jacobi_turn(a[n], v[n], pq[0], pq[1]);
    }
}

// The stretches' block with its negative eigenvalues set to zero, in the lanes where it is not
// positive definite (strongly compressed elements; the others keep theirs unchanged). The test
// and the eigen-solve run on the block divided by its largest entry: its third minor cubes the
// entries (beyond about 1e103 it overflows, below 1e-103 it underflows) and a Jacobi turn
// squares them; the projection scales with the block, so the result is multiplied back.
void project_stretch_block(Lanes (&k)[3][3]) {
    Lanes size = Lanes{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) size = max_lane(size, abs_lane(k[i][j]));
    const Lanes scale = unit_scale(size);
    Lanes a[1][3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) a[0][i][j] = scale * k[i][j];
    const Lanes(&u)[3][3] = a[0];
    const Lanes minor2 = u[0][0] * u[1][1] - u[0][1] * u[0][1];
    const Lanes minor3 = u[0][0] * (u[1][1] * u[2][2] - u[1][2] * u[1][2]) -
                         u[0][1] * (u[0][1] * u[2][2] - u[1][2] * u[0][2]) +
                         u[0][2] * (u[0][1] * u[1][2] - u[1][1] * u[0][2]);
    const LaneMask indefinite = !(u[0][0] > 0.0 && minor2 > 0.0 && minor3 > 0.0);
    if (!any_lane(indefinite)) return;
    Mat3L w[1];
    symmetric_eigen(a, w);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            Lanes sum = Lanes{};
            for (int m = 0; m < 3; ++m) sum += w[0].m[i][m] * positive_part(a[0][m][m]) * w[0].m[j][m];
            k[i][j] = select(indefinite, size * sum, k[i][j]);
        }
}

// A Gram batch's frames stand where every lane's F is well-conditioned: its smallest
// eigenvalue of F^T F is at least this fraction of its largest (singular values within a factor
// of about 3). There u = F v / s is as accurate as the polar path's r v: F^T F's eigen-solve
// leaves off-diagonal parts of about 1e-15 |F|^2, which u^T F v carries divided by s, within
// round-off of |F| while s is within that factor of |F|.
constexpr double kGramConditioning = 0.1;

// Lanes a Gram batch may serve: det F > 0 (F^T F does not see the sign of det F, which the
// frame must carry) and finite.
SH_INLINE bool gram_batch(const Mat3L& unit) {
    const Lanes d = det(unit);
    return !any_lane(!(d > 0.0));
}

// A Gram batch's frame from F (at unit size), the eigenvalues of F^T F on a's diagonal and its
// eigenvectors v: w_i = F v_i has length s_i and direction u_i; u_0 and u_1 are made
// orthonormal (Gram-Schmidt) and u_2 = u_0 x u_1 (v is a rotation, a product of Jacobi turns,
// and so is u, as in the polar path), and s_i = u_i . F v_i. False, with out untouched, if a lane is not
// as well-conditioned as kGramConditioning asks.
bool gram_frame(const Mat3L& unit, const Lanes (&a)[3][3], const Mat3L& v, Lanes scale, SingularFrameLanes& out) {
    const Lanes largest = max_lane(max_lane(a[0][0], a[1][1]), a[2][2]);
    const Lanes smallest = -max_lane(max_lane(-a[0][0], -a[1][1]), -a[2][2]);
    if (any_lane(!(smallest >= kGramConditioning * largest))) return false;
    const Mat3L w = mul(unit, v);  // column i: F v_i
    Lanes u[3][3];                  // u[i]: column i of u
    for (int i = 0; i < 2; ++i)
        for (int k = 0; k < 3; ++k) u[i][k] = w.m[k][i];
    const Lanes along = u[0][0] * u[1][0] + u[0][1] * u[1][1] + u[0][2] * u[1][2];
    const Lanes length0 = u[0][0] * u[0][0] + u[0][1] * u[0][1] + u[0][2] * u[0][2];
    for (int k = 0; k < 3; ++k) u[1][k] -= (along / length0) * u[0][k];
    for (int i = 0; i < 2; ++i) {
        const Lanes inverse = lanes_rsqrt(u[i][0] * u[i][0] + u[i][1] * u[i][1] + u[i][2] * u[i][2]);
        for (int k = 0; k < 3; ++k) u[i][k] *= inverse;
    }
    for (int k = 0; k < 3; ++k) u[2][k] = u[0][(k + 1) % 3] * u[1][(k + 2) % 3] - u[0][(k + 2) % 3] * u[1][(k + 1) % 3];
    out.v = v;
    for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 3; ++k) out.u.m[k][i] = u[i][k];
        out.s[i] = (u[i][0] * w.m[0][i] + u[i][1] * w.m[1][i] + u[i][2] * w.m[2][i]) / scale;
    }
    return true;
}

// The frames of N batches at once (their eigen-solves interleaved: symmetric_eigen). A batch
// with det F > 0 in every lane solves F^T F where the others solve sym(r^T F) after a polar
// iteration (from near where given): u then comes from F v directly, and the polar iteration
// (five to eight Newton steps cold, one or two from near) is saved. Where its lanes are not
// well-conditioned enough for that (gram_frame), the batch is solved again the polar way
// (gram false).
template <int N>
void frames_of(const Mat3L* F, const Mat3L* const* near, SingularFrameLanes* out, bool gram = true) {
    Lanes a[N][3][3], scale[N];
    Mat3L r[N], v[N], unit[N];
    bool by_gram[N];
    for (int n = 0; n < N; ++n) {
        // F scaled to unit size first: the polar iteration's scaling multiplies |F|^8, which
        // leaves the doubles' range for |F| beyond about 1e-40 or 1e39; the frame is the same.
        scale[n] = unit_scale(lanes_sqrt(ddot(F[n], F[n])));
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) unit[n].m[i][j] = scale[n] * F[n].m[i][j];
        by_gram[n] = gram && gram_batch(unit[n]);
        if (by_gram[n]) {
            const Mat3L m = mul_tn(unit[n], unit[n]);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) a[n][i][j] = m.m[i][j];
            continue;
        }
        r[n] = near[n] ? polar_rotation_near(unit[n], *near[n]) : polar_rotation(unit[n]);  // the same rotation as F's
        const Mat3L m = mul_tn(r[n], unit[n]);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) a[n][i][j] = 0.5 * (m.m[i][j] + m.m[j][i]);
    }
    symmetric_eigen(a, v);
    for (int n = 0; n < N; ++n) {
        if (by_gram[n]) {
            if (!gram_frame(unit[n], a[n], v[n], scale[n], out[n])) frames_of<1>(&F[n], &near[n], &out[n], false);
            continue;
        }
        out[n].v = v[n];
        for (int i = 0; i < 3; ++i) out[n].s[i] = a[n][i][i] / scale[n];
        out[n].u = mul(r[n], v[n]);
    }
}

}  // namespace

SingularFrameLanes singular_frames(const Mat3L& F, const Mat3L* near) {
    SingularFrameLanes frame;
    frames_of<1>(&F, &near, &frame);
    return frame;
}

void singular_frame_pair(const Mat3L (&F)[2], const Mat3L* const (&near)[2], SingularFrameLanes (&out)[2]) {
    frames_of<2>(F, near, out);
}

PrincipalStiffnessLanes projected_principal_stiffness(const PrincipalStiffnessLanes& stiffness) {
    PrincipalStiffnessLanes projected = stiffness;
    project_stretch_block(projected.stretch);
    for (int m = 0; m < 3; ++m) {
        projected.shear[m] = positive_part(stiffness.shear[m]);
        projected.turn[m] = positive_part(stiffness.turn[m]);
    }
    return projected;
}

}  // namespace sh
