// BodyContacts: one body's contact candidates for a step (against tools, obstacles and other
// bodies) and the contact forces they exert at any state the integrators try. Implemented in
// parts: body_contacts.cpp (the potential: forces, energy, stable step), contact_detection.cpp
// (broad phase), contact_tangent.cpp, contact_friction.cpp and contact_reactions.cpp; the
// per-term geometry and law are shape_contact's, shared with the haptic buffer.
#pragma once

#include "collision/aabb_tree.hpp"
#include "contact/ball_mix.hpp"
#include "contact/collider.hpp"
#include "contact/shape_contact.hpp"
#include "model/body.hpp"
#include "model/external_field.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

/// A contact that may act during the step: found by the broad phase, its depth and force are
/// evaluated afresh at each state.
struct ContactCandidate {
    enum Kind : uint8_t {
        kNodeShape,  ///< own node inside a collider (its depth's term)
        kFaceShape,  ///< a collider on own surface triangle `face` (its excess term)
        kNodeFace,   ///< own surface node inside another body, behind its triangle `face`
        kFaceNode,   ///< another body's node behind own triangle `face`
        kEdgeShape   ///< a collider on own surface edge (face[0], face[1]) (its excess term,
                     ///< subtracted)
    };
    Kind kind;
    int32_t node;     ///< kNodeShape, kNodeFace: own node; kFaceNode: the other body's node
    int32_t face[3];  ///< kFaceShape, kFaceNode: own nodes; kEdgeShape: own nodes in face[0],
                      ///< face[1]; kNodeFace: the other body's nodes
    Collider* collider;                ///< shape kinds
    const Body* other;                 ///< body-pair kinds
    const sh_contact_params* params;   ///< the contact law
    /// Implicit bodies: the candidate's normal force at the start of the step (N, 0 if it did
    /// not touch then), which its friction uses throughout the step (see finish_detection).
    double friction_normal = 0.0;
    /// Implicit bodies: its depth at the start of the step (m, 0 if it did not touch then),
    /// from which the step's law takes the depth rate (hunt_crossley_step_law).
    double start_depth = 0.0;
    /// kFaceShape, kEdgeShape: the share of its excess it carries (excess_weight of its rest
    /// size).
    double excess_weight = 1.0;
};

/// The buffers contact evaluation writes and drops again within one call or one explicit
/// (sub)step. One serves every body of a world, since the world evaluates its bodies' contacts
/// one after another: the world owns it (in its step scratch) and lends it to each
/// BodyContacts it builds, so that warmed-up steps allocate nothing here.
struct ContactScratch {
    /// Time spent evaluating contact forces and tangents since the last take (s).
    double evaluation_seconds = 0.0;
    /// Per node (of the largest body so far): a collider's net push on it (N), zero between
    /// evaluations (see BodyContacts::add_node_push).
    vec<double> node_push;
    /// The nodes with a push in node_push.
    vec<int32_t> pushed_nodes;
    /// Explicit bodies: the friction contacts of the (sub)step's first add_forces, applied by
    /// end_explicit_step of the same body.
    vec<FrictionRecord> friction_records;
    /// The next add_forces records its friction contacts (set by begin_explicit_step).
    bool recording = false;
    /// keep_deepest's sort keys (a candidate's depth).
    vec<double> keys;
    /// The balls' mix of the collider being evaluated, for colliders of several balls.
    BallMix balls;

    /// Returns evaluation_seconds and restarts it from 0.
    double take_evaluation_seconds() {
        const double s = evaluation_seconds;
        evaluation_seconds = 0.0;
        return s;
    }
};

/// The contact state of one body: surface, broad phase and candidates.
class BodyContacts final : public ExternalField {
public:
    /// Prepares the body's surface (FEM: its boundary triangles; springs: every node with
    /// mass). implicit: the body's solver minimises an implicit step's potential (contact
    /// takes the step's law over its depth rate and lagged friction), else it steps explicitly
    /// (the law at rest, friction as impulses per node after each step). scratch: the world's
    /// evaluation buffers, which must outlive this (grown here for the body's nodes).
    /// Allocates.
    BodyContacts(const Body& body, bool implicit, ContactScratch& scratch);

    /// Drops the last step's candidates.
    void clear();

    /// Refits the surface hierarchy at the body's current positions, every primitive grown by
    /// margin (m): how far a node may move before the next detection.
    void refit(double margin);

    /// Adds the candidates against collider: every surface node (and, for shapes other than
    /// planes, the excess terms of every surface triangle and its edges) whose box
    /// overlaps the collider's bounds grown by reach (m): the terms of the contact potential
    /// of shape_contact.hpp. Keeps at most its capacity, the deepest first; returns true if
    /// it dropped any.
    bool detect(Collider& collider, double reach);

    /// Adds to both a and b the candidates of a's surface nodes inside b's tets, each behind b's
    /// nearest surface triangle, and of those outside b within the two bodies' refit margins of
    /// a triangle of b they are in front of (they may reach it in the step). Both must be FEM
    /// bodies.
    static bool detect_pair(BodyContacts& a, BodyContacts& b, const sh_contact_params& params);


    /// Adds the reactions at the body's current state to each touched collider's state and
    /// returns how many contacts act (a body-pair contact counts on its node's side only).
    int32_t accumulate_reactions();

    /// Number of candidates.
    int32_t candidate_count() const { return static_cast<int32_t>(candidates_.size()); }

    /// Sets marks[node] = 1 for every node of the last detection's candidates other than those
    /// against collider `except` (obstacles, other tools, other bodies): the nodes whose
    /// contacts the haptic buffer of `except` does not model.
    void mark_nodes_of_other_contacts(const Collider* except, uint8_t* marks) const;

    /// Anticipated extra depth (m) used by stable_step for contacts that deepen in the step.
    double anticipated_depth = 0.0;

    /// Ends a detection pass (after every detect and detect_pair) for a step of h (s; 0 for
    /// a static solve): an implicit body's candidates record their depth at the body's
    /// current state, the step's start (with the colliders where the step starts), and for
    /// their friction the normal force and geometry there (lagged, see lagged_friction).
    /// Returns this if there are candidates, else null: the field to attach to the body.
    BodyContacts* finish_detection(double h);

    void add_forces(const double* x, const double* v, double* f) const override;
    void add_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                     const int32_t* free_index, SparseSystem& system) const override;
    /// Each body-pair contact counts half here and half in the other body's contacts.
    double energy(const double* x) const override;
    /// Implicit steps: the friction's dissipation potential at velocities v (friction_potential
    /// of each candidate's lagged friction).
    double dissipation(const double* v) const override;
    bool does_work() const override;
    /// The most nodes whose pairs one collider's links ask for: they form a dense block of
    /// the factorisation, whose cost grows with their cube (a static solve's candidates,
    /// taken within 5 % of the body's size, reach 99 nodes under a 1.2 cm capsule on a block
    /// of 3.3 mm cells; a palpation step's, 14-24 on liver2).
    static constexpr size_t kMaxLinkedNodes = 128;
    /// The node pairs a collider made of several balls couples through its smooth maximum
    /// (BallMix::tangent): every pair of the nodes of its candidate edges and faces, for
    /// colliders whose candidates have at most kMaxLinkedNodes nodes.
    void add_tangent_links(vec<int32_t>& pairs) const override;
    /// The blocks between this body's node and the other body's face of each kNodeFace
    /// candidate against other.
    void add_coupling_pattern(const Body& other, const int32_t* own_index, const int32_t* other_index,
                              vec<int32_t>& pairs) const override;
    void add_coupling_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                              const int32_t* own_index, const Body& other, const int32_t* other_index,
                              SparseSystem& system) const override;
    double stable_step(const double* x, const double* v, const double* mass) const override;
    void begin_explicit_step() const override;
    void end_explicit_step(double h, bool move_positions, double* x, double* v) const override;

private:
    struct Group {
        int32_t begin, end;  ///< candidates [begin, end): node kinds first, then faces
    };
    /// True if the body is stepped implicitly (the step's law, lagged friction).
    bool implicit_step() const { return implicit_; }
    /// Candidate c's law over the step (hunt_crossley_step_law from its start depth); the law
    /// at rest for explicit bodies and static solves (step_ and start_depth are 0 there).
    StepLaw step_law(const ContactCandidate& c) const;
    /// Candidate c at (x, v) (v null: at rest): true if it touches, with out filled: the
    /// normal law, and for explicit bodies with v their friction.
    bool touching(const ContactCandidate& c, const double* x, const double* v, ContactPoint& out) const;
    /// Implicit bodies: the friction of a candidate that touched at the step's start, at its
    /// start geometry (depth 0, no normal force), at velocities v; false if it has none.
    bool lagged_friction(const ContactCandidate& c, const double* v, ContactPoint& out) const;
    /// Implicit bodies with v: calls emit(candidate, point) for each lagged_friction point.
    template <class Emit>
    void evaluate_friction(const double* v, Emit&& emit) const;
    /// Implicit bodies, from add_forces: records candidate c's friction at a Newton iterate
    /// (point null: not touching there) for friction_chord.
    void record_friction_iterate(const ContactCandidate& c, const ContactPoint* point) const;
    /// Implicit bodies, from add_tangent: the slope along the slip that candidate c's friction
    /// tangent takes at point p instead of the exact one (-1: the exact one), and records the
    /// tangent it then has. See the comment in contact_friction.cpp.
    double friction_chord(const ContactCandidate& c, const ContactPoint& p) const;
    /// Calls emit(candidate, point) for every candidate at (x, v) (v null: at rest, without
    /// damping or friction), point null for one not in contact.
    template <class Emit>
    void evaluate_candidates(const double* x, const double* v, Emit&& emit) const;
    /// evaluate_candidates, calling after_group(group) when a group's candidates are done (its
    /// collider's BallMix still in scratch_.balls).
    template <class Emit, class AfterGroup>
    void evaluate_candidates(const double* x, const double* v, Emit&& emit, AfterGroup&& after_group) const;
    /// evaluate_candidates for the candidates in contact only, with a reference to the point.
    template <class Emit>
    void evaluate(const double* x, const double* v, Emit&& emit) const;
    bool keep_deepest(Group& group, int32_t capacity);
    /// If group's collider is made of several balls: sums its excess terms at x into
    /// scratch_.balls for the group's evaluation (BallMix).
    void mix_balls(const Group& group, const double* x) const;
    /// Group's collider if it is made of several balls (a BallMix), else null.
    const Collider* ball_mix_collider(const Group& group) const;
    /// Calls visit(candidate, count) for each of group's excess candidates (edges 2, faces 3).
    template <class Visit>
    void for_each_excess_candidate(const Group& group, Visit&& visit) const;
    /// The tangent of group's collider's BallMix across its terms (if it is made of several
    /// balls; the mix at x already in scratch_.balls) into system, times stiffness_scale.
    void add_ball_mix_tangent(const Group& group, const double* x, double stiffness_scale, const int32_t* free_index,
                              SparseSystem& system) const;
    /// Adds p's node forces (a collider's term) to the nodes' net push, listing each node once.
    void add_node_push(const ContactPoint& p) const;
    /// Calls emit(node, push) for each node with a net push since the last call, and clears it.
    template <class Emit>
    void drain_node_pushes(Emit&& emit) const;
    /// evaluate, calling on_point(candidate, point) for each contact and, with pushes, after
    /// each collider's candidates on_node(collider, node, push) for each surface node its terms
    /// push: their net force on it (N).
    template <class OnPoint, class OnNode>
    void evaluate_with_node_pushes(const double* x, const double* v, bool pushes, OnPoint&& on_point,
                                   OnNode&& on_node) const;
    /// Calls visit(candidate) for each kNodeFace candidate against other whose node has
    /// own_index >= 0.
    template <class Visit>
    void for_each_pair_candidate(const Body& other, const int32_t* own_index, Visit&& visit) const;
    void ensure_tet_tree();

    const Body& body_;
    const bool implicit_;  ///< see the constructor
    vec<int32_t> surface_nodes_;   ///< nodes on the surface
    vec<double> node_area_;        ///< per node: a third of its surface triangles' rest area (m^2)
    vec<int32_t> edge_neighbor_;   ///< per surface triangle and edge k (nodes k, k + 1): the
                                   ///< triangle across it, -1 if not exactly one
    vec<double> edge_length_;      ///< per surface triangle and edge k: its rest length (m), for
                                   ///< excess_weight
    vec<Aabb> boxes_;              ///< per surface primitive (triangle, or node for springs)
    AabbTree tree_;
    double margin_ = 0.0;          ///< the last refit's margin (m)
    double step_ = 0.0;            ///< implicit bodies: the step's length (s); else 0 (at rest)
    vec<Aabb> tet_boxes_;          ///< per tet, for other bodies' nodes (built on first use)
    AabbTree tet_tree_;
    vec<uint32_t> stamp_;          ///< per node: last detection pass that took it
    uint32_t pass_ = 0;
    vec<ContactCandidate> candidates_;
    vec<Group> groups_;
    ContactScratch& scratch_;  ///< the world's scratch, shared by its bodies' evaluations
    /// Implicit bodies with friction: per candidate, its geometry at the step's start and its
    /// friction over the step's Newton iterates (see friction_chord). State of the candidates
    /// for the whole (sub)step, not scratch: an island's Newton solve interleaves its bodies'
    /// evaluations, so each body keeps its own; `mutable` since evaluations update it. Residual and response
    /// are per unit step: the row of the Newton residual over h (N) and the rest of the
    /// system's stiffness along the last update over h (N s/m).
    struct FrictionIterate {
        struct Point {
            double vrel[3];      ///< relative velocity (m/s)
            double force[3];     ///< friction (N)
            double residual[3];  ///< the contact's residual row: its linear model's friction error
            double response;     ///< the rest of the system's stiffness along the last update
            bool has_residual, has_response;
        };
        double lag_normal[3], lag_point[3];  ///< at the step's start
        double lag_face[3];    ///< the face's barycentric weights then (face kinds)
        Point cur, prev;       ///< the latest iterate and the one before
        double start_vrel[3];  ///< the step's first iterate (a retried step returns to it)
        double tangent[9];     ///< -dF/dvrel the last add_tangent gave
        double last_slip[3];   ///< slip at the last add_tangent
        int tangents;          ///< add_tangent calls at this contact in the step
        bool has_start, has_cur, has_prev, has_tangent, reversed;
    };
    mutable vec<FrictionIterate> iterates_;
};

}  // namespace sh
