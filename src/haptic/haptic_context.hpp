// HapticContext: the Volumetric Buffer Model of one tool. The sim side (World::step) cuts the
// tets around the tool's contact out of the full model into a buffer and publishes it; the
// haptic side (sh_haptic_step) takes the newest buffer, steps it explicitly at the device rate
// in memory fixed at creation, and renders the tool's force through the ForceFilter. The two
// sides meet only in two triple buffers (buffers one way, device poses the other).
#pragma once

#include "contact/collider.hpp"
#include "contact/ball_mix.hpp"
#include "core/memory.hpp"
#include "haptic/buffer.hpp"
#include "haptic/force_filter.hpp"
#include "haptic/triple_buffer.hpp"
#include "world/step_hook.hpp"

#include <softhap/softhap.h>

#include <atomic>
#include <cstdint>

namespace sh {

class Body;
class FemBody;
struct FrictionRecord;
class World;

/// Validates def's fields (messages name them as def->field).
void validate_haptic_def(const sh_haptic_def& def);

/// One tool's haptic context; the world calls it around each full step.
class HapticContext final : public StepHook {
public:
    /// Doubles per buffer node in the contact tangent workspace: stiffness (9), damping (9)
    /// and the stiffness's mixed-bound part (1).
    static constexpr size_t kTangentStride = 19;

    /// Bytes of the arena a context made from (validated) def holds.
    static size_t memory_bytes(const sh_haptic_def& def);

    /// Validates def against world (a live sphere, capsule or box tool), allocates the arena
    /// and extracts the first buffer. Does not register with world.
    HapticContext(World& world, const sh_haptic_def& def);
    ~HapticContext() override;
    HapticContext(const HapticContext&) = delete;
    HapticContext& operator=(const HapticContext&) = delete;

    // --- sim side ---------------------------------------------------------------------------

    /// Moves the tool to the newest device pose and keeps the buffer body's start state.
    void before_step(World& world) override;

    /// Cuts a new buffer from the full model after a step of dt (s) and publishes it.
    void after_step(World& world, double dt) override;
    /// A cut of the buffer's body: drops what follows its old topology and cuts a new buffer
    /// at once, so that the device feels the cut before the next full step.
    void topology_changed(World& world, Id id) noexcept override;

    /// The world is gone: from now on the haptic step reports SH_HAPTIC_FAULT_NO_TOOL.
    void detach() override;

    /// The world it serves (null once detached).
    World* world() const { return world_; }

    // --- haptic side ------------------------------------------------------------------------

    /// One haptic step (see sh_haptic_step). Never allocates, locks or throws.
    sh_status step(const double position[3], const double orientation[4], double dt, sh_haptic_output& out) noexcept;

    /// The warning counters (SH_WARN_COUNT values).
    void read_warnings(uint64_t out[SH_WARN_COUNT]) const;

private:
    /// A device pose handed to the sim side.
    struct DevicePose {
        Pose pose;
        bool valid = false;
    };

    // sim side
    void extract(World& world, double period, Buffer& out);
    /// Where the tool acts on the body a buffer is cut from: tets rank by their centroid's
    /// distance to the segment from a to b, and those around the seed nodes come first.
    struct BufferCentre {
        double a[3] = {}, b[3] = {};
        const int32_t* seeds = nullptr;
        size_t seed_count = 0;
    };
    /// The body, point and seeds of tool's blade hold, if it holds nodes of a FEM body.
    bool find_held_centre(const World& world, Id& body, BufferCentre& centre);
    void select_tets(const FemBody& body, const BufferCentre& centre, Buffer& out);
    void fill_buffer(const World& world, const Collider& tool, const FemBody& body, Buffer& out);
    void number_nodes(const FemBody& body, Buffer& out);
    void fill_nodes(const FemBody& body, Buffer& out);
    void fill_blocks(const FemBody& body, Buffer& out);
    void fill_rotations(Buffer& out) const;
    void fill_triangles(const FemBody& body, Buffer& out);
    void fill_surface_features(const FemBody& body, Buffer& out);
    void ensure_adjacency(const FemBody& body, Id id);
    void fill_held(const World& world, const Collider& tool, Buffer& out);

    // haptic side
    void load_state(const Buffer& b, bool keep);
    void follow_boundary(const Buffer& b, double t, double* x, double* v) const;
    void hold_nodes(const Buffer& b, double* x, double* v);
    void add_held_reaction(const Buffer& b, const double* x, double force[3], double torque[3]);
    bool hold_broken(const Buffer& b) const { return b.held_serial != 0 && b.held_serial == broken_hold_ && b.body == broken_body_; }
    void adopt(const Buffer& b);
    bool step_buffer(const Buffer& b, double dt, double force[3], double torque[3], int32_t& substeps, bool& contact);
    void add_contact_forces(const Buffer& b, const double* x, const double* v, double* f, double force[3],
                            double torque[3], bool& contact);
    void record_node_friction(const Buffer& b, const double* x, const double* v);
    void apply_friction_impulses(const Buffer& b, double h, double* x, double* v, double force[3], double torque[3]);
    bool proxy_force(const Buffer& b, double force[3], double torque[3]) const;
    double substep_limit(const Buffer& b) const;
    void clear_contact();
    void add_contact_tangent(int32_t node, const double direction[3], double stiffness, double damping);
    /// Adds a mixed term's stiffness bound (N/m) to node's contact stiffness on every axis, and
    /// notes it apart: it steadies the node but is not felt (integrate()).
    void add_mixed_bound(int32_t node, double bound);
    void integrate(const Buffer& b, double h, double* x, double* v, double force[3], double torque[3]) const;
    /// The buffer's elastic forces at x (damped with v) into force_, its rotations kept.
    void add_elastic_forces(const Buffer& b, const double* x, const double* v);

    sh_haptic_def def_;
    World* world_;
    std::atomic<bool> detached_{false};
    Collider tool_;  ///< the haptic side's own copy of the tool (shape, law, pose)
    BallMix balls_;  ///< the tool's balls' mix, room reserved at creation (BallMix)

    // the arena and what is carved from it
    void* arena_ = nullptr;
    size_t arena_bytes_ = 0;
    Buffer buffers_[3];
    TripleIndex buffer_index_;  ///< sim writes, haptic reads
    DevicePose device_[3];
    TripleIndex device_index_;  ///< haptic writes, sim reads

    // haptic-side working state (arena)
    double* x_[2] = {};  ///< node positions, current and spare for the hand-over
    double* v_[2] = {};
    int32_t* id_[2] = {};  ///< body node of each working node
    int current_ = 0;
    int32_t node_count_ = 0;
    Id state_body_ = kNullId;
    double* force_ = nullptr;  ///< 3 per node
    double* contact_ = nullptr;  ///< 3 per node: the sub-step's contact force on it
    /// Per node, kTangentStride doubles: the sub-step's contact stiffness (3x3, N/m) and
    /// damping (3x3, N s/m) on it, lumped (integrate()), and the part of that stiffness that
    /// is a mixed term's isotropic bound (N/m, on every axis; add_mixed_bound).
    double* contact_tangent_ = nullptr;
    int32_t* contacted_ = nullptr;       ///< the nodes the sub-step's contact acts on
    int32_t contacted_count_ = 0;
    uint8_t* in_contact_ = nullptr;      ///< 1 per node: 1 if on contacted_
    double* saved_x_ = nullptr;
    double* saved_v_ = nullptr;
    double* path_x_ = nullptr;  ///< where each boundary node's path starts: the haptic side's
    double* path_v_ = nullptr;  ///< state of the node at the hand-over, else the full model's
    double* held_pull_ = nullptr;  ///< 3 per held node: the material's pull at the last sub-step
    double held_work_ = 0.0;       ///< the blade's work on the held nodes since the last break (J)
    uint64_t broken_hold_ = 0;     ///< the hold the haptic side let go (Buffer::held_serial), 0 none
    Id broken_body_ = kNullId;     ///< and its body
    Pose held_pose_;               ///< the tool's pose when the held nodes last moved
    bool have_held_pose_ = false;
    /// Per block of a law that keeps rotations: its elements' rotations at the last force
    /// pass, each pass's warm start (from the buffer's own while rotations_from_buffer_).
    Mat3L* rotation_ = nullptr;
    bool rotations_from_buffer_ = true;
    FrictionRecord* friction_ = nullptr;  ///< the sub-step's friction contacts
    int32_t friction_capacity_ = 0;
    int32_t friction_count_ = 0;
    uint32_t step_warnings_ = 0;  ///< SH_WARN bits raised inside the current step
    double age_ = 0.0;         ///< haptic time since the newest buffer arrived (s)
    Pose pose_;                ///< the last good device pose
    bool have_pose_ = false;
    ForceFilter filter_;
    std::atomic<uint64_t> warnings_[SH_WARN_COUNT] = {};

    // sim side (may allocate)
    Id extracted_body_ = kNullId;  ///< the body of the last extraction
    Id adjacency_body_ = kNullId;
    uint64_t adjacency_version_ = 0;  ///< the body's topology_version the adjacency is for
    vec<int32_t> node_tet_begin_, node_tet_;  ///< per body node: its tets (CSR)
    vec<double> x_before_;                     ///< the buffer body's x before the step
    Id x_before_body_ = kNullId;
    vec<std::pair<double, int32_t>> ranked_;   ///< candidate tets by distance
    vec<int32_t> seeds_;                       ///< the buffer's seed nodes (BufferCentre)
    vec<int32_t> local_of_;                    ///< body node -> local node, -1 outside
    vec<uint8_t> in_buffer_;                   ///< per body tet
    vec<int32_t> chosen_;                      ///< the buffer's tets (body numbers)
    vec<int32_t> ring_;                        ///< the buffer's body nodes, ascending
    vec<int32_t> members_;                     ///< the buffer's tets of one material model
    vec<uint8_t> moved_;                       ///< per local node: free or held (its forces matter)
    vec<int32_t> neighbor_;                    ///< per buffer triangle side: the triangle across
    vec<uint8_t> other_contact_;               ///< per body node: in contact with something else
};

}  // namespace sh
