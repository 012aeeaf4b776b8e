#include "world/contact_islands.hpp"

#include "core/clock.hpp"
#include "core/union_find.hpp"
#include "solver/implicit_integrator.hpp"
#include "solver/newton_problem.hpp"
#include "solver/static_solver.hpp"
#include "world/body_step.hpp"
#include "world/step_doubling.hpp"
#include "world/world.hpp"

#include <algorithm>

namespace sh {

ContactIslands::~ContactIslands() {
    for (Kept& k : kept_) sh::destroy(k.problem);
}

uint32_t ContactIslands::root(uint32_t slot) { return union_root(parent_, slot); }

int32_t ContactIslands::group(size_t slot_count) {
    parent_.resize(slot_count);
    for (size_t s = 0; s < slot_count; ++s) parent_[s] = static_cast<uint32_t>(s);
    for (const Link& link : links) {
        const uint32_t a = root(link.a), b = root(link.b);
        if (a != b) parent_[std::max(a, b)] = std::min(a, b);  // a set's root is its smallest slot
    }
    // island_ first counts each root's slots, then becomes the island index of every slot.
    island_.assign(slot_count, 0);
    for (size_t s = 0; s < slot_count; ++s) ++island_[root(static_cast<uint32_t>(s))];
    island_start_.assign(1, 0);
    for (size_t s = 0; s < slot_count; ++s) {
        if (parent_[s] != s) continue;  // roots come before the rest of their set
        const int32_t size = island_[s];
        island_[s] = size > 1 ? static_cast<int32_t>(island_start_.size()) - 1 : -1;
        if (size > 1) island_start_.push_back(island_start_.back() + size);
    }
    member_slots_.resize(static_cast<size_t>(island_start_.back()));
    vec<int32_t>& fill = island_start_;  // advanced while filling, then moved back
    for (size_t s = 0; s < slot_count; ++s) {
        const int32_t i = island_[root(static_cast<uint32_t>(s))];
        island_[s] = i;
        if (i >= 0) member_slots_[static_cast<size_t>(fill[static_cast<size_t>(i)]++)] = static_cast<uint32_t>(s);
    }
    for (size_t i = fill.size() - 1; i > 0; --i) fill[i] = fill[i - 1];
    fill[0] = 0;
    return island_count();
}

NewtonProblem& ContactIslands::problem(const Id* ids_, int32_t count) {
    for (Kept& k : kept_)
        if (k.ids.size() == static_cast<size_t>(count) && std::equal(k.ids.begin(), k.ids.end(), ids_)) {
            k.used = true;
            return *k.problem;
        }
    Kept k;
    k.ids.assign(ids_, ids_ + count);
    kept_.push_back(std::move(k));
    kept_.back().problem = sh::create<NewtonProblem>();
    kept_.back().used = true;
    return *kept_.back().problem;
}

void ContactIslands::drop_unused() {
    for (Kept& k : kept_)
        if (!k.used) sh::destroy(k.problem);
    kept_.erase(std::remove_if(kept_.begin(), kept_.end(), [](const Kept& k) { return !k.used; }), kept_.end());
    for (Kept& k : kept_) k.used = false;
}

void World::step_islands(double h, sh_step_report& r, vec<uint8_t>& skip) {
    ContactIslands& islands = *islands_;
    for (int32_t i = 0; i < islands.island_count(); ++i) {
        const uint32_t* members = islands.members(i);
        const int32_t count = islands.member_count(i);
        islands.stepped.clear();
        islands.doublings.clear();
        islands.ids.clear();
        bool keep_best = false;  // the island's last attempt is that of any member's
        for (int32_t m = 0; m < count; ++m) {
            Slot& slot = slots_[members[m]];
            keep_best |= scratch_.bodies[members[m]].keep_best;
            if (!slot.stepped->newton) slot.stepped->newton = sh::create<NewtonBodyState>();
            islands.stepped.push_back(slot.stepped);
            islands.doublings.push_back(slot.doubling);
            islands.ids.push_back(id_of(members[m]));
        }
        NewtonProblem& problem = islands.problem(islands.ids.data(), count);
        problem.prepare(islands.stepped.data(), count, islands.stepped[0]->settings.implicit);
        bool half_steps_stable = false;
        if (error_estimate_) {
            const ScopedTimer timer(r.error_estimate_seconds);
            half_steps_stable = take_half_steps_together(islands.stepped.data(), islands.doublings.data(), count, h,
                                                         [&](double half) { return step_implicit_coupled(problem, half, gravity).stable; });
        }
        for (SteppedBody* stepped : islands.stepped) stepped->body->clear_inverted_elements();
        const BodyStepResult result = step_implicit_coupled(problem, h, gravity, keep_best);
        for (int32_t m = 0; m < count && error_estimate_; ++m) {
            if (half_steps_stable && result.stable && r.error_estimate >= 0.0)
                r.error_estimate = std::max(r.error_estimate, largest_half_step_difference(*islands.stepped[static_cast<size_t>(m)]->body,
                                                                                           *islands.doublings[static_cast<size_t>(m)]));
            else
                r.error_estimate = -1.0;
        }
        add_step_figures(r, result);
        for (int32_t m = 0; m < count; ++m) note_result(members[m], result, r, skip);
    }
    islands.drop_unused();
}

void World::solve_static_islands(const sh_static_def& def, sh_static_report& r) {
    ContactIslands& islands = *islands_;
    for (int32_t i = 0; i < islands.island_count(); ++i) {
        const uint32_t* members = islands.members(i);
        const int32_t count = islands.member_count(i);
        islands.stepped.clear();
        for (int32_t m = 0; m < count; ++m) islands.stepped.push_back(slots_[members[m]].stepped);
        NewtonProblem problem;
        solve_static_coupled(problem, islands.stepped.data(), count, gravity, def, r);
    }
}

}  // namespace sh
