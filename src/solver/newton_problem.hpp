// NewtonProblem: what one Newton solve (an implicit step, a static solve) solves for, seen the
// same way whether it is one body alone or several bodies that act on each other (in contact):
// the bodies and the offset of each one's DOFs in the problem's matrix, their potential and
// applied load, and the assembly of their tangent into that matrix. A body alone is solved with
// its own matrix (NewtonBodyState); bodies solved together with a joint one that holds their own
// matrices, each at its offset, and the blocks their fields couple between them.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"
#include "solver/joint_pattern.hpp"
#include "solver/newton_body_state.hpp"
#include "solver/newton_matrix.hpp"
#include "solver/stepped_body.hpp"

#include <softhap/softhap.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace sh {

/// Round-off (J) of a sum of energy terms whose magnitudes add up to scale: what the Newton
/// line searches allow a potential to rise by and still count as not raised.
inline double sum_roundoff(double scale) { return 64.0 * std::numeric_limits<double>::epsilon() * scale; }

/// Moves a full Newton update towards the minimum of the potential along it, when the update
/// ends far from it: still falling steeply (its slope there, slope_here(), below a quarter of
/// the start's slope0 < 0), or rising steeply (above a quarter of -slope0: past the minimum).
/// Either comes from a tangent that is wrong along the update: too stiff where it leaves out a
/// negative part (an edge's excess, a rounded tool's sideways -F / r), too soft where it
/// leaves out a positive one (how an excess term's maximiser moves with the nodes). Newton
/// then creeps by the slope ratio per iteration (0.5 over a whole step of a capsule drawn
/// through its slit), or swings across the minimum, with the line search accepting each swing
/// for its small fall. Each try goes where the slope, taken as linear through the last two
/// points (a secant), vanishes: past the minimum one try, back between the start and the full
/// update; else further out, at most 8 times further than the last point and 64 times the
/// update in all. move_to(s) goes to s times the update and returns the potential there
/// (non-finite: unusable); value is the potential at the full update. A try is kept if the
/// potential fell by more than roundoff, or stayed within it with a smaller slope (closer to
/// the minimum, where the potential is too flat to tell); the update ends on the last one kept.
/// Each try costs an evaluation; Newton's own updates near convergence end flat and take none.
/// The static solve and the implicit step share it.
template <class SlopeHere, class MoveTo>
void move_update_towards_line_minimum(double slope0, double value, double roundoff, SlopeHere&& slope_here,
                                      MoveTo&& move_to) {
    constexpr double kSteepRatio = 0.25, kFurthest = 64.0, kFurthestStride = 8.0;
    constexpr int kMaxTries = 6;
    double scale = 1.0, slope = slope_here(), last_scale = 0.0, last_slope = slope0;
    const auto kept = [&](double there, double slope_there) {
        return std::isfinite(there) &&
               (there < value - roundoff || (there <= value + roundoff && std::fabs(slope_there) < std::fabs(slope)));
    };
    if (slope > -kSteepRatio * slope0) {  // well past the minimum: back to the secant's zero
        const double back = slope0 / (slope0 - slope);
        const double there = move_to(back), slope_there = slope_here();
        if (!kept(there, slope_there)) move_to(1.0);
        return;
    }
    for (int k = 0; k < kMaxTries && slope < kSteepRatio * slope0 && scale < kFurthest; ++k) {
        // Where the secant's slope vanishes, if the slope grew (the potential curves upward
        // along the update); else twice as far.
        const double secant = scale - slope * (scale - last_scale) / (slope - last_slope);
        const bool curves_up = slope > last_slope && std::isfinite(secant);
        const double next = std::min(curves_up ? std::min(secant, kFurthestStride * scale) : 2.0 * scale, kFurthest);
        const double there = move_to(next), slope_there = slope_here();
        if (!kept(there, slope_there)) {
            move_to(scale);
            return;
        }
        last_scale = scale, last_slope = slope;
        scale = next, slope = slope_there, value = there;
    }
}

/// The bodies a Newton solve solves for: one alone (a view of it, made per solve) or several
/// solved together (made empty, then prepared; the joint pattern is kept across solves, and
/// grown, while it covers what the bodies need).
class NewtonProblem {
public:
    /// A problem over bodies solved together, empty until prepare().
    NewtonProblem() = default;
    /// The problem of stepped's body alone, solved with its own matrix (its NewtonBodyState,
    /// prepared with a solver).
    explicit NewtonProblem(SteppedBody& stepped) : alone_(&stepped) {}
    NewtonProblem(const NewtonProblem&) = delete;             ///< not copyable: owns a solver
    NewtonProblem& operator=(const NewtonProblem&) = delete;  ///< not copyable: owns a solver

    /// Takes bodies[0..count) (each with its NewtonBodyState) as the bodies solved together, in
    /// that order: prepares each body's own matrix (without a solver of its own) and rebuilds
    /// the joint pattern, solver (from settings) and symbolic analysis if the bodies, their free
    /// nodes or their sizes changed, or if their fields now couple nodes the pattern has no
    /// block for. Not for a problem made for a body alone.
    void prepare(SteppedBody* const* bodies, int32_t count, const sh_implicit_settings& settings);

    /// The matrix the solve assembles and factorises: the body's own alone, the joint one else.
    NewtonMatrix& matrix() { return alone_ ? alone_->newton->matrix : joint_; }

    /// Number of bodies solved for.
    int32_t body_count() const { return alone_ ? 1 : static_cast<int32_t>(members_.size()); }
    /// Body m (< body_count()).
    SteppedBody& body(int32_t m) const { return alone_ ? *alone_ : *members_[static_cast<size_t>(m)].stepped; }

    /// Calls visit(stepped, offset) for each body, offset its first DOF in matrix().
    template <class Visit>
    void each(Visit&& visit) const {
        if (alone_) {
            visit(*alone_, size_t{0});
            return;
        }
        for (const CoupledMember& member : members_) visit(*member.stepped, static_cast<size_t>(member.offset));
    }

    /// Assembles matrix(): assemble_body(stepped) fills each body's own matrix and returns its
    /// force round-off; bodies solved together then have their own matrices added into the
    /// joint one with their coupling blocks (stiffness_scale K + damping_scale D, at rest or
    /// not). Returns the round-off of the forces (together: the root of the sum of squares).
    template <class AssembleBody>
    double assemble(AssembleBody&& assemble_body, double stiffness_scale, double damping_scale, bool at_rest) {
        if (alone_) return assemble_body(*alone_);
        joint_.system.clear_values();
        double roundoff2 = 0.0;
        for (CoupledMember& m : members_) {
            const double roundoff = assemble_body(*m.stepped);
            roundoff2 += roundoff * roundoff;
            add_member_values(m);
        }
        add_coupling(stiffness_scale, damping_scale, at_rest);
        return std::sqrt(roundoff2);
    }

    /// The bodies' matrix version (together: the sum of theirs, which changes whenever one does).
    uint64_t matrix_version() const {
        if (alone_) return alone_->body->matrix_version;
        uint64_t version = 0;
        for (const CoupledMember& m : members_) version += m.body().matrix_version;
        return version;
    }

    /// |f_ext + m g| over the free DOFs (N).
    double applied_load_norm(const double g[3]) const;

    /// The bodies' potential energy at their positions (at_start: the step's start,
    /// workspace.x0): elastic energy, the fields' potential, minus load_factor times the work
    /// of f_ext + m g over the free DOFs (J). scale gets the terms' magnitudes.
    double potential_energy(const double g[3], double load_factor, bool at_start, double& scale) const;

    /// potential_energy at the current positions where the elastic and field energies there
    /// are already known (stored: their sum over the bodies). Only the loads' work is computed.
    double potential_energy_from(const double g[3], double load_factor, double stored) const;

private:
    /// Adds the values of m's own matrix into the joint one.
    void add_member_values(const CoupledMember& m);
    /// Adds the blocks the bodies' fields couple between them into the joint matrix.
    void add_coupling(double stiffness_scale, double damping_scale, bool at_rest);
    /// Builds the joint pattern from the members' patterns and links (taken as links_), the
    /// slot maps, the solver and its analysis; on failure nothing changes but the slot maps.
    void build_joint(vec<uint64_t>& links, const sh_implicit_settings& settings);

    SteppedBody* alone_ = nullptr;  ///< the body alone, or null: the members solved together
    NewtonMatrix joint_;            ///< together: the joint matrix
    vec<CoupledMember> members_;    ///< together: the bodies, in order
    vec<uint64_t> links_;   ///< coupled joint node pairs in the pattern: (i << 32) | j, i < j, sorted
    vec<uint64_t> needed_;  ///< the pairs the current contacts couple
    vec<int32_t> pairs_;    ///< scratch: node pairs as the fields report them
};

}  // namespace sh
