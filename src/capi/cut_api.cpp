// C API: cutting and the topology queries whose answers a cut changes (tets, springs, surface,
// node parents). Translation only: what a cut does is src/cut's.
#include "capi/guard.hpp"
#include "capi/world_handle.hpp"
#include "cut/body_cut.hpp"
#include "cut/tool_cutting.hpp"
#include "model/body.hpp"

#include <algorithm>

using namespace sh;

namespace {

Body& body_of(const sh_world* world, sh_body_id id) { return capi::world_of(world).body(id.value); }

const char* kind_name(const Body& body) { return body.is_fem() ? "an FEM body" : "a mass-spring body"; }

/// Throws SH_ERR_UNSUPPORTED from function unless body is FEM (want_fem) or mass-spring.
void require_kind(const Body& body, bool want_fem, const char* function) {
    SH_REQUIRE(body.is_fem() == want_fem, SH_ERR_UNSUPPORTED, "%s needs %s; this is %s", function,
               want_fem ? "an FEM body" : "a mass-spring body", kind_name(body));
}

/// Copies the body's element connectivity (tets or springs) into out, room for capacity
/// elements. Element arrays are a raw pointer behind the Body interface, so capi::copy_out
/// (which takes a vector) does not apply.
void copy_elements(const Body& body, int32_t* out, int32_t capacity, const char* name, const char* items) {
    capi::require_pointer(out, name);
    const size_t count = static_cast<size_t>(body.element_count());
    capi::require_capacity(capacity, count, name, items);
    const int32_t* nodes = body.element_nodes();
    std::copy(nodes, nodes + count * static_cast<size_t>(body.nodes_per_element()), out);
}

}  // namespace

extern "C" {

SH_API sh_status sh_body_cut(sh_world* world, sh_body_id body, const double* triangles, int32_t triangle_count,
                             sh_cut_report* out_report) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        w.body(body.value);  // a stale id is reported before the arguments, as elsewhere
        capi::require_pointer(triangles, "triangles");
        SH_REQUIRE(triangle_count >= 1, SH_ERR_INVALID_ARGUMENT, "triangle_count = %d, must be >= 1",
                   triangle_count);
        sh_cut_report report{};
        cut_body(w, body.value, triangles, triangle_count, report);
        // Written only after success: a failed cut leaves the host's report as it was.
        if (out_report) *out_report = report;
    });
}

/// The element getters of one body kind: checks the kind, then copies its connectivity.
static sh_status get_elements(const sh_world* world, sh_body_id body, bool fem, int32_t* out, int32_t capacity,
                              const char* function, const char* name, const char* items) {
    return capi::guard([&] {
        const Body& b = body_of(world, body);
        require_kind(b, fem, function);
        copy_elements(b, out, capacity, name, items);
    });
}

SH_API sh_status sh_body_get_tets(const sh_world* world, sh_body_id body, int32_t* out_tets, int32_t capacity) {
    return get_elements(world, body, true, out_tets, capacity, "sh_body_get_tets", "out_tets", "tets");
}

SH_API sh_status sh_body_get_springs(const sh_world* world, sh_body_id body, int32_t* out_springs,
                                     int32_t capacity) {
    return get_elements(world, body, false, out_springs, capacity, "sh_body_get_springs", "out_springs", "springs");
}

SH_API sh_status sh_body_get_surface_triangles(const sh_world* world, sh_body_id body, int32_t* out_triangles,
                                               int32_t capacity) {
    return capi::guard([&] {
        const Body& b = body_of(world, body);
        require_kind(b, true, "sh_body_get_surface_triangles");
        capi::copy_out(b.surface_triangles, 3, out_triangles, capacity, "out_triangles", "triangles");
    });
}

SH_API sh_status sh_body_get_node_parents(const sh_world* world, sh_body_id body, int32_t* out_parents,
                                          int32_t capacity) {
    return capi::guard([&] {
        const Body& b = body_of(world, body);
        capi::require_pointer(out_parents, "out_parents");
        capi::require_capacity(capacity, static_cast<size_t>(b.node_count()), "out_parents", "nodes");
        // node_parent stays empty until the first topology change; parent_of answers -1 then.
        for (int32_t i = 0; i < b.node_count(); ++i) out_parents[i] = b.parent_of(i);
    });
}

}  // extern "C"

SH_API void sh_cut_def_default(sh_cut_def* def) {
    if (!def) return;
    *def = sh_cut_def{};
    def->internal_init = capi::kDefInitialised;
    def->criterion = SH_CUT_GEOMETRIC;
    def->edge[0][2] = -0.005;
    def->edge[1][2] = 0.005;
    def->sharpness = 1.0;
}

SH_API sh_status sh_tool_set_cutting(sh_world* world, sh_tool_id tool, const sh_cut_def* def) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        if (def) capi::require_initialised(def, "def");
        set_tool_cutting(w, tool.value, def);
    });
}
