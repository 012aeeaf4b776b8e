#include "cut/body_cut.hpp"

#include "collision/aabb_tree.hpp"
#include "collision/closest_point.hpp"
#include "core/clock.hpp"
#include "core/vec3.hpp"
#include "cut/cut_surface.hpp"
#include "cut/material_frame.hpp"
#include "cut/refinement.hpp"
#include "cut/separation.hpp"
#include "cut/tet_cut.hpp"
#include "model/fem_body.hpp"
#include "model/spring_body.hpp"
#include "world/step_hook.hpp"
#include "world/world.hpp"

#include <algorithm>

namespace sh {
namespace {

/// Adds to on_nodes (ascending) the new nodes numbered from first that origins[k] makes
/// between two of its nodes (or as a copy of one).
void extend_on_nodes(vec<int32_t>& on_nodes, const vec<NodeOrigin>& origins, int32_t first) {
    const auto on = [&](int32_t node) { return std::binary_search(on_nodes.begin(), on_nodes.end(), node); };
    vec<int32_t> added;  // ascending, as the new nodes are numbered
    const auto on_or_added = [&](int32_t node) { return on(node) || std::binary_search(added.begin(), added.end(), node); };
    for (size_t k = 0; k < origins.size(); ++k)
        if (on_or_added(origins[k].a) && on_or_added(origins[k].b)) added.push_back(first + static_cast<int32_t>(k));
    on_nodes.insert(on_nodes.end(), added.begin(), added.end());
    std::sort(on_nodes.begin(), on_nodes.end());
}

void cut_fem(World& world, Id id, FemBody& body, const CutSurface& surface, bool at_rest, sh_cut_report& report,
             vec<int32_t>* on_nodes, const Aabb* focus) {
    // A surface in the material frame is a tool's growing sweep, or a body's kept cuts, cut
    // with again; the nodes it went through (on_nodes) keep the quality guard's earlier choices.
    TetCut cut(body, surface, at_rest ? body.rest.data() : body.x.data(), true, on_nodes, focus);
    const int32_t node_count = body.node_count(), tet_count = body.element_count();
    report.faces_separated = separate(cut, node_count);
    report.min_quality = cut.min_quality;
    if (cut.origins.empty() && cut.split_count == 0) return;  // the surface missed the body
    // The nodes on the cut, grown before the body changes: nothing may fail after it.
    vec<int32_t> grown_on;
    if (on_nodes) {
        grown_on = *on_nodes;
        grown_on.insert(grown_on.end(), cut.cut_nodes.begin(), cut.cut_nodes.end());
        std::sort(grown_on.begin(), grown_on.end());
        grown_on.erase(std::unique(grown_on.begin(), grown_on.end()), grown_on.end());
        extend_on_nodes(grown_on, cut.origins, node_count);  // the copies of nodes on the cut
    }
    TopologyScratch prepared;
    world.prepare_topology_change(id, node_count + static_cast<int32_t>(cut.origins.size()), prepared);
    body.retopologize(cut.origins.data(), cut.origins.size(), std::move(cut.tets), cut.source);
    world.topology_changed(id, prepared);
    report.nodes_added = body.node_count() - node_count;
    report.tets_added = body.element_count() - tet_count;
    if (on_nodes) on_nodes->swap(grown_on);
}

void cut_springs(World& world, Id id, SpringBody& body, const CutSurface& surface, bool at_rest, sh_cut_report& report) {
    const double* frame = at_rest ? body.rest.data() : body.x.data();
    const int32_t count = body.element_count();
    vec<uint8_t> broken(static_cast<size_t>(count), 0);
    bool any = false;
    for (int32_t s = 0; s < count; ++s) {
        const int32_t* ends = body.element_nodes() + 2 * static_cast<size_t>(s);
        double t = 0.0;
        int32_t triangle = -1;
        broken[static_cast<size_t>(s)] = surface.first_hit(at(frame, ends[0]), at(frame, ends[1]), t, triangle);
        any = any || broken[static_cast<size_t>(s)];
    }
    if (!any) return;
    TopologyScratch prepared;
    world.prepare_topology_change(id, body.node_count(), prepared);
    report.springs_cut = body.remove_springs(broken);
    world.topology_changed(id, prepared);
}

/// Cuts body id along surface, given against its current (at_rest false) or rest positions;
/// an FEM body only where the surface's last focus_count triangles are (all of it if 0).
void cut_in_frame(World& world, Id id, const CutSurface& surface, bool at_rest, sh_cut_report& report,
                  vec<int32_t>* on_nodes, int32_t focus_count = 0) {
    const double start = now_seconds();
    Body& body = world.body(id);
    report = sh_cut_report{};
    report.min_quality = 1.0;
    Aabb focus;
    for (int32_t i = surface.triangle_count() - focus_count; i < surface.triangle_count(); ++i)
        for (int c = 0; c < 3; ++c) focus.add(surface.corner(i, c));
    if (body.is_fem())
        cut_fem(world, id, static_cast<FemBody&>(body), surface, at_rest, report, on_nodes, focus_count > 0 ? &focus : nullptr);
    else
        cut_springs(world, id, static_cast<SpringBody&>(body), surface, at_rest, report);
    report.seconds = now_seconds() - start;
}

/// Names the world's memory of programmatic cuts.
const char kKeptCutsKey = 0;

/// The programmatic cuts of each FEM body, in its rest shape, with the nodes they went through
/// (see cut_body). The world owns it once a body has been cut.
class KeptCuts final : public BeforeMotionHook {
public:
    struct Kept {
        Id body;
        vec<double> triangles;  ///< 9 per triangle, rest shape
        vec<int32_t> on_nodes;  ///< ascending
    };

    /// What is kept of body id (an empty entry if nothing), bodies gone forgotten first.
    Kept& of(World& world, Id id) {
        kept_.erase(std::remove_if(kept_.begin(), kept_.end(), [&](const Kept& k) { return !world.is_valid(k.body); }),
                    kept_.end());
        for (Kept& k : kept_)
            if (k.body == id) return k;
        kept_.push_back({id, vec<double>(), vec<int32_t>()});
        return kept_.back();
    }

private:
    vec<Kept> kept_;
};

/// A triangle's centre and unit normal (zero for a flat one); returns about its size (the
/// square root of twice its area; 0 if flat).
double centre_and_normal(const double* t, double c[3], double n[3]) {
    double e0[3], e1[3];
    for (int k = 0; k < 3; ++k) c[k] = (t[k] + t[3 + k] + t[6 + k]) / 3.0, e0[k] = t[3 + k] - t[k], e1[k] = t[6 + k] - t[k];
    cross3(e0, e1, n);
    const double length = norm3(n);
    for (int k = 0; k < 3; ++k) n[k] = length > 0.0 ? n[k] / length : 0.0;
    return std::sqrt(length);
}

/// The triangles of kept (9 doubles each) that a cut along added (count triangles) continues:
/// those near the added ones' box, within 30 degrees of the plane of the added triangle
/// nearest them (by centre), and not lying on the added ones (a cut over an earlier one, which
/// it covers): a blade's earlier strips, not a crossing cut. Each is turned, if need be, to
/// face the way that triangle does (CutSurface orients only across shared edges).
vec<double> continued(const vec<double>& kept, const double* added, int32_t count) {
    constexpr double kCos30 = 0.86602540378443865;
    // A kept triangle whose centre lies within a tenth of its size of the added ones is one
    // they cover (cut along again, mapped to the rest shape anew as the body moved).
    constexpr double kCovered = 0.1;
    Aabb box;
    vec<double> centres(3 * static_cast<size_t>(count)), normals(3 * static_cast<size_t>(count));
    for (int32_t j = 0; j < count; ++j) {
        centre_and_normal(&added[9 * static_cast<size_t>(j)], &centres[3 * static_cast<size_t>(j)], &normals[3 * static_cast<size_t>(j)]);
        for (int c = 0; c < 3; ++c) box.add(&added[9 * static_cast<size_t>(j) + 3 * static_cast<size_t>(c)]);
    }
    vec<double> out;
    for (size_t i = 0; i < kept.size(); i += 9) {
        double c[3], n[3], w[3];
        // Only a triangle within its own size of the added ones' box can continue them (a
        // flat one, which the cut would refuse, continues nothing).
        const double size = centre_and_normal(&kept[i], c, n);
        if (!(size > 0.0) || box.distance2(c) > size * size) continue;
        int32_t nearest = 0;
        double best = INFINITY, on = INFINITY;
        for (int32_t j = 0; j < count; ++j) {
            const double* t = &added[9 * static_cast<size_t>(j)];
            double d[3];
            sub3(&centres[3 * static_cast<size_t>(j)], c, d);
            if (dot3(d, d) < best) best = dot3(d, d), nearest = j;
            on = std::fmin(on, closest_on_triangle(c, t, t + 3, t + 6, w));
        }
        const double facing = dot3(n, &normals[3 * static_cast<size_t>(nearest)]);
        if (std::fabs(facing) < kCos30 || on <= kCovered * size) continue;
        out.insert(out.end(), &kept[i], &kept[i] + 9);
        if (facing < 0.0) std::swap_ranges(out.end() - 6, out.end() - 3, out.end() - 3);
    }
    return out;
}

/// cut_body for an FEM body: along triangles with what its earlier cuts kept, which grows by
/// them only once the cut succeeded.
void cut_fem_keeping(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report) {
    const CutSurface surface(triangles, count);  // bad input is refused before anything changes
    KeptCuts::Kept& kept = world.own_hook_once<KeptCuts>(&kKeptCutsKey).of(world, id);
    vec<double> rest(9 * static_cast<size_t>(count));
    to_rest_all(world.body(id), triangles, 3 * count, rest.data());
    // What is kept after the cut, made before it: nothing may fail once the body changed.
    vec<double> grown = kept.triangles;
    grown.insert(grown.end(), rest.begin(), rest.end());
    keep_recent(grown);
    vec<int32_t> on_nodes = kept.on_nodes;
    vec<double> along = continued(kept.triangles, rest.data(), count);
    if (along.empty()) {
        cut_in_frame(world, id, surface, false, report, &on_nodes);
    } else {
        along.insert(along.end(), rest.begin(), rest.end());
        cut_in_frame(world, id, CutSurface(along.data(), static_cast<int32_t>(along.size() / 9)), true, report, &on_nodes,
                     count);
    }
    kept.triangles.swap(grown);
    kept.on_nodes.swap(on_nodes);
}

}  // namespace

void keep_recent(vec<double>& kept) {
    if (kept.size() > 9 * kKeptCutTriangles) kept.erase(kept.begin(), kept.end() - 9 * kKeptCutTriangles);
}

void refine_body_near(World& world, Id id, const double* segments, int32_t segment_count, double edge_length,
                      vec<int32_t>* on_nodes) {
    Body& found = world.body(id);
    if (!found.is_fem()) return;
    FemBody& body = static_cast<FemBody&>(found);
    // One refinement adds at most about a body's worth of tets, so a misjudged length cannot
    // run away with the memory.
    Refinement refined = refine_near(body, segments, segment_count, edge_length, std::max(body.element_count(), 4096));
    if (refined.origins.empty()) return;
    const int32_t node_count = body.node_count();
    TopologyScratch prepared;
    world.prepare_topology_change(id, node_count + static_cast<int32_t>(refined.origins.size()), prepared);
    body.retopologize(refined.origins.data(), refined.origins.size(), std::move(refined.tets), refined.source);
    world.topology_changed(id, prepared);
    if (on_nodes) extend_on_nodes(*on_nodes, refined.origins, node_count);
}

void cut_body(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report) {
    if (world.body(id).is_fem())
        cut_fem_keeping(world, id, triangles, count, report);
    else
        cut_in_frame(world, id, CutSurface(triangles, count), false, report, nullptr);
}

void cut_body_at_rest(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report,
                      vec<int32_t>* on_nodes, int32_t focus_count) {
    cut_in_frame(world, id, CutSurface(triangles, count), true, report, on_nodes, focus_count);
}

}  // namespace sh
