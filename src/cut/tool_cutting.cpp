#include "cut/tool_cutting.hpp"

#include "contact/collider.hpp"
#include "core/clock.hpp"
#include "core/error.hpp"
#include "core/vec3.hpp"
#include "cut/body_cut.hpp"
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

/// Most triangles of a blade's swept surface kept per body: a blade advancing by at least
/// 1/256 of an element per step still crosses whole elements with what is kept.
constexpr size_t kKeptTriangles = 512;

/// Cuts every body along each cutting tool's swept blade before the step's motion. A blade
/// that advances by less than an element per step crosses each tet bit by bit, so what it
/// swept is kept and cut with whole; it is kept in each body's rest shape (the material
/// frame), where it stays with the material as the body moves, so that cutting again along
/// where the blade has been finds the same faces and shaves nothing off them.
class ToolCutting final : public BeforeMotionHook {
public:
    void before_motion(World& world, sh_step_report& report) override {
        const double start = now_seconds();
        forget_gone(world);
        world.for_each_collider([&](Id id, const Collider& tool) {
            double triangles[18];
            if (!tool.is_tool || !tool.cuts || !swept_blade(tool, triangles)) return;
            world.for_each_body([&](Id body_id, const Body& body) {
                if (!near(body, triangles)) return;  // the blade is away from it
                double rest[18];
                for (int c = 0; c < 6; ++c) to_rest(body, &triangles[3 * c], &rest[3 * c]);
                Sweep& sweep = sweep_of(id, body_id);
                refine_body_near(world, body_id, quad_sides(rest).data(), 4, resolution(tool.cutting), &sweep.on_nodes);
                vec<double>& swept = sweep.triangles;
                swept.insert(swept.end(), rest, rest + 18);
                if (swept.size() > 9 * kKeptTriangles) swept.erase(swept.begin(), swept.end() - 9 * kKeptTriangles);
                sh_cut_report cut{};
                cut_body_at_rest(world, body_id, swept.data(), static_cast<int32_t>(swept.size() / 9), cut, &sweep.on_nodes);
                report.cut_faces += cut.faces_separated;
            });
        });
        report.topology_seconds += now_seconds() - start;
    }

    /// Forgets what tool id's blade swept (it stopped cutting).
    void forget(Id tool) {
        swept_.erase(std::remove_if(swept_.begin(), swept_.end(), [&](const Sweep& s) { return s.tool == tool; }), swept_.end());
    }

private:
    /// What one tool's blade swept through one body, in the body's rest shape.
    struct Sweep {
        Id tool, body;
        vec<double> triangles;  ///< 9 per triangle
        vec<int32_t> on_nodes;  ///< the nodes the cut along it went through, ascending
    };

    Sweep& sweep_of(Id tool, Id body) {
        for (Sweep& s : swept_)
            if (s.tool == tool && s.body == body) return s;
        swept_.push_back({tool, body, vec<double>(), vec<int32_t>()});
        return swept_.back();
    }

    void forget_gone(const World& world) {
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
    if (StepHook* hook = world.owned_hook(&kCuttingKey)) static_cast<ToolCutting*>(hook)->forget(id);
}

}  // namespace sh
