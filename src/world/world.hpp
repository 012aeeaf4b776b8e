// World: owns bodies behind generation-checked ids and steps them.
#pragma once

#include "core/id_pool.hpp"
#include "core/memory.hpp"
#include "model/body.hpp"
#include "solver/explicit_integrator.hpp"
#include "solver/stepped_body.hpp"
#include "world/step_hook.hpp"
#include "world/step_scratch.hpp"

#include <softhap/softhap.h>

#include <cstdint>
#include <utility>

namespace sh {

class BodyContacts;
struct TetMesh;
class ContactIslands;
struct Collider;
struct NewtonBodyState;
struct StepDoubling;

/// What a world needs for a body whose topology is about to change, allocated beforehand
/// (World::prepare_topology_change) so that the change itself cannot fail.
struct TopologyScratch {
    int32_t node_count = 0;            ///< the body's node count after the change
    StepDoubling* doubling = nullptr;  ///< its step-doubling scratch, with error estimates only
    TopologyScratch() = default;
    ~TopologyScratch();
    TopologyScratch(const TopologyScratch&) = delete;             ///< owns doubling
    TopologyScratch& operator=(const TopologyScratch&) = delete;  ///< owns doubling
};

/// The simulation world of the C API's sh_world. Bodies, tools and obstacles are named by
/// generation-checked Ids (core/id_pool.hpp), the values the C API's id types carry.
class World {
public:
    explicit World(const sh_world_def& def);
    ~World();
    World(const World&) = delete;
    World& operator=(const World&) = delete;

    /// Takes ownership of body (made with sh::create), to be stepped with settings; returns
    /// its new id.
    Id add_body(Body* body, const StepSettings& settings);

    /// Adds an FEM body made from mesh with one material (see FemBody), stepped with settings;
    /// counts SH_WARN_LOCKING if the material locks linear tets. Returns its id.
    Id add_fem_body(const TetMesh& mesh, const sh_material& material, double damping_mass,
                    double damping_stiffness, const StepSettings& settings);

    /// Gives elements[0..count) of FEM body id material (SH_ERR_UNSUPPORTED for a spring body);
    /// counts SH_WARN_LOCKING if it locks linear tets.
    void set_material(Id id, const int32_t* elements, int32_t count, const sh_material& material);

    /// How body id is stepped; throws SH_ERR_INVALID_HANDLE like body().
    const StepSettings& step_settings(Id id) const;

    /// Destroys the body; its id becomes stale. Throws SH_ERR_INVALID_HANDLE if not live.
    void remove_body(Id id);

    /// True if id names a live body of this world.
    bool is_valid(Id id) const;

    /// The body named by id; throws SH_ERR_INVALID_HANDLE if the id is null, stale or foreign.
    Body& body(Id id) const;

    /// Adds a tool (is_tool) or an obstacle made from def; returns its id.
    Id add_collider(const sh_collider_def& def, bool is_tool);

    /// Destroys a tool or obstacle; throws SH_ERR_INVALID_HANDLE if id is not a live one of
    /// that kind.
    void remove_collider(Id id, bool is_tool);

    /// True if id names a live tool (is_tool) or obstacle of this world.
    bool is_valid_collider(Id id, bool is_tool) const;

    /// The tool or obstacle named by id; throws SH_ERR_INVALID_HANDLE otherwise.
    Collider& collider(Id id, bool is_tool) const;

    /// Enables contact between bodies a and b with params, or disables it for null.
    void set_body_contact(Id a, Id b, const sh_contact_params* params);

    /// Steps every body by dt; fills report if not null. Throws SH_ERR_UNSTABLE (after
    /// filling report and advancing the stable bodies) if any body was rejected or rolled back.
    void step(double dt, sh_step_report* report);

    /// Moves every body to static equilibrium (see sh_world_solve_static); on failure every
    /// body is restored and the error rethrown.
    void solve_static(const sh_static_def& def, sh_static_report* report);

    /// Allocates into out what body id needs from the world once it has node_count nodes, before
    /// its topology changes. Throws SH_ERR_INVALID_HANDLE or std::bad_alloc, changing nothing.
    void prepare_topology_change(Id id, int32_t node_count, TopologyScratch& out);

    /// Body id's topology changed (its nodes, elements or surface): adopts prepared (from
    /// prepare_topology_change at its new node count), drops what the world keeps per node or
    /// element of it (contact state, Newton solver data, joint systems) and tells the hooks.
    void topology_changed(Id id, TopologyScratch& prepared) noexcept;

    /// Registers a step hook (a haptic context takes its device pose before each step and
    /// refreshes its buffer after). The hook is told (detach) if the world goes first.
    void add_hook(StepHook* hook);

    /// Unregisters a step hook.
    void remove_hook(StepHook* hook);

    /// Registers hook (made with sh::create) and owns it: it is destroyed with the world. key
    /// names it for owned_hook (one hook per key).
    void own_hook(StepHook* hook, const void* key);

    /// The hook owned under key, or null.
    StepHook* owned_hook(const void* key) const;

    /// What tool's blade holds of body (StepHook::blade_hold, asked of every hook); false if
    /// it holds nothing.
    bool blade_hold(Id tool, Id body, BladeHold& out) const;

    /// The Hook owned under key, made (default-constructed) and owned first if there is none.
    /// Throws std::bad_alloc owning nothing new.
    template <class Hook>
    Hook& own_hook_once(const void* key) {
        if (StepHook* found = owned_hook(key)) return static_cast<Hook&>(*found);
        Hook* hook = sh::create<Hook>();
        try {
            own_hook(hook, key);
        } catch (...) {
            sh::destroy(hook);
            throw;
        }
        return *hook;
    }

    /// The contact state of body id after the last step, or null if it has none yet.
    const BodyContacts* contacts_of(Id id) const;

    /// Calls visit(id, body) for every live body.
    template <class Visit>
    void for_each_body(Visit&& visit) const {
        for (size_t index = 0; index < slots_.size(); ++index)
            if (slots_[index].body()) visit(slots_.id_at(index), *slots_[index].body());
    }

    /// Calls visit(id, collider) for every live tool and obstacle (needs collider.hpp).
    template <class Visit>
    void for_each_collider(Visit&& visit) const {
        for (size_t index = 0; index < colliders_.size(); ++index)
            if (colliders_.is_live(index)) visit(colliders_.id_at(index), *colliders_[index]);
    }

    double gravity[3];                       ///< m/s^2, on every body
    uint64_t warnings[SH_WARN_COUNT] = {};   ///< per kind: how often it was raised (sh_world_get_warnings)

private:
    /// What a body slot owns (all null while free). Its step scratch is in scratch_.
    struct Slot {
        SteppedBody* stepped = nullptr;     ///< the body with its step settings and scratch;
                                            ///< null for a free slot
        /// The body, or null for a free slot.
        Body* body() const { return stepped ? stepped->body : nullptr; }
        StepDoubling* doubling = nullptr;   ///< with error_estimate_ only
        BodyContacts* contacts = nullptr;   ///< built on the first step with contact
    };
    /// Two bodies in contact with each other, with their contact law.
    struct BodyPair {
        Id a, b;
        sh_contact_params params;
        bool has_candidates = false;  ///< the last detection found candidates between them
    };
    /// Destroys what slot owns and leaves it empty.
    void destroy_slot(Slot& slot);
    /// True if any tool, obstacle or body pair may touch: the step then detects contact.
    bool has_contact() const { return colliders_.live_count() > 0 || !pairs_.empty(); }
    /// Starts every collider's step of dt; returns the contact sub-steps it needs.
    int32_t begin_colliders(double dt);
    /// Saves body slot index's x and v (the step's start) in its attempt scratch.
    void save_step_start(size_t index);
    /// Puts body slot index back to the step's start.
    void restore_step_start(size_t index);
    /// Runs the step's attempts (see world.cpp).
    void run_attempts(double dt, sh_step_report& r);
    /// True if a failed step of a body stepped with s is retried in sub-steps and its last
    /// attempt keeps its best iterate (an implicit body with policy SH_UNSTABLE_SUBSTEP).
    static bool sub_steps_on_failure(const StepSettings& s);
    /// How many sub-steps (times the contact sub-steps) a step of a body stepped with s may be
    /// retried in: the cap of its substep_count.
    static int32_t retry_limit(const StepSettings& s);
    /// True if a body stepped with s may retry its step in substeps sub-steps (times the
    /// contact sub-steps): that many are within its retry_limit.
    static bool may_retry_in(const StepSettings& s, int32_t substeps);
    /// Steps the bodies not in scratch_.skip through substeps equal sub-steps of dt.
    void run_substeps(double dt, int32_t substeps, sh_step_report& r);
    /// Steps every body not in skip by h, adding to r; a body that fails joins skip.
    void step_bodies(double h, sh_step_report& r, vec<uint8_t>& skip);
    /// Adds body index's step result to r (warnings); records a failure in its slot and skip.
    void note_result(size_t index, const BodyStepResult& result, sh_step_report& r, vec<uint8_t>& skip);
    /// Kinetic, elastic and gravitational energies of every body into r.
    void add_energies(sh_step_report& r) const;
    void log_step(double dt, const sh_step_report& r) const;
    /// Groups the bodies of pairs with candidates into islands (only implicit bodies with
    /// implicit_only, none in failed); false if no island has two bodies. Nothing without pairs.
    bool group_islands(bool implicit_only, const vec<uint8_t>* failed);
    /// Steps each island of more than one body as one implicit system (contact_islands.cpp).
    void step_islands(double h, sh_step_report& r, vec<uint8_t>& skip);
    /// Solves each island of more than one body for its joint equilibrium (contact_islands.cpp).
    void solve_static_islands(const sh_static_def& def, sh_static_report& r);
    /// Finds the contact candidates of every body for a (sub)step of h with colliders at their
    /// current poses, each tool moving by travel_fraction of its step, every box grown by
    /// extra_reach (m); attaches the fields; returns SH_WARN bits.
    uint32_t detect_contacts(double h, double travel_fraction, double extra_reach);
    /// Contact forces at the end state into every collider's state; detaches the fields.
    int32_t finish_contacts();
    /// Tools and obstacles in one pool (Collider::is_tool tells them apart, so a tool's id
    /// never names an obstacle): detection visits them in slot order, as they were added.
    IdPool<Collider*> colliders_;
    vec<BodyPair> pairs_;                ///< body pairs with contact enabled
    ContactIslands* islands_ = nullptr;  ///< built on the first step with body pairs
    vec<StepHook*> hooks_;               ///< told before and after each step
    vec<std::pair<const void*, StepHook*>> owned_hooks_;  ///< hooks the world owns, by key
    bool error_estimate_ = false;        ///< bodies take half steps for sh_step_report's estimate
    /// The id of live body slot index.
    Id id_of(size_t index) const { return slots_.id_at(index); }
    IdPool<Slot> slots_;                 ///< the bodies
    StepScratch scratch_;                ///< the step's scratch, indexed like slots_
};

}  // namespace sh
