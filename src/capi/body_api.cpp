// C API: body state, boundary conditions, loads and queries.
#include "capi/guard.hpp"
#include "capi/world_handle.hpp"
#include "material/material_params.hpp"
#include "mesh/io/mesh_io.hpp"
#include "solver/integrator_table.hpp"
#include "model/fem_body.hpp"

#include <algorithm>
#include <cmath>

using namespace sh;

namespace {

Body& body_of(const sh_world* world, sh_body_id id) { return capi::world_of(world).body(id.value); }

void require_node_count(const Body& body, int32_t node_count) {
    SH_REQUIRE(node_count == body.node_count(), SH_ERR_INVALID_ARGUMENT, "node_count = %d, the body has %d nodes", node_count, body.node_count());
}

void require_all_finite(const double* values, size_t count, const char* name) {
    capi::require_pointer(values, name);
    for (size_t i = 0; i < count; ++i)
        SH_REQUIRE(std::isfinite(values[i]), SH_ERR_INVALID_ARGUMENT, "%s[%zu] (node %zu) is not finite", name, i, i / 3);
}

void require_node_indices(const Body& body, const int32_t* nodes, int32_t count) {
    SH_REQUIRE(count >= 0, SH_ERR_INVALID_ARGUMENT, "count = %d, must be >= 0", count);
    if (count > 0) capi::require_pointer(nodes, "nodes");
    for (int32_t k = 0; k < count; ++k)
        SH_REQUIRE(nodes[k] >= 0 && nodes[k] < body.node_count(), SH_ERR_INVALID_ARGUMENT, "nodes[%d] = %d is not a node index in [0, %d)", k, nodes[k], body.node_count());
}

}  // namespace

extern "C" {

SH_API sh_status sh_body_set_material(sh_world* world, sh_body_id body, const int32_t* elements, int32_t element_count,
                                      const sh_material* material) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        w.body(body.value);  // validates the id first
        capi::require_initialised(material, "material");
        validate_material(*material, "sh_body_set_material");
        SH_REQUIRE(element_count >= 0, SH_ERR_INVALID_ARGUMENT, "element_count = %d, must be >= 0", element_count);
        if (element_count > 0) capi::require_pointer(elements, "elements");
        w.set_material(body.value, elements, element_count, *material);
    });
}

SH_API sh_status sh_body_destroy(sh_world* world, sh_body_id body) {
    return capi::guard([&] { capi::world_of(world).remove_body(body.value); });
}

SH_API int32_t sh_body_is_valid(const sh_world* world, sh_body_id body) {
    int32_t valid = 0;
    capi::guard([&] { valid = capi::world_of(world).is_valid(body.value) ? 1 : 0; });
    return valid;
}

SH_API sh_status sh_body_get_info(const sh_world* world, sh_body_id body, sh_body_info* out_info) {
    return capi::guard([&] {
        const Body& b = body_of(world, body);
        capi::require_pointer(out_info, "out_info");
        sh_body_info info{};
        info.node_count = b.node_count();
        info.element_count = b.element_count();
        info.is_fem = b.is_fem() ? 1 : 0;
        for (int32_t i = 0; i < b.node_count(); ++i) {
            info.fixed_node_count += b.kinematic[static_cast<size_t>(i)] ? 1 : 0;
            info.total_mass += b.mass[static_cast<size_t>(i)];
        }
        info.dt_critical = critical_step(b, capi::world_of(world).step_settings(body.value).integrator);
        info.surface_triangle_count = static_cast<int32_t>(b.surface_triangles.size() / 3);
        info.topology_version = b.topology_version;
        *out_info = info;
    });
}

SH_API sh_status sh_body_get_positions(const sh_world* world, sh_body_id body, double* out_positions, int32_t capacity) {
    return capi::guard([&] { capi::copy_out(body_of(world, body).x, 3, out_positions, capacity, "out_positions", "nodes"); });
}

SH_API sh_status sh_body_get_velocities(const sh_world* world, sh_body_id body, double* out_velocities,
                                        int32_t capacity) {
    return capi::guard([&] { capi::copy_out(body_of(world, body).v, 3, out_velocities, capacity, "out_velocities", "nodes"); });
}

SH_API sh_status sh_body_get_masses(const sh_world* world, sh_body_id body, double* out_masses, int32_t capacity) {
    return capi::guard([&] { capi::copy_out(body_of(world, body).mass, 1, out_masses, capacity, "out_masses", "nodes"); });
}

SH_API sh_status sh_body_set_positions(sh_world* world, sh_body_id body, const double* positions, int32_t node_count) {
    return capi::guard([&] {
        Body& b = body_of(world, body);
        require_node_count(b, node_count);
        require_all_finite(positions, b.x.size(), "positions");
        b.set_positions(positions);
    });
}

SH_API sh_status sh_body_set_velocities(sh_world* world, sh_body_id body, const double* velocities, int32_t node_count) {
    return capi::guard([&] {
        Body& b = body_of(world, body);
        require_node_count(b, node_count);
        require_all_finite(velocities, b.v.size(), "velocities");
        b.set_velocities(velocities);
    });
}

SH_API sh_status sh_body_fix_nodes(sh_world* world, sh_body_id body, const int32_t* nodes, int32_t count) {
    return capi::guard([&] {
        Body& b = body_of(world, body);
        require_node_indices(b, nodes, count);
        b.fix_nodes(nodes, count);
    });
}

SH_API sh_status sh_body_release_nodes(sh_world* world, sh_body_id body, const int32_t* nodes, int32_t count) {
    return capi::guard([&] {
        Body& b = body_of(world, body);
        require_node_indices(b, nodes, count);
        b.release_nodes(nodes, count);
    });
}

SH_API sh_status sh_body_prescribe_positions(sh_world* world, sh_body_id body, const int32_t* nodes,
                                             const double* positions, int32_t count) {
    return capi::guard([&] {
        Body& b = body_of(world, body);
        require_node_indices(b, nodes, count);
        if (count > 0) require_all_finite(positions, 3 * static_cast<size_t>(count), "positions");
        b.prescribe_positions(nodes, positions, count);
    });
}

SH_API sh_status sh_body_set_external_forces(sh_world* world, sh_body_id body, const double* forces, int32_t node_count) {
    return capi::guard([&] {
        Body& b = body_of(world, body);
        if (!forces) {
            std::fill(b.external_force.begin(), b.external_force.end(), 0.0);
            return;
        }
        require_node_count(b, node_count);
        require_all_finite(forces, b.external_force.size(), "forces");
        std::copy(forces, forces + b.external_force.size(), b.external_force.begin());
    });
}

SH_API sh_status sh_body_set_node_damping(sh_world* world, sh_body_id body, const double* coefficients, int32_t node_count) {
    return capi::guard([&] {
        Body& b = body_of(world, body);
        if (coefficients) {
            require_node_count(b, node_count);
            for (int32_t i = 0; i < node_count; ++i)
                SH_REQUIRE(std::isfinite(coefficients[i]) && coefficients[i] >= 0.0, SH_ERR_INVALID_ARGUMENT, "coefficients[%d] = %g 1/s, must be finite and >= 0", i, coefficients[i]);
        }
        b.set_node_damping(coefficients);
    });
}

SH_API sh_status sh_body_get_elastic_forces(const sh_world* world, sh_body_id body, double* out_forces,
                                            int32_t capacity) {
    return capi::guard([&] {
        const Body& b = body_of(world, body);
        capi::require_pointer(out_forces, "out_forces");
        capi::require_capacity(capacity, static_cast<size_t>(b.node_count()), "out_forces", "nodes");
        std::fill(out_forces, out_forces + b.x.size(), 0.0);
        b.add_internal_forces(b.x.data(), nullptr, out_forces);
    });
}

SH_API sh_status sh_body_get_elastic_energy(const sh_world* world, sh_body_id body, double* out_energy) {
    return capi::guard([&] {
        const Body& b = body_of(world, body);
        capi::require_pointer(out_energy, "out_energy");
        *out_energy = b.elastic_energy_recalled(b.x.data());
    });
}

SH_API sh_status sh_body_write_vtu(const sh_world* world, sh_body_id body, const char* path) {
    return capi::guard([&] {
        const Body& b = body_of(world, body);
        capi::require_pointer(path, "path");
        VtuFrame frame;
        frame.points = b.x.data();
        frame.point_count = b.node_count();
        frame.cells = b.element_nodes();
        frame.cell_count = b.element_count();
        frame.nodes_per_cell = b.nodes_per_element();
        frame.point_vectors = b.v.data();
        frame.point_vectors_name = "velocity";
        write_vtu(path, frame);
    });
}

}  // extern "C"
