#include "world/world.hpp"

#include "core/error.hpp"
#include "solver/explicit_integrator.hpp"

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

World::World(const sh_world_def& def) {
    for (int k = 0; k < 3; ++k) gravity[k] = def.gravity[k];
}

World::~World() {
    for (Slot& slot : slots_) sh::destroy(slot.body);
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
    Slot& slot = slots_[index];
    slot.body = body;
    slot.generation = next_generation();
    return (static_cast<uint64_t>(slot.generation) << 32) | (static_cast<uint64_t>(index) + 1);
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
    sh::destroy(slots_[index].body);
    slots_[index].body = nullptr;
}

void World::step(double dt, sh_step_report* report) {
    SH_REQUIRE(std::isfinite(dt) && dt > 0.0, SH_ERR_INVALID_ARGUMENT, "dt = %g s, must be finite and > 0", dt);
    const auto start = std::chrono::steady_clock::now();
    sh_step_report r{};
    r.substeps = 1;
    r.dt_critical = INFINITY;
    sh_body_id first_unstable = SH_NULL_BODY;
    double first_unstable_dt_crit = 0.0;
    bool first_unstable_rejected = false;
    for (size_t index = 0; index < slots_.size(); ++index) {
        Body* body = slots_[index].body;
        if (!body) continue;
        const BodyStepResult result = step_explicit(*body, dt, gravity);
        r.dt_critical = std::min(r.dt_critical, result.dt_critical);
        r.substeps = std::max(r.substeps, result.substeps);
        if (result.substeps > 1) r.warnings |= 1u << SH_WARN_SUBSTEPPED;
        if (!result.stable) {
            r.warnings |= 1u << SH_WARN_UNSTABLE;
            ++r.unstable_body_count;
            if (first_unstable == SH_NULL_BODY) {
                first_unstable = (static_cast<uint64_t>(slots_[index].generation) << 32) | (index + 1);
                first_unstable_dt_crit = result.dt_critical;
                first_unstable_rejected = result.rejected;
            }
        }
    }
    if (r.warnings & (1u << SH_WARN_SUBSTEPPED)) ++warnings[SH_WARN_SUBSTEPPED];
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
    if (first_unstable != SH_NULL_BODY) {
        if (first_unstable_rejected)
            throw Error(SH_ERR_UNSTABLE,
                        format("body 0x%llx: dt = %g s exceeds its critical step %g s (policy: reject); %d "
                               "body(ies) left unchanged",
                               static_cast<unsigned long long>(first_unstable), dt, first_unstable_dt_crit,
                               r.unstable_body_count));
        throw Error(SH_ERR_UNSTABLE,
                    format("body 0x%llx: the state became non-finite or exceeded the runaway speed; rolled back "
                           "(%d body(ies) unstable)",
                           static_cast<unsigned long long>(first_unstable), r.unstable_body_count));
    }
}

}  // namespace sh
