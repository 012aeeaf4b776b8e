#include "world/world.hpp"


#include "collision/aabb_tree.hpp"
#include "contact/body_contacts.hpp"
#include "contact/collider.hpp"
#include "core/clock.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "material/material_params.hpp"
#include "model/fem_body.hpp"
#include "solver/explicit_integrator.hpp"
#include "solver/implicit_integrator.hpp"
#include "solver/static_solver.hpp"
#include "solver/step_support.hpp"
#include "solver/substeps.hpp"
#include "world/body_step.hpp"
#include "world/contact_islands.hpp"
#include "world/step_doubling.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

World::World(const sh_world_def& def) : error_estimate_(def.error_estimate != 0) {
    for (int k = 0; k < 3; ++k) gravity[k] = def.gravity[k];
}

World::~World() {
    for (StepHook* hook : hooks_) hook->detach();
    for (auto& owned : owned_hooks_) sh::destroy(owned.second);
    slots_.for_each([&](Slot& slot) { destroy_slot(slot); });
    colliders_.for_each([](Collider* c) { sh::destroy(c); });
    sh::destroy(islands_);
}

void World::destroy_slot(Slot& slot) {
    if (slot.stepped) {
        sh::destroy(slot.body());
        sh::destroy(slot.stepped->newton);
    }
    sh::destroy(slot.stepped);
    sh::destroy(slot.doubling);
    sh::destroy(slot.contacts);
    slot = Slot{};
}

Id World::add_body(Body* body, const StepSettings& settings) {
    StepDoubling* doubling = nullptr;
    SteppedBody* stepped = nullptr;
    Id id = kNullId;
    try {
        if (error_estimate_) doubling = sh::create<StepDoubling>(body->x.size());
        stepped = sh::create<SteppedBody>();
        stepped->workspace.resize(body->node_count());
        stepped->body = body;
        stepped->settings = settings;
        id = slots_.allocate(Slot{stepped, doubling, nullptr});
        // Room for the step's start state, scratch and attempt flags, so that a step allocates
        // nothing.
        scratch_.reserve_body(slots_.size(), id_index(id), body->x.size() + body->v.size());
    } catch (...) {
        if (id != kNullId) slots_.release(id);
        sh::destroy(stepped);
        sh::destroy(doubling);
        sh::destroy(body);
        throw;
    }
    return id;
}

bool World::is_valid(Id id) const { return slots_.contains(id); }

Body& World::body(Id id) const {
    const Slot* slot = slots_.find(id);
    if (!slot)
        throw Error(SH_ERR_INVALID_HANDLE,
                    id == kNullId ? std::string("body id is null (0)")
                                  : format("body id 0x%llx is not a live body of this world (removed or never created)",
                                           static_cast<unsigned long long>(id)));
    return *slot->body();
}

Id World::add_fem_body(const TetMesh& mesh, const sh_material& material, double damping_mass,
                       double damping_stiffness, const StepSettings& settings) {
    const Id id = add_body(sh::create<FemBody>(mesh, material, damping_mass, damping_stiffness), settings);
    if (locks_linear_tets(material)) ++warnings[SH_WARN_LOCKING];
    return id;
}

void World::set_material(Id id, const int32_t* elements, int32_t count, const sh_material& material) {
    Body& b = body(id);
    require(b.is_fem(), SH_ERR_UNSUPPORTED, "sh_body_set_material needs an FEM body; this is a mass-spring body");
    static_cast<FemBody&>(b).set_material(elements, count, material);
    if (locks_linear_tets(material) && count > 0) ++warnings[SH_WARN_LOCKING];
}

const StepSettings& World::step_settings(Id id) const {
    body(id);  // validates
    return slots_[id_index(id)].stepped->settings;
}

void World::remove_body(Id id) {
    body(id);  // validates
    destroy_slot(slots_[id_index(id)]);
    scratch_.release_body(id_index(id));
    slots_.release(id);  // never allocates
    pairs_.erase(std::remove_if(pairs_.begin(), pairs_.end(), [&](const BodyPair& p) { return p.a == id || p.b == id; }),
                 pairs_.end());
}

TopologyScratch::~TopologyScratch() { sh::destroy(doubling); }

void World::prepare_topology_change(Id id, int32_t node_count, TopologyScratch& out) {
    body(id);  // validates
    slots_[id_index(id)].stepped->workspace.reserve(node_count);  // room only: its size follows the body's
    out.node_count = node_count;
    if (error_estimate_) out.doubling = sh::create<StepDoubling>(3 * static_cast<size_t>(node_count));
    scratch_.reserve_body(slots_.size(), id_index(id), 6 * static_cast<size_t>(node_count));
}

void World::topology_changed(Id id, TopologyScratch& prepared) noexcept {
    Slot& slot = slots_[id_index(id)];
    slot.stepped->workspace.resize(prepared.node_count);  // within the room prepared: no allocation
    std::swap(slot.doubling, prepared.doubling);
    sh::destroy(slot.contacts);  // rebuilt over the new surface on the next step with contact
    slot.contacts = nullptr;
    // Its pattern and symbolic analysis follow the elements; the elimination order carries over.
    if (slot.stepped->newton) slot.stepped->newton->forget_pattern();
    sh::destroy(islands_);  // joint systems are rebuilt on the next step with body contact
    islands_ = nullptr;
    for (StepHook* hook : hooks_) hook->topology_changed(*this, id);
}

Id World::add_collider(const sh_collider_def& def, bool is_tool) {
    Collider* collider = sh::create<Collider>(def, is_tool);
    try {
        return colliders_.allocate(collider);
    } catch (...) {
        sh::destroy(collider);
        throw;
    }
}

bool World::is_valid_collider(Id id, bool is_tool) const {
    Collider* const* collider = colliders_.find(id);
    return collider && (*collider)->is_tool == is_tool;
}

Collider& World::collider(Id id, bool is_tool) const {
    const char* kind = is_tool ? "tool" : "obstacle";
    if (!is_valid_collider(id, is_tool))
        throw Error(SH_ERR_INVALID_HANDLE, id == kNullId ? format("%s id is null (0)", kind)
                                                         : format("%s id 0x%llx is not a live %s of this world (removed or never created)",
                                                                  kind, static_cast<unsigned long long>(id), kind));
    return **colliders_.find(id);
}

void World::remove_collider(Id id, bool is_tool) {
    collider(id, is_tool);  // validates
    sh::destroy(colliders_.release(id));  // release never allocates
}

void World::set_body_contact(Id a, Id b, const sh_contact_params* params) {
    require(body(a).is_fem() && body(b).is_fem(), SH_ERR_UNSUPPORTED,
            "body contact needs two FEM bodies (a mass-spring body has no tets to be inside of)");
    require(a != b, SH_ERR_INVALID_ARGUMENT, "a and b are the same body: self-contact is not supported");
    if (params) validate_contact_params(*params, "params");
    const auto same = [&](const BodyPair& p) { return (p.a == a && p.b == b) || (p.a == b && p.b == a); };
    const auto it = std::find_if(pairs_.begin(), pairs_.end(), same);
    if (!params) {
        if (it != pairs_.end()) pairs_.erase(it);
    } else if (it != pairs_.end()) {
        it->params = *params;
    } else {
        pairs_.push_back(BodyPair{a, b, *params});
    }
}

const BodyContacts* World::contacts_of(Id id) const {
    const Slot* slot = slots_.find(id);
    return slot ? slot->contacts : nullptr;
}

void World::add_hook(StepHook* hook) { hooks_.push_back(hook); }

void World::own_hook(StepHook* hook, const void* key) {
    owned_hooks_.reserve(owned_hooks_.size() + 1);
    hooks_.reserve(hooks_.size() + 1);
    owned_hooks_.push_back({key, hook});
    hooks_.push_back(hook);
}

StepHook* World::owned_hook(const void* key) const {
    for (const auto& owned : owned_hooks_)
        if (owned.first == key) return owned.second;
    return nullptr;
}

bool World::blade_hold(Id tool, Id body, BladeHold& out) const {
    for (const StepHook* hook : hooks_)
        if (hook->blade_hold(*this, tool, body, out)) return true;
    return false;
}

void World::remove_hook(StepHook* hook) { hooks_.erase(std::remove(hooks_.begin(), hooks_.end(), hook), hooks_.end()); }

void World::step_bodies(double h, sh_step_report& r, vec<uint8_t>& skip) {
    // Implicit bodies pressing on each other are stepped together, island by island.
    const bool coupled = group_islands(true, &skip);
    for (size_t index = 0; index < slots_.size(); ++index) {
        Slot& slot = slots_[index];
        if (!slot.body() || skip[index]) continue;
        if (coupled && islands_->island_of(index) >= 0) continue;
        bool half_steps_stable = false;
        if (slot.doubling) {
            const ScopedTimer timer(r.error_estimate_seconds);
            half_steps_stable = take_half_steps(*slot.stepped, *slot.doubling, h, gravity);
        }
        slot.body()->clear_inverted_elements();
        const BodyStepResult result = step_body(*slot.stepped, h, gravity, scratch_.bodies[index].keep_best);
        if (slot.doubling) {
            if (half_steps_stable && result.stable && r.error_estimate >= 0.0)
                r.error_estimate = std::max(r.error_estimate, largest_half_step_difference(*slot.body(), *slot.doubling));
            else
                r.error_estimate = -1.0;
        }
        add_step_figures(r, result);
        note_result(index, result, r, skip);
    }
    if (coupled) step_islands(h, r, skip);
    else if (islands_) islands_->drop_unused();
}

void World::note_result(size_t index, const BodyStepResult& result, sh_step_report& r, vec<uint8_t>& skip) {
    Slot& slot = slots_[index];
    if (slot.body()->inverted_elements() > 0) r.warnings |= 1u << SH_WARN_INVERTED;
    if (result.not_converged) r.warnings |= 1u << SH_WARN_NOT_CONVERGED;
    if (result.stable) return;
    skip[index] = 1;  // the body sits out the rest of this attempt
    scratch_.bodies[index].failure = result;
    scratch_.bodies[index].failed = true;
}

bool World::group_islands(bool implicit_only, const vec<uint8_t>* failed) {
    if (pairs_.empty()) return false;
    if (!islands_) islands_ = sh::create<ContactIslands>();
    islands_->links.clear();
    for (const BodyPair& pair : pairs_) {
        const uint32_t a = id_index(pair.a), b = id_index(pair.b);
        const auto eligible = [&](uint32_t index) {
            return !(failed && (*failed)[index]) &&
                   (!implicit_only || slots_[index].stepped->settings.integrator == SH_INTEGRATOR_IMPLICIT_EULER);
        };
        if (pair.has_candidates && eligible(a) && eligible(b)) islands_->links.push_back({a, b});
    }
    return islands_->group(slots_.size()) > 0;
}

uint32_t World::detect_contacts(double h, double travel_fraction, double extra_reach) {
    uint32_t warning_bits = 0;
    slots_.for_each([&](Slot& slot) {
        Body& body = *slot.body();
        if (!slot.contacts)
            slot.contacts = sh::create<BodyContacts>(body, slot.stepped->settings.integrator == SH_INTEGRATOR_IMPLICIT_EULER,
                                                     scratch_.contact);
        BodyContacts& contacts = *slot.contacts;
        contacts.clear();
        // How far a node may go in the (sub)step: twice its speed's reach, plus a little.
        double speed2 = 0.0;
        for (size_t j = 0; j < body.v.size(); j += 3)
            speed2 = std::max(speed2, body.v[j] * body.v[j] + body.v[j + 1] * body.v[j + 1] + body.v[j + 2] * body.v[j + 2]);
        const double margin = 2.0 * h * std::sqrt(speed2) + extra_reach;
        contacts.refit(margin);
        double anticipated = margin;
        colliders_.for_each([&](Collider* c) {
            const double reach = margin + travel_fraction * c->travel();
            anticipated = std::max(anticipated, reach);
            if (contacts.detect(*c, reach)) warning_bits |= 1u << SH_WARN_CAPACITY;
        });
        contacts.anticipated_depth = anticipated;
    });
    for (BodyPair& pair : pairs_) {
        Slot& a = slots_[id_index(pair.a)];
        Slot& b = slots_[id_index(pair.b)];
        const int32_t before = a.contacts->candidate_count() + b.contacts->candidate_count();
        if (BodyContacts::detect_pair(*a.contacts, *b.contacts, pair.params)) warning_bits |= 1u << SH_WARN_CAPACITY;
        if (BodyContacts::detect_pair(*b.contacts, *a.contacts, pair.params)) warning_bits |= 1u << SH_WARN_CAPACITY;
        pair.has_candidates = a.contacts->candidate_count() + b.contacts->candidate_count() > before;
    }
    // Implicit bodies take each candidate's depth at the step's start for the depth rate of
    // the step's contact law: with the colliders where the (sub)step starts.
    const auto swap_poses = [](Collider* c) { std::swap(c->pose, c->previous); };
    colliders_.for_each(swap_poses);
    slots_.for_each([&](Slot& slot) { slot.body()->field = slot.contacts->finish_detection(h); });
    colliders_.for_each(swap_poses);
    return warning_bits;
}

int32_t World::finish_contacts() {
    colliders_.for_each([](Collider* c) { c->state = sh_contact_state{}; });
    int32_t count = 0;
    slots_.for_each([&](Slot& slot) {
        if (!slot.contacts) return;
        if (slot.body()->field) count += slot.contacts->accumulate_reactions();
        slot.body()->field = nullptr;
    });
    colliders_.for_each([](Collider* c) {
        c->start = c->target;
        c->pose = c->target;
        c->velocity_given = false;
    });
    return count;
}

void World::log_step(double dt, const sh_step_report& r) const {
    // What the step's warnings mean, for the host's log (sh_set_log_callback).
    if (!logging()) return;
    const auto raised = [&](sh_warning kind) { return (r.warnings & (1u << kind)) != 0; };
    if (raised(SH_WARN_SUBSTEPPED))
        log_message(SH_LOG_INFO, "step of %g s: split into %d sub-steps (critical step %g s)", dt, r.substeps,
                    r.dt_critical);
    if (raised(SH_WARN_INVERTED))
        log_message(SH_LOG_WARNING, "step of %g s: some elements are inverted (det F <= 0)", dt);
    if (raised(SH_WARN_NOT_CONVERGED))
        log_message(SH_LOG_WARNING, "step of %g s: an implicit body did not converge within its Newton cap and "
                    "sub-steps and kept its best iterate", dt);
    if (raised(SH_WARN_CAPACITY))
        log_message(SH_LOG_WARNING, "step of %g s: a contact capacity was reached; contacts beyond it were dropped", dt);
    if (r.unstable_body_count > 0)
        log_message(SH_LOG_WARNING, "step of %g s: %d body(ies) rolled back (rejected, non-finite or running away)",
                    dt, r.unstable_body_count);
}

void World::step(double dt, sh_step_report* report) {
    SH_REQUIRE(std::isfinite(dt) && dt > 0.0, SH_ERR_INVALID_ARGUMENT, "dt = %g s, must be finite and > 0", dt);
    const double start = now_seconds();
    sh_step_report r{};
    r.substeps = 1;
    r.error_estimate = error_estimate_ ? 0.0 : -1.0;
    r.dt_critical = INFINITY;
    for (StepHook* hook : hooks_) hook->before_step(*this);
    for (StepHook* hook : hooks_) hook->before_motion(*this, r);
    r.contact_substeps = begin_colliders(dt);
    try {
        run_attempts(dt, r);
    } catch (...) {
        slots_.for_each([](Slot& slot) { slot.body()->field = nullptr; });
        throw;
    }
    if (has_contact()) {
        {
            const ScopedTimer timer(r.collision_seconds);
            r.contact_count = finish_contacts();
        }
        r.collision_seconds += scratch_.contact.take_evaluation_seconds();
        if (r.warnings & (1u << SH_WARN_CAPACITY)) ++warnings[SH_WARN_CAPACITY];
    }
    for (StepHook* hook : hooks_) hook->after_step(*this, dt);
    size_t failed = slots_.size();  // the first failed body's slot, if any
    for (size_t index = 0; index < slots_.size(); ++index)
        if (slots_.is_live(index) && scratch_.bodies[index].failed) {
            ++r.unstable_body_count;
            if (failed == slots_.size()) failed = index;
        }
    if (r.unstable_body_count > 0) r.warnings |= 1u << SH_WARN_UNSTABLE;
    for (const sh_warning kind : {SH_WARN_SUBSTEPPED, SH_WARN_INVERTED, SH_WARN_NOT_CONVERGED})
        if (r.warnings & (1u << kind)) ++warnings[kind];
    warnings[SH_WARN_UNSTABLE] += static_cast<uint64_t>(r.unstable_body_count);
    log_step(dt, r);
    if (report) {
        add_energies(r);
        r.wall_seconds = now_seconds() - start;
        *report = r;
    }
    if (failed == slots_.size()) return;
    const unsigned long long id = static_cast<unsigned long long>(id_of(failed));
    const BodyStepResult& failure = scratch_.bodies[failed].failure;
    if (failure.rejected)
        throw Error(SH_ERR_UNSTABLE, format("body 0x%llx: dt = %g s exceeds its critical step %g s (policy: reject); "
                                            "%d body(ies) left unchanged",
                                            id, dt, failure.dt_critical, r.unstable_body_count));
    throw Error(failure.status, format("body 0x%llx: %s (%d body(ies) left as before the step)", id, failure.reason,
                                       r.unstable_body_count));
}

int32_t World::begin_colliders(double dt) {
    // Tools move from their last pose to the host's in sub-steps short enough that none
    // crosses more than half its inner radius at once.
    int32_t substeps = 1;
    colliders_.for_each([&](Collider* c) {
        c->begin_step(dt);
        const double travel = c->travel(), limit = 0.5 * c->shape.inner_radius();
        substeps = std::max(substeps, substep_count(travel, limit, kMaxContactSubsteps).count);
    });
    return substeps;
}

void World::save_step_start(size_t index) {
    const Body& body = *slots_[index].body();
    vec<double>& saved = scratch_.bodies[index].saved;
    saved.assign(body.x.begin(), body.x.end());
    saved.insert(saved.end(), body.v.begin(), body.v.end());
}

void World::restore_step_start(size_t index) {
    Body& body = *slots_[index].body();
    const vec<double>& saved = scratch_.bodies[index].saved;
    const size_t n = body.x.size();
    std::copy(saved.begin(), saved.begin() + static_cast<std::ptrdiff_t>(n), body.x.begin());
    std::copy(saved.begin() + static_cast<std::ptrdiff_t>(n), saved.end(), body.v.begin());
}

// The step as attempts of 1, 2, 4, ... times the contact sub-steps: a body whose attempt
// failed goes back to the step's start and, if it may (an implicit body sub-stepping within
// its max_substeps), takes part in the next attempt, whose last allowed one keeps its best
// iterate; the others' failures are final. A body that fails an attempt of one sub-step is
// already back at the step's start (every integrator restores its own start on failure), so
// the start is copied only for attempts of more sub-steps.
void World::run_attempts(double dt, sh_step_report& r) {
    const int32_t base = r.contact_substeps;
    vec<uint8_t>& skip = scratch_.skip;
    skip.assign(slots_.size(), 0);  // within the capacity reserved in add_body
    for (size_t index = 0; index < slots_.size(); ++index) {
        scratch_.bodies[index].failed = false;
        if (slots_.is_live(index) && base > 1) save_step_start(index);
    }
    for (int32_t factor = 1;; factor *= 2) {
        for (size_t index = 0; index < slots_.size(); ++index) {
            if (!slots_.is_live(index)) continue;
            const StepSettings& s = slots_[index].stepped->settings;
            scratch_.bodies[index].keep_best = sub_steps_on_failure(s) && !may_retry_in(s, 2 * factor);
        }
        run_substeps(dt, base * factor, r);
        bool retry = false;
        for (size_t index = 0; index < slots_.size(); ++index) {
            if (!slots_.is_live(index)) continue;
            BodyAttempt& attempt = scratch_.bodies[index];
            skip[index] = 1;  // done, unless it retries
            if (!attempt.failed) continue;
            if (base * factor > 1) restore_step_start(index);
            if (!may_retry_in(slots_[index].stepped->settings, 2 * factor)) continue;  // final: reported by step()
            if (base * factor == 1) save_step_start(index);
            attempt.failed = false;
            skip[index] = 0;
            retry = true;
        }
        if (!retry) return;
        r.substeps = std::max(r.substeps, 2 * factor);
        r.warnings |= 1u << SH_WARN_SUBSTEPPED;
    }
}

bool World::sub_steps_on_failure(const StepSettings& s) {
    return s.integrator == SH_INTEGRATOR_IMPLICIT_EULER && s.on_unstable == SH_UNSTABLE_SUBSTEP;
}

int32_t World::retry_limit(const StepSettings& s) { return sub_steps_on_failure(s) ? s.implicit.max_substeps : 1; }

bool World::may_retry_in(const StepSettings& s, int32_t substeps) {
    // Counted in sub-steps: a step of `substeps` units, none longer than one unit, needs
    // exactly that many, which the body's cap may clamp.
    return !substep_count(substeps, 1.0, retry_limit(s)).clamped;
}

// substeps equal sub-steps of the bodies not in scratch_.skip, each tool moving its share of
// the step from its start pose, with contact detection before each.
void World::run_substeps(double dt, int32_t substeps, sh_step_report& r) {
    const double h = dt / substeps;
    vec<uint8_t>& skip = scratch_.skip;
    if (!has_contact()) {
        step_bodies(h, r, skip);
        return;
    }
    colliders_.for_each([](Collider* c) {
        if (c->is_tool) c->pose = c->start;
    });
    for (int32_t s = 0; s < substeps; ++s) {
        const double fraction = static_cast<double>(s + 1) / substeps;
        colliders_.for_each([&](Collider* c) {
            c->previous = c->pose;
            if (c->is_tool) c->pose = interpolate(c->start, c->target, fraction);
        });
        {
            const ScopedTimer timer(r.collision_seconds);
            r.warnings |= detect_contacts(h, 1.0 / substeps, 0.0);
        }
        step_bodies(h, r, skip);
    }
}

void World::add_energies(sh_step_report& r) const {
    slots_.for_each([&](const Slot& slot) {
        const Body* body = slot.body();
        for (int32_t i = 0; i < body->node_count(); ++i) {
            const double m = body->mass[static_cast<size_t>(i)];
            const double* v = &body->v[3 * static_cast<size_t>(i)];
            const double* x = &body->x[3 * static_cast<size_t>(i)];
            r.kinetic_energy += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            r.potential_energy -= m * (gravity[0] * x[0] + gravity[1] * x[1] + gravity[2] * x[2]);
        }
        r.elastic_energy += body->elastic_energy_recalled(body->x.data());
    });
}

void World::solve_static(const sh_static_def& def, sh_static_report* report) {
    const double start = now_seconds();
    sh_static_report r{};
    slots_.for_each([](Slot& slot) { save_start_state(*slot.stepped); });
    for (StepHook* hook : hooks_) hook->before_step(*this);
    try {
        if (has_contact()) {
            // Tools rest at their host-set poses; candidates reach as far as the tool's size,
            // since the solve may move the surface that far.
            colliders_.for_each([](Collider* c) {
                c->start = c->pose = c->previous = c->target;
                c->velocity_given = false;
                for (int k = 0; k < 3; ++k) c->velocity[k] = c->angular[k] = 0.0;
            });
            slots_.for_each([](Slot& slot) { std::fill(slot.body()->v.begin(), slot.body()->v.end(), 0.0); });
        }
        double reach = 0.0, extent = 0.0;
        colliders_.for_each([&](const Collider* c) {
            if (!c->shape.is_half_space()) reach = std::max(reach, c->shape.inner_radius());
        });
        slots_.for_each([&](const Slot& slot) {
            Aabb box;
            for (size_t j = 0; j < slot.body()->x.size(); j += 3) box.add(&slot.body()->x[j]);
            for (int k = 0; k < 3; ++k) extent = std::max(extent, box.hi[k] - box.lo[k]);
        });
        reach = std::max(reach, 0.05 * extent);
        // Bodies pressing on each other are solved together, for their joint equilibrium.
        if (has_contact()) detect_contacts(0.0, 0.0, reach);  // h = 0: the contact law at rest
        const bool coupled = group_islands(false, nullptr);
        for (size_t index = 0; index < slots_.size(); ++index)
            if (slots_[index].body() && !(coupled && islands_->island_of(index) >= 0))
                solve_static_body(*slots_[index].stepped, gravity, def, r);
        if (coupled) solve_static_islands(def, r);
        if (has_contact()) finish_contacts();
    } catch (...) {
        slots_.for_each([](Slot& slot) {
            slot.body()->field = nullptr;
            restore_start_state(*slot.stepped);
        });
        r.wall_seconds = now_seconds() - start;
        if (report) *report = r;  // what was tried, for the host's diagnosis
        throw;
    }
    r.converged = 1;
    // The hooks take up the equilibrium at once (no step to move across).
    for (StepHook* hook : hooks_) hook->after_step(*this, 0.0);
    r.wall_seconds = now_seconds() - start;
    if (report) *report = r;
}

}  // namespace sh
