#include "cut/body_cut.hpp"

#include "core/clock.hpp"
#include "core/vec3.hpp"
#include "cut/cut_surface.hpp"
#include "cut/refinement.hpp"
#include "cut/separation.hpp"
#include "cut/tet_cut.hpp"
#include "model/fem_body.hpp"
#include "model/spring_body.hpp"
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
             vec<int32_t>* on_nodes) {
    // A surface in the material frame is a tool's growing sweep, cut with again at every step;
    // the nodes it went through (on_nodes) keep the quality guard's earlier choices.
    TetCut cut(body, surface, at_rest ? body.rest.data() : body.x.data(), true, on_nodes);
    const int32_t node_count = body.node_count(), tet_count = body.element_count();
    report.faces_separated = separate(cut, node_count);
    report.min_quality = cut.min_quality;
    if (cut.origins.empty() && cut.split_count == 0) return;  // the surface missed the body
    TopologyScratch prepared;
    world.prepare_topology_change(id, node_count + static_cast<int32_t>(cut.origins.size()), prepared);
    body.retopologize(cut.origins.data(), cut.origins.size(), std::move(cut.tets), cut.source);
    world.topology_changed(id, prepared);
    report.nodes_added = body.node_count() - node_count;
    report.tets_added = body.element_count() - tet_count;
    if (on_nodes) {
        on_nodes->insert(on_nodes->end(), cut.cut_nodes.begin(), cut.cut_nodes.end());
        std::sort(on_nodes->begin(), on_nodes->end());
        on_nodes->erase(std::unique(on_nodes->begin(), on_nodes->end()), on_nodes->end());
        extend_on_nodes(*on_nodes, cut.origins, node_count);  // the copies of nodes on the cut
    }
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

/// Cuts body id along triangles given against its current (at_rest false) or rest positions.
void cut_in_frame(World& world, Id id, const double* triangles, int32_t count, bool at_rest, sh_cut_report& report,
                  vec<int32_t>* on_nodes) {
    const double start = now_seconds();
    Body& body = world.body(id);
    const CutSurface surface(triangles, count);
    report = sh_cut_report{};
    report.min_quality = 1.0;
    if (body.is_fem())
        cut_fem(world, id, static_cast<FemBody&>(body), surface, at_rest, report, on_nodes);
    else
        cut_springs(world, id, static_cast<SpringBody&>(body), surface, at_rest, report);
    report.seconds = now_seconds() - start;
}

}  // namespace

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
    cut_in_frame(world, id, triangles, count, false, report, nullptr);
}

void cut_body_at_rest(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report,
                      vec<int32_t>* on_nodes) {
    cut_in_frame(world, id, triangles, count, true, report, on_nodes);
}

}  // namespace sh
