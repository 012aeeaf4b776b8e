// SpringBody: a mass-spring network with one spring law for all its springs.
#pragma once

#include "material/spring_laws.hpp"
#include "model/body.hpp"

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
    double stable_step(const double* x) const override;
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

private:
    vec<int32_t> springs_;      ///< 2 per spring
    vec<double> rest_length_;   ///< l0 per spring (m)
    SpringLaw law_;
    mutable vec<double> row_bound_;  ///< stable_step scratch: Gershgorin row sums per node
};

}  // namespace sh
