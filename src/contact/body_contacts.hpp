// BodyContacts: one body's contact candidates for a step (against tools, obstacles and other
// bodies) and the contact forces they exert at any state the integrators try.
#pragma once

#include "collision/aabb_tree.hpp"
#include "contact/collider.hpp"
#include "model/body.hpp"
#include "model/external_field.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

/// A contact that may act during the step: found by the broad phase, its depth and force are
/// evaluated afresh at each state.
struct ContactCandidate {
    enum Kind : uint8_t {
        kNodeShape,  ///< own node inside a collider
        kFaceShape,  ///< a collider through own surface triangle (smaller than it)
        kNodeFace,   ///< own surface node inside another body, behind its triangle `face`
        kFaceNode    ///< another body's node behind own triangle `face`
    };
    Kind kind;
    int32_t node;     ///< kNodeShape, kNodeFace: own node; kFaceNode: the other body's node
    int32_t face[3];  ///< kFaceShape, kFaceNode: own nodes; kNodeFace: the other body's nodes
    Collider* collider;                ///< shape kinds
    const Body* other;                 ///< body-pair kinds
    const sh_contact_params* params;   ///< the contact law
};

/// One acting contact, as evaluate() reports it.
struct ContactPoint {
    double depth;            ///< penetration (m), > 0
    double normal[3];        ///< unit direction of the push on the node side (node or face)
    double point[3];         ///< touching point (world)
    int32_t nodes[3];        ///< own nodes the contact acts on
    int count;               ///< 1 or 3
    double weights[3];       ///< own nodes' shares of the node side's motion and friction (sign
                             ///< included: kFaceNode's own face is the far side)
    double gradient[3][3];   ///< per own node: -d depth / d x, its weight times the normal (the
                             ///< normal force on it is the normal force times this)
    double node_force[3][3]; ///< per own node: the force it feels (N)
    double stiffness;        ///< dFn/dx (N/m)
    double damping;          ///< dFn/dx' (N s/m)
    double friction;         ///< viscous coefficient of the friction (N s/m)
};

/// The contact state of one body: surface, broad phase and candidates.
class BodyContacts final : public ExternalField {
public:
    /// Prepares the body's surface (FEM: its boundary triangles; springs: every node with
    /// mass). Allocates.
    explicit BodyContacts(const Body& body);

    /// Drops the last step's candidates.
    void clear();

    /// Refits the surface hierarchy at the body's current positions, every primitive grown by
    /// margin (m): how far a node may move before the next detection.
    void refit(double margin);

    /// Adds the candidates against collider: every surface node (and, for shapes other than
    /// planes, every surface triangle) whose box overlaps the collider's bounds grown by reach
    /// (m). Keeps at most its capacity, the deepest first; returns true if it dropped any.
    bool detect(Collider& collider, double reach);

    /// Adds to both a and b the candidates of a's surface nodes inside b's tets, each behind b's
    /// nearest surface triangle. Both must be FEM bodies.
    static bool detect_pair(BodyContacts& a, BodyContacts& b, const sh_contact_params& params);


    /// Adds the reactions at the body's current state to each touched collider's state and
    /// returns how many contacts act (a body-pair contact counts on its node's side only).
    int32_t accumulate_reactions();

    /// Time spent evaluating contact forces and tangents since the last call (s).
    double take_evaluation_seconds() {
        const double s = evaluation_seconds_;
        evaluation_seconds_ = 0.0;
        return s;
    }

    /// Number of candidates.
    int32_t candidate_count() const { return static_cast<int32_t>(candidates_.size()); }

    /// Anticipated extra depth (m) used by stable_step for contacts that deepen in the step.
    double anticipated_depth = 0.0;

    /// For explicit bodies: 1 / the coming (sub)step (1/s). Friction's viscous coefficient is
    /// capped at the touched mass times this, so that it can stop a sliding node within a
    /// step but never reverse it (0: no cap, for implicit bodies).
    double friction_rate_limit = 0.0;

    void add_forces(const double* x, const double* v, double* f) const override;
    void add_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                     const int32_t* free_index, SparseSystem& system) const override;
    double energy(const double* x) const override;
    double stable_step(const double* x, const double* v, const double* mass) const override;

private:
    struct Group {
        int32_t begin, end;  ///< candidates [begin, end): node kinds first, then faces
    };
    bool contact(const ContactCandidate& c, const double* x, const double* v, ContactPoint& out) const;
    /// Calls emit(candidate, point) for every candidate at (x, v) (v null: at rest, without
    /// damping or friction), point null for one not in contact. Group by group, node contacts
    /// before the faces they share depth with.
    template <class Emit>
    void evaluate_candidates(const double* x, const double* v, Emit&& emit) const;
    /// evaluate_candidates for the candidates in contact only, with a reference to the point.
    template <class Emit>
    void evaluate(const double* x, const double* v, Emit&& emit) const;
    bool keep_deepest(Group& group, int32_t capacity);
    void ensure_tet_tree();

    const Body& body_;
    vec<int32_t> surface_nodes_;   ///< nodes on the surface
    vec<double> node_area_;        ///< per node: a third of its surface triangles' rest area (m^2)
    vec<Aabb> boxes_;              ///< per surface primitive (triangle, or node for springs)
    AabbTree tree_;
    vec<Aabb> tet_boxes_;          ///< per tet, for other bodies' nodes (built on first use)
    AabbTree tet_tree_;
    vec<uint32_t> stamp_;          ///< per node: last detection pass that took it
    uint32_t pass_ = 0;
    vec<ContactCandidate> candidates_;
    vec<Group> groups_;
    mutable vec<double> node_depth_; ///< per node: its depth in the current group's collider
    vec<double> keys_;               ///< scratch for keep_deepest
    mutable double evaluation_seconds_ = 0.0;
};

}  // namespace sh
