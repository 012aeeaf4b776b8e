// C API: meshes.
#include "capi/guard.hpp"
#include "capi/handles.hpp"
#include "mesh/io/mesh_io.hpp"
#include "mesh/tet_mesh.hpp"

#include <algorithm>
#include <cmath>

using namespace sh;
using capi::HandleKind;

namespace {

const TetMesh& checked_mesh(const sh_mesh* mesh) { return capi::object_of<TetMesh>(HandleKind::Mesh, mesh, "mesh"); }

sh_mesh* publish(TetMesh&& built) {
    TetMesh* mesh = sh::create<TetMesh>(std::move(built));
    try {
        return static_cast<sh_mesh*>(const_cast<void*>(capi::register_handle(HandleKind::Mesh, mesh)));
    } catch (...) {
        sh::destroy(mesh);
        throw;
    }
}

}  // namespace

namespace sh::capi {
const TetMesh& mesh_of(const sh_mesh* mesh) { return checked_mesh(mesh); }
}  // namespace sh::capi

extern "C" {

SH_API sh_status sh_mesh_create(const double* nodes, int32_t node_count, const int32_t* tets,
                                int32_t tet_count, sh_mesh** out_mesh) {
    return capi::guard([&] {
        capi::require_pointer(out_mesh, "out_mesh");
        *out_mesh = nullptr;
        SH_REQUIRE(node_count > 0, SH_ERR_INVALID_ARGUMENT, "node_count is %d, must be > 0", node_count);
        SH_REQUIRE(tet_count > 0, SH_ERR_INVALID_ARGUMENT, "tet_count is %d, must be > 0", tet_count);
        capi::require_pointer(nodes, "nodes");
        capi::require_pointer(tets, "tets");
        MeshData data;
        data.nodes.assign(nodes, nodes + 3 * static_cast<size_t>(node_count));
        data.tets.assign(tets, tets + 4 * static_cast<size_t>(tet_count));
        *out_mesh = publish(build_tet_mesh(std::move(data), "sh_mesh_create"));
    });
}

SH_API sh_status sh_mesh_load(const char* path, sh_mesh** out_mesh) {
    return capi::guard([&] {
        capi::require_pointer(out_mesh, "out_mesh");
        *out_mesh = nullptr;
        capi::require_pointer(path, "path");
        *out_mesh = publish(build_tet_mesh(load_mesh_file(path), path));
    });
}

SH_API sh_status sh_mesh_transform(const sh_mesh* mesh, double scale, const double translation[3], sh_mesh** out_mesh) {
    return capi::guard([&] {
        capi::require_pointer(out_mesh, "out_mesh");
        *out_mesh = nullptr;
        const TetMesh& source = checked_mesh(mesh);
        SH_REQUIRE(std::isfinite(scale) && scale > 0.0, SH_ERR_INVALID_ARGUMENT, "scale = %g, must be finite and > 0", scale);
        double t[3] = {0.0, 0.0, 0.0};
        if (translation)
            for (int k = 0; k < 3; ++k) {
                capi::require_finite(translation[k], "translation");
                t[k] = translation[k];
            }
        MeshData data;
        data.nodes = source.nodes;
        for (size_t i = 0; i < data.nodes.size(); ++i) data.nodes[i] = scale * data.nodes[i] + t[i % 3];
        data.tets = source.tets;
        data.skipped_elements = source.skipped_element_count;
        TetMesh moved = build_tet_mesh(std::move(data), "sh_mesh_transform");
        moved.reoriented_tet_count = source.reoriented_tet_count;
        *out_mesh = publish(std::move(moved));
    });
}

SH_API sh_status sh_mesh_destroy(sh_mesh* mesh) {
    return capi::guard([&] {
        if (!mesh) return;
        TetMesh* object = static_cast<TetMesh*>(capi::unregister_handle(HandleKind::Mesh, mesh));
        require(object != nullptr, SH_ERR_INVALID_HANDLE, "mesh is not a live object (destroyed twice or never created)");
        sh::destroy(object);
    });
}

SH_API sh_status sh_mesh_get_info(const sh_mesh* mesh, sh_mesh_info* out_info) {
    return capi::guard([&] {
        const TetMesh& m = checked_mesh(mesh);
        capi::require_pointer(out_info, "out_info");
        sh_mesh_info info{};
        info.node_count = m.node_count();
        info.tet_count = m.tet_count();
        info.surface_triangle_count = static_cast<int32_t>(m.surface_triangles.size() / 3);
        info.edge_count = static_cast<int32_t>(m.edges.size() / 2);
        info.orphan_node_count = m.orphan_node_count;
        info.reoriented_tet_count = m.reoriented_tet_count;
        info.skipped_element_count = m.skipped_element_count;
        for (int k = 0; k < 3; ++k) {
            info.bounds_min[k] = m.bounds_min[k];
            info.bounds_max[k] = m.bounds_max[k];
        }
        info.volume = m.volume;
        *out_info = info;
    });
}

SH_API sh_status sh_mesh_get_nodes(const sh_mesh* mesh, double* out_nodes, int32_t capacity) {
    return capi::guard([&] { capi::copy_out(checked_mesh(mesh).nodes, 3, out_nodes, capacity, "out_nodes", "nodes"); });
}

SH_API sh_status sh_mesh_get_tets(const sh_mesh* mesh, int32_t* out_tets, int32_t capacity) {
    return capi::guard([&] { capi::copy_out(checked_mesh(mesh).tets, 4, out_tets, capacity, "out_tets", "tets"); });
}

SH_API sh_status sh_mesh_get_surface_triangles(const sh_mesh* mesh, int32_t* out_triangles, int32_t capacity) {
    return capi::guard([&] {
        capi::copy_out(checked_mesh(mesh).surface_triangles, 3, out_triangles, capacity, "out_triangles", "triangles");
    });
}

SH_API sh_status sh_mesh_get_edges(const sh_mesh* mesh, int32_t* out_edges, int32_t capacity) {
    return capi::guard([&] { capi::copy_out(checked_mesh(mesh).edges, 2, out_edges, capacity, "out_edges", "edges"); });
}

SH_API sh_status sh_mesh_write_vtu(const sh_mesh* mesh, const char* path) {
    return capi::guard([&] {
        const TetMesh& m = checked_mesh(mesh);
        capi::require_pointer(path, "path");
        VtuFrame frame;
        frame.points = m.nodes.data();
        frame.point_count = m.node_count();
        frame.cells = m.tets.data();
        frame.cell_count = m.tet_count();
        frame.nodes_per_cell = 4;
        write_vtu(path, frame);
    });
}

}  // extern "C"
