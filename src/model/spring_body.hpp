// SpringBody: a mass-spring network with one spring law for all its springs.
#pragma once

#include "material/spring_laws.hpp"
#include "model/body.hpp"

#include <utility>

namespace sh {

/// Mass-spring body. Rest lengths are the initial lengths.
class SpringBody final : public Body {
public:
    /// nodes: 3 per node; springs: 2 node indices per spring; masses: one per node (> 0);
    /// damping_mass: Rayleigh alpha (1/s). Throws SH_ERR_INVALID_ARGUMENT naming the spring or
    /// node that is invalid.
    SpringBody(vec<double> nodes, vec<int32_t> springs, const sh_spring_params& params, const vec<double>& masses,
               double damping_mass);

    void add_internal_forces(const double* x, const double* v, double* f) const override;
    bool has_internal_damping() const override { return law_.damping() > 0.0; }
    double elastic_energy(const double* x) const override;
    ElasticEnergy add_elastic_forces_and_energy(const double* x, double* f) const override;
    double stable_step(const double* x) const override;
    /// kSpringTangentWork per spring.
    double tangent_work() const override;
    void add_tangent(const double* x, double stiffness_scale, double damping_scale,
                     SparseSystem& system) const override;
    const int32_t* element_nodes() const override { return springs_.data(); }
    int nodes_per_element() const override { return 2; }
    int32_t element_count() const override { return static_cast<int32_t>(rest_length_.size()); }
    bool is_fem() const override { return false; }

    /// Removes the springs whose entry in broken (one per spring) is nonzero, keeping the
    /// others' order; bumps topology_version and matrix_version if any went. A failed
    /// allocation changes nothing. Returns how many went.
    int32_t remove_springs(const vec<uint8_t>& broken);

    /// The strain beyond which a spring breaks (sh_spring_params.break_strain; 0 = never).
    double break_strain() const { return break_strain_; }

    /// Per spring: 1 if it is stretched beyond break_strain at positions xs, else 0.
    vec<uint8_t> overstretched(const double* xs) const;

    /// The springs (2 node indices each) and their rest lengths (m).
    const vec<int32_t>& springs() const { return springs_; }
    const vec<double>& rest_lengths() const { return rest_length_; }

    /// True if the nodes a and b descend from (through node_parent) were joined by a spring
    /// when the body was made.
    bool were_joined(int32_t a, int32_t b) const;

    /// Adopts a new spring list with rest lengths, nodes appended as copies (origins with
    /// a == b) and every node's mass (the old nodes' and the copies'); bumps topology_version
    /// and matrix_version. A failed allocation changes nothing.
    void retopologize(const vec<NodeOrigin>& copies, vec<int32_t> springs, vec<double> rest_lengths, const vec<double>& masses);

private:
    int32_t root_of(int32_t node) const;
    /// Calls visit(s, a, b, d, l) for every spring s at positions xs: its end nodes a and b,
    /// d = x_b - x_a and l = |d|.
    template <class Visit>
    void each_spring(const double* xs, Visit&& visit) const;

    vec<int32_t> springs_;      ///< 2 per spring
    vec<double> rest_length_;   ///< l0 per spring (m)
    double break_strain_ = 0.0; ///< see break_strain
    vec<std::pair<int32_t, int32_t>> original_;  ///< the springs at creation, (lo, hi), sorted
    SpringLaw law_;
    mutable vec<double> row_bound_;  ///< stable_step scratch: Gershgorin row sums per node
};

}  // namespace sh
