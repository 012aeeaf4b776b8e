// The excess of a collider of several balls: the Lehmer mean of its balls' excesses (see
// ball_mix.hpp), its terms, and its tangent across them.
#include "contact/ball_mix.hpp"

#include "contact/ball_terms.hpp"
#include "collision/unit_vector.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace sh {
namespace {

// Adds `share` of term's energy and geometry, and `coefficient` of its forces, to out;
// geometry weighs by |share * energy| (`mass` keeps the sum).
void mix_term(const ContactPoint& term, double share, double coefficient, ContactPoint& out, double& mass) {
    const double w = std::fabs(share * term.energy);
    out.energy += share * term.energy;
    out.stiffness += share * term.stiffness;
    out.normal_force += coefficient * term.normal_force;
    out.net_normal_force += coefficient * term.net_normal_force;
    out.depth += w * term.depth;
    for (int k = 0; k < 3; ++k) {
        out.point[k] += w * term.point[k];
        out.normal[k] += w * term.normal[k];
    }
    for (int a = 0; a < term.count; ++a) {
        out.weights[a] += w * term.weights[a];
        for (int k = 0; k < 3; ++k) {
            out.node_force[a][k] += coefficient * term.node_force[a][k];
            out.gradient[a][k] += w * term.gradient[a][k];
        }
    }
    mass += w;
}

// The stiffness of a mixed term over its nodes' 3 count coordinates, for its bound per node
// (ContactPoint::stiffness_bound; the full model's tangent takes the mix's across all its
// terms instead, BallMix::tangent), in two parts: its balls' law curvature, sum_i c_i k_i
// g_i g_i^T (each ball's own tangent) where c_i k_i > 0, and the smooth maximum's curvature
// within the term, sum_ij (d c_i / d P_j) G_i G_j^T, G_i the gradient of ball i's term (minus
// its node forces) and d c_i / d P_j from BallMix. Each part's bound is Gershgorin's: its row
// sums of its blocks' norms.
class MixedHessian {
public:
    void add(const ContactPoint& term, double coefficient, double curvature, double cross) {
        double g[9] = {}, G[9] = {};
        for (int a = 0; a < term.count; ++a)
            for (int k = 0; k < 3; ++k) {
                g[3 * a + k] = term.gradient[a][k];
                G[3 * a + k] = -term.node_force[a][k];
            }
        const double law = std::max(coefficient * term.stiffness, 0.0);
        for (int r = 0; r < 9; ++r) {
            b_[r] += cross * G[r];
            c_[r] += coefficient * G[r];
            for (int s = 0; s < 9; ++s) {
                law_[r][s] += law * g[r] * g[s];
                curvature_[r][s] += curvature * G[r] * G[s];
            }
        }
    }
    /// Node a's bound (N/m) over the term's count nodes.
    double bound(int a, int count) const {
        double sum = 0.0;
        for (int b = 0; b < count; ++b) {
            double block[9];
            for (int r = 0; r < 3; ++r)
                for (int s = 0; s < 3; ++s) {
                    const int i = 3 * a + r, j = 3 * b + s;
                    block[3 * r + s] = curvature_[i][j] - b_[i] * c_[j] - c_[i] * b_[j];
                }
            sum += block_norm(block, 3, 1) + block_norm(&law_[3 * a][3 * b], 9, 1);
        }
        return sum;
    }

private:
    double law_[9][9] = {}, curvature_[9][9] = {}, b_[9] = {}, c_[9] = {};
};

}  // namespace

bool BallMix::term(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
                   double weight, ContactPoint& out) const {
    out = ContactPoint{};
    out.count = count;
    out.law_scale = count == 2 ? -1.0 : 1.0;
    for (int a = 0; a < count; ++a) out.nodes[a] = nodes[a];
    double mass = 0.0;
    bool any = false;
    MixedHessian hessian;
    for_each_ball_term(collider, law, x, nodes, count, weight, [&](int i, const ContactPoint& term) {
        if (share(i) == 0.0 && coefficient(i) == 0.0) return;
        mix_term(term, share(i), coefficient(i), out, mass);
        hessian.add(term, coefficient(i), curvature(i), cross(i));
        any = true;
    });
    if (!any || !(mass > 0.0)) return false;
    out.mixed = true;
    for (int a = 0; a < count; ++a) out.stiffness_bound[a] = hessian.bound(a, count);
    out.depth /= mass;
    for (int k = 0; k < 3; ++k) out.point[k] /= mass;
    if (!normalize3(out.normal)) return false;
    for (int a = 0; a < count; ++a) {
        out.weights[a] /= mass;
        for (int k = 0; k < 3; ++k) out.gradient[a][k] /= mass;
    }
    return true;
}

void BallMix::reserve(int count) {
    if (mix_.size() < kFields * static_cast<size_t>(count)) mix_.resize(kFields * static_cast<size_t>(count));
}

void BallMix::begin(const Collider& collider) {
    count_ = collider.shape.ball_count();
    assert(mix_.size() >= kFields * static_cast<size_t>(count_) && "BallMix::reserve first");
    for (int i = 0; i < count_; ++i) mix_[kFields * static_cast<size_t>(i)] = 0.0;
}

void BallMix::add(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
                  double weight) {
    for_each_ball_term(collider, law, x, nodes, count, weight,
                       [&](int i, const ContactPoint& term) { mix_[kFields * static_cast<size_t>(i)] += term.energy; });
}

void BallMix::finish() {
    // In units u_i = P_i / P_max of the largest total, so that the powers stay in range; a
    // largest total within round-off of the smallest doubles counts as none (its curvature,
    // over P_max, would overflow).
    double largest = 0.0;
    for (int i = 0; i < count_; ++i) largest = std::max(largest, mix_[kFields * static_cast<size_t>(i)]);
    if (!(largest > std::numeric_limits<double>::min() / std::numeric_limits<double>::epsilon())) largest = 0.0;
    double sum_p = 0.0, sum_p1 = 0.0;
    for (int i = 0; i < count_ && largest > 0.0; ++i) {
        const double u = std::max(mix_[kFields * static_cast<size_t>(i)], 0.0) / largest;
        const double power = std::pow(u, kOrder);
        sum_p += power;
        sum_p1 += power * u;
    }
    const double mean = sum_p > 0.0 ? sum_p1 / sum_p : 0.0, p = kOrder;
    for (int i = 0; i < count_; ++i) {
        double* m = &mix_[kFields * static_cast<size_t>(i)];
        const double u = largest > 0.0 ? std::max(m[0], 0.0) / largest : 0.0;
        const double power = u > 0.0 ? std::pow(u, kOrder - 2) : 0.0;  // u^(p-2)
        m[1] = power > 0.0 ? power * u * u / sum_p : 0.0;
        m[2] = power > 0.0 ? power * u * ((p + 1.0) * u - p * mean) / sum_p : 0.0;
        m[3] = power > 0.0 ? p * power * ((p + 1.0) * u - (p - 1.0) * mean) / (sum_p * largest) : 0.0;
        m[4] = power > 0.0 ? p * power * u / (sum_p * largest) : 0.0;
    }
}

void BallMix::begin_tangent() {
    touched_.clear();
    column_.assign(static_cast<size_t>(count_), -1);
    columns_ = 0;
    gradient_.clear();
    gradient_column_.clear();
    gradient_node_.clear();
    law_.clear();
    law_node_.clear();
}

void BallMix::add_tangent_term(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes,
                               int count, double weight) {
    int32_t local[3];
    for (int a = 0; a < count; ++a) {
        const auto found = std::find(touched_.begin(), touched_.end(), nodes[a]);
        local[a] = static_cast<int32_t>(found - touched_.begin());
        if (found == touched_.end()) touched_.push_back(nodes[a]);
    }
    double law_curvature[9][9] = {};  // the term's sum_i c_i k_i g_i g_i^T, sign included
    for_each_ball_term(collider, law, x, nodes, count, weight, [&](int i, const ContactPoint& term) {
        if (share(i) == 0.0 && coefficient(i) == 0.0) return;
        int32_t& column = column_[static_cast<size_t>(i)];
        if (column < 0) column = columns_++;
        for (int a = 0; a < count; ++a) {
            gradient_column_.push_back(column);
            gradient_node_.push_back(local[a]);
            for (int k = 0; k < 3; ++k) gradient_.push_back(-term.node_force[a][k]);
        }
        const double scale = coefficient(i) * term.stiffness;
        for (int r = 0; r < 3 * count; ++r)
            for (int s = 0; s < 3 * count; ++s) law_curvature[r][s] += scale * term.gradient[r / 3][r % 3] * term.gradient[s / 3][s % 3];
    });
    for (int a = 0; a < count; ++a)
        for (int b = 0; b < count; ++b) {
            law_node_.push_back(local[a]);
            law_node_.push_back(local[b]);
            for (int r = 0; r < 3; ++r)
                for (int s = 0; s < 3; ++s) law_.push_back(law_curvature[3 * a + r][3 * b + s]);
        }
}

void BallMix::tangent_matrix(vec<double>& out) const {
    const Eigen::Index dim = 3 * static_cast<Eigen::Index>(touched_.size());
    const Eigen::Index balls = columns_;
    out.assign(static_cast<size_t>(dim * dim), 0.0);
    if (dim == 0 || balls == 0) return;
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(dim, balls);
    for (size_t e = 0; e < gradient_column_.size(); ++e)
        for (int k = 0; k < 3; ++k) g(3 * gradient_node_[e] + k, gradient_column_[e]) += gradient_[3 * e + static_cast<size_t>(k)];
    vec<int> ball(static_cast<size_t>(balls));
    for (int i = 0; i < count_; ++i)
        if (column_[static_cast<size_t>(i)] >= 0) ball[static_cast<size_t>(column_[static_cast<size_t>(i)])] = i;
    Eigen::MatrixXd h(balls, balls);
    for (Eigen::Index r = 0; r < balls; ++r) {
        const int i = ball[static_cast<size_t>(r)];
        for (Eigen::Index s = 0; s < balls; ++s) {
            const int j = ball[static_cast<size_t>(s)];
            h(r, s) = -(cross(i) * coefficient(j) + coefficient(i) * cross(j));
        }
        h(r, r) += curvature(i);
    }
    // With the terms' law curvature, projected to positive semi-definite over the nodes (not
    // per term or over the balls: an edge's negative part must cancel its faces' first).
    Eigen::MatrixXd k = g * h * g.transpose();
    for (size_t e = 0; 2 * e < law_node_.size(); ++e)
        for (int r = 0; r < 3; ++r)
            for (int s = 0; s < 3; ++s)
                k(3 * law_node_[2 * e] + r, 3 * law_node_[2 * e + 1] + s) += law_[9 * e + static_cast<size_t>(3 * r + s)];
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (k + k.transpose()));
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(out.data(), dim, dim) =
        eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
}

}  // namespace sh
