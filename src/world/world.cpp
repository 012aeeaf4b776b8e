#include "world/world.hpp"

#include "core/error.hpp"
#include "solver/explicit_integrator.hpp"
#include "solver/implicit_integrator.hpp"
#include "solver/static_solver.hpp"
#include "solver/step_support.hpp"
#include "world/body_step.hpp"
#include "world/step_doubling.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

namespace sh {
namespace {

uint32_t slot_of(sh_body_id id) { return static_cast<uint32_t>(id & 0xffffffffu) - 1u; }
uint32_t generation_of(sh_body_id id) { return static_cast<uint32_t>(id >> 32); }

// Generations come from one counter shared by all worlds, so an id is never valid in a world
// other than the one that issued it.
std::atomic<uint32_t> g_next_generation{1};

uint32_t next_generation() {
    uint32_t g = g_next_generation.fetch_add(1);
    while (g == 0) g = g_next_generation.fetch_add(1);
    return g;
}

}  // namespace

World::World(const sh_world_def& def) : error_estimate_(def.error_estimate != 0) {
    for (int k = 0; k < 3; ++k) gravity[k] = def.gravity[k];
}

World::~World() {
    for (Slot& slot : slots_) destroy_slot(slot);
}

void World::destroy_slot(Slot& slot) {
    sh::destroy(slot.body);
    sh::destroy(slot.implicit);
    sh::destroy(slot.doubling);
    slot.body = nullptr;
    slot.implicit = nullptr;
    slot.doubling = nullptr;
}

sh_body_id World::add_body(Body* body) {
    uint32_t index;
    if (!free_slots_.empty()) {
        index = free_slots_.back();
        free_slots_.pop_back();
    } else {
        try {
            // Room for every slot in the free list, so that remove_body never allocates.
            if (free_slots_.capacity() < slots_.size() + 1) free_slots_.reserve(2 * slots_.size() + 1);
            slots_.push_back(Slot{});
        } catch (...) {
            sh::destroy(body);
            throw;
        }
        index = static_cast<uint32_t>(slots_.size() - 1);
    }
    StepDoubling* doubling = nullptr;
    if (error_estimate_) {
        try {
            doubling = sh::create<StepDoubling>(body->x.size());
        } catch (...) {
            free_slots_.push_back(index);
            sh::destroy(body);
            throw;
        }
    }
    Slot& slot = slots_[index];
    slot.body = body;
    slot.doubling = doubling;
    slot.generation = next_generation();
    return id_of(index);
}

bool World::is_valid(sh_body_id id) const {
    if (id == SH_NULL_BODY) return false;
    const uint32_t index = slot_of(id);
    return index < slots_.size() && slots_[index].body && slots_[index].generation == generation_of(id);
}

Body& World::body(sh_body_id id) const {
    if (!is_valid(id))
        throw Error(SH_ERR_INVALID_HANDLE,
                    id == SH_NULL_BODY ? std::string("body id is null (0)")
                                       : format("body id 0x%llx is not a live body of this world (removed or never created)",
                                                static_cast<unsigned long long>(id)));
    return *slots_[slot_of(id)].body;
}

void World::remove_body(sh_body_id id) {
    body(id);  // validates
    const uint32_t index = slot_of(id);
    free_slots_.push_back(index);  // within the capacity reserved in add_body
    destroy_slot(slots_[index]);
}

void World::step(double dt, sh_step_report* report) {
    SH_REQUIRE(std::isfinite(dt) && dt > 0.0, SH_ERR_INVALID_ARGUMENT, "dt = %g s, must be finite and > 0", dt);
    const auto start = std::chrono::steady_clock::now();
    sh_step_report r{};
    r.substeps = 1;
    r.error_estimate = error_estimate_ ? 0.0 : -1.0;
    r.dt_critical = INFINITY;
    sh_body_id first_failed = SH_NULL_BODY;
    BodyStepResult first_failure;
    for (size_t index = 0; index < slots_.size(); ++index) {
        Slot& slot = slots_[index];
        if (!slot.body) continue;
        bool half_steps_stable = false;
        if (slot.doubling) {
            const auto t0 = std::chrono::steady_clock::now();
            half_steps_stable = take_half_steps(*slot.body, *slot.doubling, dt, gravity);
            r.error_estimate_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        }
        slot.body->clear_inverted_elements();
        const BodyStepResult result = step_body(*slot.body, slot.implicit, dt, gravity);
        if (slot.doubling) {
            if (half_steps_stable && result.stable && r.error_estimate >= 0.0)
                r.error_estimate = std::max(r.error_estimate, largest_half_step_difference(*slot.body, *slot.doubling));
            else
                r.error_estimate = -1.0;
        }
        r.dt_critical = std::min(r.dt_critical, result.dt_critical);
        r.substeps = std::max(r.substeps, result.substeps);
        r.newton_iterations = std::max(r.newton_iterations, result.newton_iterations);
        r.linear_iterations += result.linear_iterations;
        r.newton_residual = std::max(r.newton_residual, result.newton_residual);
        r.factorize_seconds += result.factorize_seconds;
        r.solve_seconds += result.solve_seconds;
        r.factorizations += result.factorizations;
        if (result.substeps > 1) r.warnings |= 1u << SH_WARN_SUBSTEPPED;
        if (slot.body->inverted_elements() > 0) r.warnings |= 1u << SH_WARN_INVERTED;
        if (!result.stable) {
            r.warnings |= 1u << SH_WARN_UNSTABLE;
            ++r.unstable_body_count;
            if (first_failed == SH_NULL_BODY) {
                first_failed = id_of(index);
                first_failure = result;
            }
        }
    }
    if (r.warnings & (1u << SH_WARN_SUBSTEPPED)) ++warnings[SH_WARN_SUBSTEPPED];
    if (r.warnings & (1u << SH_WARN_INVERTED)) ++warnings[SH_WARN_INVERTED];
    warnings[SH_WARN_UNSTABLE] += static_cast<uint64_t>(r.unstable_body_count);

    if (report) {
        for (const Slot& slot : slots_) {
            const Body* body = slot.body;
            if (!body) continue;
            for (int32_t i = 0; i < body->node_count(); ++i) {
                const double m = body->mass[static_cast<size_t>(i)];
                const double* v = &body->v[3 * static_cast<size_t>(i)];
                const double* x = &body->x[3 * static_cast<size_t>(i)];
                r.kinetic_energy += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                r.potential_energy -= m * (gravity[0] * x[0] + gravity[1] * x[1] + gravity[2] * x[2]);
            }
            r.elastic_energy += body->elastic_energy(body->x.data());
        }
        r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        *report = r;
    }
    if (first_failed == SH_NULL_BODY) return;
    const unsigned long long id = static_cast<unsigned long long>(first_failed);
    if (first_failure.rejected)
        throw Error(SH_ERR_UNSTABLE, format("body 0x%llx: dt = %g s exceeds its critical step %g s (policy: reject); "
                                            "%d body(ies) left unchanged",
                                            id, dt, first_failure.dt_critical, r.unstable_body_count));
    throw Error(first_failure.status, format("body 0x%llx: %s (%d body(ies) left as before the step)", id,
                                             first_failure.reason, r.unstable_body_count));
}

void World::solve_static(const sh_static_def& def, sh_static_report* report) {
    const auto start = std::chrono::steady_clock::now();
    sh_static_report r{};
    for (Slot& slot : slots_)
        if (slot.body) save_start_state(*slot.body);
    try {
        for (Slot& slot : slots_)
            if (slot.body) solve_static_body(*slot.body, gravity, def, r);
    } catch (...) {
        for (Slot& slot : slots_)
            if (slot.body) restore_start_state(*slot.body);
        r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (report) *report = r;  // what was tried, for the host's diagnosis
        throw;
    }
    r.converged = 1;
    r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (report) *report = r;
}

sh_body_id World::id_of(size_t index) const {
    return (static_cast<uint64_t>(slots_[index].generation) << 32) | (static_cast<uint64_t>(index) + 1);
}

}  // namespace sh
