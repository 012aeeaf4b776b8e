// Body: a deformable object's node state, boundary conditions and loads, and the interface
// the integrators use (internal forces, energy, critical step).
#pragma once

#include "core/memory.hpp"
#include "model/elastic_energy_memo.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

class ExternalField;
class SparseSystem;

/// Where a node appended by a topology change comes from: the point (1 - t) a + t b of the
/// edge from node a to node b, in the rest and in the current shape. A copy of node a is
/// {a, a, 0}.
struct NodeOrigin {
    int32_t a = 0, b = 0;  ///< the edge's end nodes (equal for a copy)
    double t = 0.0;        ///< where on the edge, in [0, 1]
};

class Body;

/// The nodes a topology change appends to a body, built aside (Body::grow_nodes, which also
/// makes room for them in the body's arrays) so that a failed allocation leaves the body as
/// it was; Body::adopt_nodes appends them without allocating.
struct GrownNodes {
    size_t first = 0;  ///< the first appended node's index: the body's node count before
    vec<double> x, v, rest, target;  ///< 3 per appended node
    vec<double> node_damping;        ///< 1 per appended node, if the body has node damping
    vec<uint8_t> kinematic;
    vec<int32_t> parent;

    /// Node count once appended.
    size_t node_count() const { return first + kinematic.size(); }

    /// The rest position (3 values) of node, the body's own or an appended one.
    const double* rest_of(const Body& body, int32_t node) const;

    /// values (3 per node of the body) followed by appended's (3 per appended node).
    static vec<double> joined(const vec<double>& values, const vec<double>& appended);
};

/// A deformable body. Orphan nodes have zero mass and are never integrated.
class Body {
public:
    /// A body at rest at rest_positions (3 per node), with Rayleigh mass damping alpha (1/s).
    Body(vec<double> rest_positions, double damping_mass);
    virtual ~Body() = default;
    Body(const Body&) = delete;
    Body& operator=(const Body&) = delete;

    /// Adds internal forces at (x, v) into f (3 per node): elastic forces, plus the body's
    /// internal damping (stiffness-proportional or spring dashpots) when v is not null.
    virtual void add_internal_forces(const double* x, const double* v, double* f) const = 0;

    /// True if add_internal_forces with velocities adds damping (stiffness-proportional
    /// damping or spring dashpots).
    virtual bool has_internal_damping() const = 0;

    /// Elastic energy at positions x (J).
    virtual double elastic_energy(const double* x) const = 0;

    /// An elastic energy and the magnitude its round-off is relative to.
    struct ElasticEnergy {
        double value = 0.0;  ///< J
        /// J: eps times it is the order of value's round-off. |value|, plus the largest
        /// coordinate times the sum of the elements' (springs') force norms: rounding the
        /// positions to eps |x| moves each element's energy by its forces times that, which
        /// near rest is far above eps |value|.
        double scale = 0.0;
    };

    /// Adds the elastic forces at x into f (add_internal_forces without damping) and returns
    /// the elastic energy at x, as the two calls would, with its round-off scale; from one
    /// pass over the elements.
    virtual ElasticEnergy add_elastic_forces_and_energy(const double* x, double* f) const = 0;

    /// elastic_energy(x), recalled without a pass over the elements where x is, bit for bit,
    /// the positions remember_elastic_energy was last given, and no element or material has
    /// changed since.
    double elastic_energy_recalled(const double* x) const;

    /// Keeps value as the elastic energy at x (3 per node): positions an evaluation just took
    /// it at, which the next caller of elastic_energy_recalled may ask about. Allocates the
    /// first time and when the body grew (std::bad_alloc, keeping nothing).
    void remember_elastic_energy(const double* x, double value);

    /// Largest stable step of an undamped leapfrog step, 2 / omega_max, at state x (s).
    virtual double stable_step(const double* x) const = 0;

    /// Adds stiffness_scale * K(x) + damping_scale * D(x) into system: K = -df/dx the tangent
    /// stiffness with each element block projected to positive semi-definite, D = -df/dv the
    /// internal damping (stiffness-proportional or dashpots).
    virtual void add_tangent(const double* x, double stiffness_scale, double damping_scale,
                             SparseSystem& system) const = 0;

    /// An estimate of add_tangent's work, in the floating-point operations of a sparse solve
    /// (FactorWork): what the implicit step weighs against factorisations and solves. A count,
    /// not a clock, so that identical runs choose alike.
    virtual double tangent_work() const = 0;

    /// Element connectivity: element_count() x nodes_per_element() node indices.
    virtual const int32_t* element_nodes() const = 0;

    /// The order add_tangent adds its elements in, a permutation of [0, element_count()), or
    /// nullptr for 0, 1, ...: the sparse system lays its scatter map out in it (see
    /// SparseSystem::build_pattern). Valid until the elements change.
    virtual const int32_t* tangent_order() const { return nullptr; }

    /// 4 for tets, 2 for springs.
    virtual int nodes_per_element() const = 0;

    /// Tets or springs.
    virtual int32_t element_count() const = 0;

    /// True for FEM bodies.
    virtual bool is_fem() const = 0;

    /// Most elements with det F <= 0 at one internal-force evaluation since the last
    /// clear_inverted_elements (0 for springs).
    virtual int32_t inverted_elements() const { return 0; }

    /// Starts a new count for inverted_elements (at the start of each step).
    virtual void clear_inverted_elements() {}

    /// True if node i is integrated (has mass, not fixed or prescribed).
    bool is_free(int32_t i) const { return inverse_mass[static_cast<size_t>(i)] > 0.0; }

    /// Recomputes inverse_mass from mass and kinematic.
    void update_inverse_mass();

    /// Recomputes node i's inverse_mass from its mass and kinematic flag (a local change
    /// touches a few nodes).
    void update_inverse_mass_of(size_t i) noexcept {
        inverse_mass[i] = (mass[i] > 0.0 && !kinematic[i]) ? 1.0 / mass[i] : 0.0;
    }

    /// Moves every node to positions (3 per node); fixed and prescribed nodes stay held where
    /// they are put.
    void set_positions(const double* positions);

    /// Sets the velocities (3 per node) of the nodes that are integrated; the others keep 0.
    void set_velocities(const double* velocities);

    /// Holds nodes[0..count) where they are, at rest.
    void fix_nodes(const int32_t* nodes, int32_t count);

    /// Lets nodes[0..count) move again.
    void release_nodes(const int32_t* nodes, int32_t count);

    /// Moves nodes[0..count) to positions (3 per node) over the next step and holds them there.
    void prescribe_positions(const int32_t* nodes, const double* positions, int32_t count);

    /// The applied load on global DOF j = 3 node + c: external force plus the node's weight
    /// under gravity g (N).
    double applied_load(size_t j, const double g[3]) const { return external_force[j] + mass[j / 3] * g[j % 3]; }

    /// Viscous mass damping of node (1/s): Rayleigh alpha plus its own node_damping.
    double mass_damping(size_t node) const {
        return damping_mass + (node_damping.empty() ? 0.0 : node_damping[node]);
    }

    /// Replaces node_damping by coefficients[node_count()] (1/s), or clears it for null.
    void set_node_damping(const double* coefficients);

    int32_t node_count() const { return static_cast<int32_t>(mass.size()); }

    /// The nodes of origins[0..count), each interpolated along its edge (positions,
    /// velocities, targets, damping): a node is held (fixed or prescribed) if both ends are,
    /// carries no external force, and its parent is the nearer end (or the one copied). Makes
    /// room for them in the body's node arrays (reserve_growing: a body grown node by node
    /// copies its arrays amortised O(1) times per node), changing nothing else. Throws
    /// std::bad_alloc.
    GrownNodes grow_nodes(const NodeOrigin* origins, size_t count);

    /// Appends grown's nodes (allocation-free after grow_nodes), with zero mass and inverse
    /// mass and no external force: the caller gives them their masses from the elements, then
    /// calls update_inverse_mass.
    void adopt_nodes(const GrownNodes& grown) noexcept;

    /// The node each node was made from by a cut (-1 for nodes the body was created with).
    int32_t parent_of(int32_t node) const {
        return static_cast<size_t>(node) < node_parent.size() ? node_parent[static_cast<size_t>(node)] : -1;
    }

    double damping_mass = 0.0;   ///< Rayleigh alpha: viscous damping of every node (1/s)
    vec<double> x, v;            ///< 3 per node (m, m/s)
    vec<double> rest;            ///< the rest shape, 3 per node (m)
    vec<double> mass;            ///< lumped mass per node (kg); 0 for orphans
    vec<double> inverse_mass;    ///< 1/m for free nodes, 0 for fixed, prescribed and orphans
    vec<uint8_t> kinematic;      ///< 1 if the node's position is fixed or prescribed
    vec<double> target;          ///< 3 per node, where kinematic nodes go in the next step
    vec<double> external_force;  ///< 3 per node (N), held
    vec<double> node_damping;    ///< per-node viscous coefficient (1/s); empty if unused
    vec<int32_t> surface_triangles;  ///< 3 per boundary triangle, outward; empty for springs
    vec<int32_t> node_parent;    ///< per node: the node it was made from, -1 for the body's own
                                 ///< nodes; empty until the first topology change
    /// Bumped by every topology change (elements, springs or nodes added or removed): whatever
    /// holds per-node or per-element data of the body rebuilds it when this moves.
    uint64_t topology_version = 0;
    /// Bumped whenever M, D or K change other than through x (a material or node-damping
    /// change): a factorisation kept by the implicit integrator is valid only for the version it
    /// was built at.
    uint64_t matrix_version = 0;
    /// Forces from outside the body (contact), attached by the world during a step; null when
    /// nothing touches the body.
    const ExternalField* field = nullptr;

private:
    ElasticEnergyMemo energy_memo_;  // the last remembered elastic energy
};

}  // namespace sh
