#include "model/spring_body.hpp"

#include "core/error.hpp"
#include "core/vec3.hpp"
#include "linalg/sparse_system.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

SpringBody::SpringBody(vec<double> nodes, vec<int32_t> springs, const sh_spring_params& params,
                       const vec<double>& masses, double damping_mass)
    : Body(std::move(nodes), damping_mass), springs_(std::move(springs)), law_(params) {
    const int32_t n = node_count();
    const size_t spring_count = springs_.size() / 2;
    vec<uint8_t> on_spring(static_cast<size_t>(n), 0);
    for (size_t s_i = 0; s_i < 2 * spring_count; ++s_i)
        if (springs_[s_i] >= 0 && springs_[s_i] < n) on_spring[static_cast<size_t>(springs_[s_i])] = 1;
    for (int32_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k)
            SH_REQUIRE(std::isfinite(x[3 * static_cast<size_t>(i) + k]), SH_ERR_INVALID_ARGUMENT, "node %d has a non-finite coordinate", i);
        const double m = masses[static_cast<size_t>(i)];
        // Zero mass is allowed only for a node no spring uses: it is left out of the dynamics.
        const bool ok = std::isfinite(m) && (m > 0.0 || (m == 0.0 && spring_count > 0 && !on_spring[static_cast<size_t>(i)]));
        SH_REQUIRE(ok, SH_ERR_INVALID_ARGUMENT, "node %d: mass %g kg, must be finite and > 0", i, m);
        mass[static_cast<size_t>(i)] = m;
    }
    rest_length_.resize(spring_count);
    for (size_t s_i = 0; s_i < spring_count; ++s_i) {
        const int32_t a = springs_[2 * s_i], b = springs_[2 * s_i + 1];
        SH_REQUIRE(a >= 0 && a < n && b >= 0 && b < n, SH_ERR_INVALID_ARGUMENT, "spring %zu: node index (%d, %d) out of range [0, %d)", s_i, a, b, n);
        SH_REQUIRE(a != b, SH_ERR_INVALID_ARGUMENT, "spring %zu joins node %d to itself", s_i, a);
        double l2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double d = x[3 * static_cast<size_t>(b) + k] - x[3 * static_cast<size_t>(a) + k];
            l2 += d * d;
        }
        SH_REQUIRE(l2 > 0.0, SH_ERR_INVALID_ARGUMENT, "spring %zu (nodes %d, %d) has zero rest length", s_i, a, b);
        rest_length_[s_i] = std::sqrt(l2);
        original_.push_back({std::min(a, b), std::max(a, b)});
    }
    SH_REQUIRE(std::isfinite(params.break_strain) && params.break_strain >= 0.0, SH_ERR_INVALID_ARGUMENT,
               "params.break_strain = %g, must be finite and >= 0", params.break_strain);
    break_strain_ = params.break_strain;
    std::sort(original_.begin(), original_.end());
    row_bound_.resize(static_cast<size_t>(n));
    update_inverse_mass();
}

vec<uint8_t> SpringBody::overstretched(const double* xs) const {
    vec<uint8_t> over(rest_length_.size(), 0);
    if (!(break_strain_ > 0.0)) return over;
    for (size_t s = 0; s < rest_length_.size(); ++s) {
        const size_t a = static_cast<size_t>(springs_[2 * s]), b = static_cast<size_t>(springs_[2 * s + 1]);
        double l2 = 0.0;
        for (int k = 0; k < 3; ++k) l2 += (xs[3 * b + k] - xs[3 * a + k]) * (xs[3 * b + k] - xs[3 * a + k]);
        over[s] = std::sqrt(l2) > (1.0 + break_strain_) * rest_length_[s] ? 1 : 0;
    }
    return over;
}

int32_t SpringBody::root_of(int32_t node) const {
    while (parent_of(node) >= 0) node = parent_of(node);
    return node;
}

bool SpringBody::were_joined(int32_t a, int32_t b) const {
    a = root_of(a), b = root_of(b);
    return std::binary_search(original_.begin(), original_.end(), std::make_pair(std::min(a, b), std::max(a, b)));
}

void SpringBody::retopologize(const vec<NodeOrigin>& copies, vec<int32_t> springs, vec<double> rest_lengths,
                              const vec<double>& masses) {
    GrownNodes grown = grow_nodes(copies.data(), copies.size());
    vec<double> new_mass = masses;
    vec<double> row_bound(grown.node_count());
    adopt_nodes(grown);
    mass.swap(new_mass);
    update_inverse_mass();
    springs_.swap(springs);
    rest_length_.swap(rest_lengths);
    row_bound_.swap(row_bound);
    ++topology_version;
    ++matrix_version;
}

int32_t SpringBody::remove_springs(const vec<uint8_t>& broken) {
    vec<int32_t> springs;
    vec<double> rest_length;
    for (size_t s_i = 0; s_i < rest_length_.size(); ++s_i) {
        if (broken[s_i]) continue;
        springs.push_back(springs_[2 * s_i]);
        springs.push_back(springs_[2 * s_i + 1]);
        rest_length.push_back(rest_length_[s_i]);
    }
    const int32_t removed = static_cast<int32_t>(rest_length_.size() - rest_length.size());
    if (removed == 0) return 0;
    springs_.swap(springs);
    rest_length_.swap(rest_length);
    ++topology_version;
    ++matrix_version;
    return removed;
}

// Visits every spring at positions xs: visit(s, a, b, d, l) with its end nodes a and b,
// d = x_b - x_a and l = |d|.
template <class Visit>
void SpringBody::each_spring(const double* xs, Visit&& visit) const {
    for (size_t s = 0; s < rest_length_.size(); ++s) {
        const size_t a = static_cast<size_t>(springs_[2 * s]), b = static_cast<size_t>(springs_[2 * s + 1]);
        double d[3], l2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            d[k] = xs[3 * b + k] - xs[3 * a + k];
            l2 += d[k] * d[k];
        }
        visit(s, a, b, d, std::sqrt(l2));
    }
}

// Adds tension t along d / l to node a and its opposite to node b; returns |t|.
static double add_tension(double t, const double* d, double l, size_t a, size_t b, double* f) {
    for (int k = 0; k < 3; ++k) {
        const double fk = t * d[k] / l;
        f[3 * a + k] += fk;
        f[3 * b + k] -= fk;
    }
    return std::fabs(t);
}

void SpringBody::add_internal_forces(const double* xs, const double* vs, double* f) const {
    const double c = vs ? law_.damping() : 0.0;
    each_spring(xs, [&](size_t s, size_t a, size_t b, const double* d, double l) {
        if (!(l > 0.0)) return;  // coincident ends have no direction: no force
        double t = law_.tension(l, rest_length_[s]);
        if (c > 0.0) {
            double rate = 0.0;
            for (int k = 0; k < 3; ++k) rate += (vs[3 * b + k] - vs[3 * a + k]) * d[k];
            t += c * rate / l;
        }
        add_tension(t, d, l, a, b, f);
    });
}

double SpringBody::elastic_energy(const double* xs) const {
    double energy = 0.0;
    each_spring(xs, [&](size_t s, size_t, size_t, const double*, double l) { energy += law_.energy(l, rest_length_[s]); });
    return energy;
}

Body::ElasticEnergy SpringBody::add_elastic_forces_and_energy(const double* xs, double* f) const {
    ElasticEnergy e;
    double tensions = 0.0;
    each_spring(xs, [&](size_t s, size_t a, size_t b, const double* d, double l) {
        e.value += law_.energy(l, rest_length_[s]);
        if (l > 0.0) tensions += add_tension(law_.tension(l, rest_length_[s]), d, l, a, b, f);
    });
    // A spring's two end forces: each node's rounding moves its energy by |t| times that.
    e.scale = std::fabs(e.value) + 2.0 * largest_magnitude(xs, x.size()) * tensions;
    return e;
}

// One spring's tangent in a sparse solve's operations (Body::tangent_work): a 3x3 block from
// its direction and the law's two derivatives, scattered into four blocks.
constexpr double kSpringTangentWork = 150.0;

double SpringBody::tangent_work() const { return kSpringTangentWork * static_cast<double>(rest_length_.size()); }

double SpringBody::stable_step(const double* xs) const {
    // Block Gershgorin bound of omega_max^2 for M^-1/2 K M^-1/2 at the current state: a
    // spring's 3x3 block k n n^T + (T/l)(I - n n^T) has norm max(k, |T|/l).
    std::fill(row_bound_.begin(), row_bound_.end(), 0.0);
    double damping_ratio_per_omega = 0.0;
    for (size_t s = 0; s < rest_length_.size(); ++s) {
        const size_t a = static_cast<size_t>(springs_[2 * s]), b = static_cast<size_t>(springs_[2 * s + 1]);
        double l2 = 0.0;
        for (int k = 0; k < 3; ++k) l2 += (xs[3 * b + k] - xs[3 * a + k]) * (xs[3 * b + k] - xs[3 * a + k]);
        const double l = std::sqrt(l2), l0 = rest_length_[s];
        double k_eff = std::fabs(law_.stiffness(l, l0));
        if (l > 0.0) k_eff = std::max(k_eff, std::fabs(law_.tension(l, l0)) / l);
        const double ia = inverse_mass[a], ib = inverse_mass[b];
        row_bound_[a] += k_eff * (ia + std::sqrt(ia * ib));
        row_bound_[b] += k_eff * (ib + std::sqrt(ia * ib));
        if (k_eff > 0.0) damping_ratio_per_omega = std::max(damping_ratio_per_omega, 0.5 * law_.damping() / k_eff);
    }
    const double omega2 = *std::max_element(row_bound_.begin(), row_bound_.end());
    if (!(omega2 > 0.0)) return INFINITY;
    const double omega = std::sqrt(omega2), xi = damping_ratio_per_omega * omega;
    return 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
}

void SpringBody::add_tangent(const double* xs, double stiffness_scale, double damping_scale, SparseSystem& system) const {
    // Spring block B = k_t n n^T + (T/l)(I - n n^T), with k_t and T/l clamped at zero (a
    // compressed spring's negative geometric stiffness is dropped so B stays semi-definite);
    // dashpot block c n n^T. The element matrix is [B, -B; -B, B].
    for (size_t s = 0; s < rest_length_.size(); ++s) {
        const size_t a = static_cast<size_t>(springs_[2 * s]), b = static_cast<size_t>(springs_[2 * s + 1]);
        double n[3], l2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            n[k] = xs[3 * b + k] - xs[3 * a + k];
            l2 += n[k] * n[k];
        }
        const double l = std::sqrt(l2), l0 = rest_length_[s];
        if (!(l > 0.0)) continue;
        for (double& c : n) c /= l;
        const double axial = stiffness_scale * std::max(law_.stiffness(l, l0), 0.0) + damping_scale * law_.damping();
        const double transverse = stiffness_scale * std::max(law_.tension(l, l0) / l, 0.0);
        double ke[36];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                const double block = axial * n[i] * n[j] + transverse * ((i == j ? 1.0 : 0.0) - n[i] * n[j]);
                ke[6 * i + j] = ke[6 * (i + 3) + j + 3] = block;
                ke[6 * i + j + 3] = ke[6 * (i + 3) + j] = -block;
            }
        system.add_element(s, ke, 1.0);
    }
}

}  // namespace sh
