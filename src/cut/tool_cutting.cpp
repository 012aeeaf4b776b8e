#include "cut/tool_cutting.hpp"

#include "contact/collider.hpp"
#include "core/clock.hpp"
#include "core/error.hpp"
#include "core/vec3.hpp"
#include "cut/body_cut.hpp"
#include "cut/breaking.hpp"
#include "cut/material_frame.hpp"
#include "world/world.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace sh {
namespace {

/// Names the world's cutting hook.
const char kCuttingKey = 0;

/// The two triangles the blade edge sweeps from the tool's start pose to its target pose (18
/// doubles); false if they have no area (the blade did not move across its own edge).
bool swept_blade(const Collider& tool, double triangles[18]) {
    double a0[3], b0[3], a1[3], b1[3];
    tool.start.to_world(tool.cutting.edge[0], a0);
    tool.start.to_world(tool.cutting.edge[1], b0);
    tool.target.to_world(tool.cutting.edge[0], a1);
    tool.target.to_world(tool.cutting.edge[1], b1);
    const double* corners[6] = {a0, b0, b1, a0, b1, a1};
    for (int c = 0; c < 6; ++c)
        for (int k = 0; k < 3; ++k) triangles[3 * c + k] = corners[c][k];
    // Each triangle's area against the blade's length: a sweep shorter than a millionth of the
    // blade is no motion.
    double e[3], d0[3], d1[3], n0[3], n1[3];
    sub3(b0, a0, e);
    sub3(b1, a0, d0);
    sub3(a1, a0, d1);
    cross3(e, d0, n0);
    cross3(d0, d1, n1);
    const double scale = 1e-6 * dot3(e, e);
    return norm3(n0) > scale && norm3(n1) > scale;
}

/// The four sides of the quad that triangles[18] (as swept_blade makes them) cover: the blade's
/// edge at the start and at the target, and the paths of its two ends (6 doubles each).
std::array<double, 24> quad_sides(const double triangles[18]) {
    // Corners 0, 1, 2 and 5 are the edge's start ends a0, b0, then its target ends b1, a1.
    const int around[5] = {0, 1, 2, 5, 0};
    std::array<double, 24> sides;
    for (int s = 0; s < 4; ++s)
        for (int k = 0; k < 3; ++k) {
            sides[6 * static_cast<size_t>(s) + static_cast<size_t>(k)] = triangles[3 * around[s] + k];
            sides[6 * static_cast<size_t>(s) + 3 + static_cast<size_t>(k)] = triangles[3 * around[s + 1] + k];
        }
    return sides;
}

/// The edge length a tool's cut refines the material to (sh_cut_def.resolution).
double resolution(const sh_cut_def& def) {
    if (def.resolution > 0.0) return def.resolution;
    double d[3];
    sub3(def.edge[1], def.edge[0], d);
    return norm3(d) / 4.0;
}

/// True if the box around body's current nodes meets the box around triangles[18].
bool near(const Body& body, const double triangles[18]) {
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) lo[k] = INFINITY, hi[k] = -INFINITY;
    for (int32_t i = 0; i < body.node_count(); ++i)
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], at(body.x.data(), i)[k]), hi[k] = std::max(hi[k], at(body.x.data(), i)[k]);
    for (int k = 0; k < 3; ++k) {
        double a = INFINITY, b = -INFINITY;
        for (int c = 0; c < 6; ++c) a = std::min(a, triangles[3 * c + k]), b = std::max(b, triangles[3 * c + k]);
        if (a > hi[k] || b < lo[k]) return false;
    }
    return true;
}

/// Cuts every body along each cutting tool's swept blade before the step's motion. A blade
/// that advances by less than an element per step crosses each tet bit by bit, so what it
/// swept is kept and cut with whole; it is kept in each body's rest shape (the material
/// frame), where it stays with the material as the body moves, so that cutting again along
/// where the blade has been finds the same faces and shaves nothing off them. A physical
/// blade's breaks are kept the same way (breaking.hpp has how it holds and breaks).
class ToolCutting final : public BeforeMotionHook {
public:
    void before_motion(World& world, sh_step_report& report) override {
        const double start = now_seconds();
        forget_gone(world);
        world.for_each_collider([&](Id id, const Collider& tool) {
            if (!tool.is_tool || !tool.cuts) return;
            world.for_each_body([&](Id body_id, const Body& body) {
                report.cut_faces += tool.cutting.criterion == SH_CUT_PHYSICAL ? break_ahead(world, id, tool, body_id, body)
                                                                             : cut_swept(world, id, tool, body_id, body);
            });
        });
        report.topology_seconds += now_seconds() - start;
    }

    /// A physical blade feels the material it holds: its force joins the tool's reaction.
    void after_step(World& world, double) override {
        for (Sweep& sweep : swept_) {
            if (sweep.breaking.held.empty() || !world.is_valid(sweep.body)) continue;
            Collider& tool = world.collider(sweep.tool, true);
            double force[3], arm[3], torque[3];
            measure_held(world.body(sweep.body), sweep.breaking, force);
            double a[3], b[3];
            tool.target.to_world(tool.cutting.edge[0], a);
            tool.target.to_world(tool.cutting.edge[1], b);
            for (int k = 0; k < 3; ++k) arm[k] = 0.5 * (a[k] + b[k]) - tool.target.p[k];
            cross3(arm, force, torque);
            for (int k = 0; k < 3; ++k) tool.state.force[k] += force[k], tool.state.torque[k] += torque[k];
        }
    }

    /// What tool's blade holds of body (for the haptic contexts).
    bool blade_hold(const World& world, Id tool, Id body, BladeHold& out) const override {
        for (const Sweep& s : swept_) {
            const BreakState& b = s.breaking;
            if (s.tool != tool || s.body != body || b.held.empty() || b.forces.size() != 3 * b.held.size()) continue;
            out.nodes = b.held.data(), out.forces = b.forces.data(), out.count = b.held.size();
            out.work = b.work + pending_work(world.body(body), b);
            out.needed = b.needed, out.serial = b.hold;
            return true;
        }
        return false;
    }

    /// Forgets what tool id's blade swept (it stopped cutting), letting go what it held.
    void forget(World& world, Id tool) {
        for (Sweep& s : swept_)
            if (s.tool == tool && world.is_valid(s.body)) release(world.body(s.body), s.breaking);
        swept_.erase(std::remove_if(swept_.begin(), swept_.end(), [&](const Sweep& s) { return s.tool == tool; }), swept_.end());
    }

private:
    /// What one tool's blade swept (or broke) through one body, in the body's rest shape.
    struct Sweep {
        Id tool, body;
        vec<double> triangles;  ///< 9 per triangle
        vec<int32_t> on_nodes;  ///< the nodes the cut along it went through, ascending
        BreakState breaking;    ///< the physical criterion's hold and count
    };

    /// The geometric criterion: cuts body along what the blade swept from its start pose to
    /// its target pose, with what it swept before. Returns the faces separated.
    int32_t cut_swept(World& world, Id id, const Collider& tool, Id body_id, const Body& body) {
        double triangles[18];
        if (!swept_blade(tool, triangles) || !near(body, triangles)) return 0;  // no motion, or away from it
        return cut_along(world, sweep_of(id, body_id), body_id, body, triangles, resolution(tool.cutting));
    }

    /// The physical criterion: the edge holds the material just ahead of it and drags it
    /// along; once the work it did since the last break pays for the crack (toughness /
    /// sharpness x engaged length x the resolution), the material breaks from the edge to one
    /// resolution beyond the crack's front. Returns the faces separated.
    int32_t break_ahead(World& world, Id id, const Collider& tool, Id body_id, const Body& body) {
        double ahead[18];
        const double advance = resolution(tool.cutting);
        if (!crack_ahead(tool, advance, ahead) || !near(body, ahead)) return 0;  // resting, or away: the hold stays
        Sweep& sweep = sweep_of(id, body_id);
        Body& held = world.body(body_id);
        count_work(body, sweep.breaking);
        const Engagement engaged = engage(body, tool);
        const double needed = engaged.toughness / tool.cutting.sharpness * engaged.length * advance;
        sweep.breaking.needed = needed;
        if (!(needed > 0.0)) {
            release(held, sweep.breaking);  // out of the material, or one that never breaks
            return 0;
        }
        double rest[18];
        if (sweep.breaking.work >= needed && break_at_rest(body, tool, sweep.breaking, sweep.on_nodes, advance, rest)) {
            // Work beyond the crack's price (the last step overshot it) goes to the next one,
            // so that over a steady cut all of the blade's work pays for crack.
            const double excess = std::min(sweep.breaking.work - needed, needed);
            release(held, sweep.breaking);
            sweep.breaking.work = excess;
            return cut_along_rest(world, sweep, body_id, rest, advance);
        }
        if (sweep.breaking.held.empty()) {
            // Refine before holding, so that nodes lie within reach ahead of the edge.
            to_rest_all(body, ahead, 6, rest);
            refine_body_near(world, body_id, quad_sides(rest).data(), 4, advance, &sweep.on_nodes);
        }
        hold_ahead(held, tool, advance, sweep.on_nodes, sweep.breaking);
        return 0;
    }

    /// Refines body around the quad triangles[18] (world frame, as swept_blade lays it out)
    /// to edge_length and cuts it along the quad and the rest of sweep. Returns the faces
    /// separated.
    int32_t cut_along(World& world, Sweep& sweep, Id body_id, const Body& body, const double triangles[18], double edge_length) {
        double rest[18];
        to_rest_all(body, triangles, 6, rest);
        return cut_along_rest(world, sweep, body_id, rest, edge_length);
    }

    /// cut_along with the quad given in the body's rest shape.
    int32_t cut_along_rest(World& world, Sweep& sweep, Id body_id, const double rest[18], double edge_length) {
        refine_body_near(world, body_id, quad_sides(rest).data(), 4, edge_length, &sweep.on_nodes);
        vec<double>& swept = sweep.triangles;
        swept.insert(swept.end(), rest, rest + 18);
        keep_recent(swept);
        sh_cut_report cut{};
        cut_body_at_rest(world, body_id, swept.data(), static_cast<int32_t>(swept.size() / 9), cut, &sweep.on_nodes);
        return cut.faces_separated;
    }

    Sweep& sweep_of(Id tool, Id body) {
        for (Sweep& s : swept_)
            if (s.tool == tool && s.body == body) return s;
        swept_.push_back({tool, body, vec<double>(), vec<int32_t>(), BreakState{}});
        return swept_.back();
    }

    void forget_gone(World& world) {
        for (Sweep& s : swept_)
            if (!world.is_valid_collider(s.tool, true) && world.is_valid(s.body)) release(world.body(s.body), s.breaking);
        swept_.erase(std::remove_if(swept_.begin(), swept_.end(),
                                    [&](const Sweep& s) { return !world.is_valid_collider(s.tool, true) || !world.is_valid(s.body); }),
                     swept_.end());
    }

    vec<Sweep> swept_;
};

void validate(const sh_cut_def& def) {
    SH_REQUIRE(def.criterion >= 0 && def.criterion < SH_CUT_CRITERION_COUNT, SH_ERR_INVALID_ARGUMENT,
               "def->criterion = %d is not an sh_cut_criterion", static_cast<int>(def.criterion));
    for (int e = 0; e < 2; ++e)
        SH_REQUIRE(finite3(def.edge[e]), SH_ERR_INVALID_ARGUMENT, "def->edge[%d] is not finite", e);
    double d[3];
    sub3(def.edge[1], def.edge[0], d);
    SH_REQUIRE(norm3(d) > 0.0, SH_ERR_INVALID_ARGUMENT, "def->edge[0] and def->edge[1] coincide: a blade needs a length");
    SH_REQUIRE(std::isfinite(def.sharpness) && def.sharpness > 0.0, SH_ERR_INVALID_ARGUMENT,
               "def->sharpness = %g, must be finite and > 0", def.sharpness);
    SH_REQUIRE(std::isfinite(def.resolution) && def.resolution >= 0.0, SH_ERR_INVALID_ARGUMENT,
               "def->resolution = %g, must be finite and >= 0", def.resolution);
}

}  // namespace

void set_tool_cutting(World& world, Id id, const sh_cut_def* def) {
    Collider& tool = world.collider(id, true);
    if (def) validate(*def);
    if (def) world.own_hook_once<ToolCutting>(&kCuttingKey);
    tool.cuts = def != nullptr;
    if (def) tool.cutting = *def;
    if (StepHook* hook = world.owned_hook(&kCuttingKey)) static_cast<ToolCutting*>(hook)->forget(world, id);
}

}  // namespace sh
