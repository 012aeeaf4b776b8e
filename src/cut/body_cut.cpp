#include "cut/body_cut.hpp"

#include "core/clock.hpp"
#include "core/vec3.hpp"
#include "cut/cut_surface.hpp"
#include "cut/separation.hpp"
#include "cut/tet_cut.hpp"
#include "model/fem_body.hpp"
#include "model/spring_body.hpp"
#include "world/world.hpp"

namespace sh {
namespace {

void cut_fem(World& world, Id id, FemBody& body, const CutSurface& surface, bool at_rest, sh_cut_report& report) {
    // A surface in the material frame is a tool's growing sweep, cut with again at every step:
    // the quality guard's choices depend on the pieces already there and would not repeat.
    TetCut cut(body, surface, at_rest ? body.rest.data() : body.x.data(), !at_rest);
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
void cut_in_frame(World& world, Id id, const double* triangles, int32_t count, bool at_rest, sh_cut_report& report) {
    const double start = now_seconds();
    Body& body = world.body(id);
    const CutSurface surface(triangles, count);
    report = sh_cut_report{};
    report.min_quality = 1.0;
    if (body.is_fem())
        cut_fem(world, id, static_cast<FemBody&>(body), surface, at_rest, report);
    else
        cut_springs(world, id, static_cast<SpringBody&>(body), surface, at_rest, report);
    report.seconds = now_seconds() - start;
}

}  // namespace

void cut_body(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report) {
    cut_in_frame(world, id, triangles, count, false, report);
}

void cut_body_at_rest(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report) {
    cut_in_frame(world, id, triangles, count, true, report);
}

}  // namespace sh
