// Buffer: one extraction of the Volumetric Buffer Model, as the sim side hands it to the
// haptic side: the buffer's tets (as force-kernel blocks over local node numbers), its nodes
// with the full model's start and end of step, its surface, and the contact context.
#pragma once

#include "core/id_pool.hpp"
#include "haptic/arena.hpp"
#include "model/tet_block.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

/// Capacities of a context's buffers, from its def.
struct BufferCapacity {
    int32_t tets, nodes;
    int32_t blocks() const { return (tets + kLanes - 1) / kLanes + SH_MATERIAL_COUNT; }  ///< one partial per model
    int32_t triangles() const { return 4 * tets; }  ///< each buffer tet has at most 4 surface faces
    int32_t edges() const { return 12 * tets; }     ///< at most 3 per triangle
    int32_t friction_records() const { return nodes; }  ///< friction contacts per sub-step: one per surface node
};

/// One exchanged buffer. The arrays are carved at creation with the capacities; the counts
/// say how much of them is in use.
struct Buffer {
    Id body = kNullId;       ///< the body it was cut from (0: none near the tool)
    bool tool_alive = true;     ///< false once the tool is destroyed
    int32_t node_count = 0, tet_count = 0, triangle_count = 0, surface_node_count = 0, edge_count = 0;
    int32_t block_begin[SH_MATERIAL_COUNT + 1] = {};  ///< blocks of material model m:
                                                     ///< [block_begin[m], block_begin[m + 1])
    double period = 0.0;          ///< the full-model step the boundary moves across (s); 0 after a
                                  ///< jump (creation, a static solve): the haptic side then
                                  ///< restarts from the full model instead of keeping its state
    double gravity[3] = {};       ///< m/s^2
    double damping_mass = 0.0;       ///< Rayleigh alpha (1/s)
    double damping_stiffness = 0.0;  ///< Rayleigh beta (s)
    double dt_stable = 0.0;          ///< critical explicit step of the buffer's tets (s)
    double runaway_speed = 0.0;      ///< m/s: faster is a fault
    uint32_t warnings = 0;           ///< SH_WARN bits of the extraction (capacity)
    bool has_proxy = false;          ///< proxy_point/normal hold the nearest surface point
    double proxy_point[3] = {}, proxy_normal[3] = {};  ///< outward normal (world)

    TetBlock* blocks = nullptr;   ///< local node numbers
    Mat3L* rotations = nullptr;   ///< per block of a law that keeps rotations (kRotates): its
                                  ///< elements' rotations at x_start, the haptic side's warm start
    int32_t* node_id = nullptr;   ///< body node of each local node, ascending
    double* x_start = nullptr;    ///< full model at the start of its step (3 per node)
    double* x_end = nullptr;      ///< at its end (the boundary's mean velocity across the step
                                  ///< is (x_end - x_start) / period)
    double* inverse_mass = nullptr;  ///< 0 for boundary nodes (driven by the full model)
    double* mass = nullptr;
    int32_t* triangles = nullptr;    ///< 3 local nodes per surface triangle, outward
    int32_t* edges = nullptr;        ///< 2 local nodes per edge of the surface triangles, each once
    double* triangle_size = nullptr; ///< per triangle: its longest edge at rest (m), for
                                     ///< excess_weight, as the full model weighs it
    double* edge_size = nullptr;     ///< per edge: its rest length (m)
    int32_t* surface_nodes = nullptr;
    /// A physical blade's hold (cut/breaking.hpp): the buffer nodes the tool's edge holds
    /// follow the device's tool pose at held_offset (3 each, in the tool's frame), and the
    /// material's pull on them is rendered; held nodes the buffer does not have add their
    /// full-model force and torque (about the tool's position) as they were at extraction.
    int32_t held_count = 0;
    int32_t* held = nullptr;
    double* held_offset = nullptr;
    double held_outside_force[3] = {}, held_outside_torque[3] = {};
    /// The hold's work so far and its price (J), and which hold it is: the haptic side counts
    /// the work on and lets go (renders the drop) once it pays the price, before the full
    /// model breaks the material at its next step.
    double held_work = 0.0, held_needed = 0.0;
    uint64_t held_serial = 0;

    /// Carves the arrays for capacity from arena (or measures them).
    void carve(Arena& arena, const BufferCapacity& capacity) {
        const size_t n = static_cast<size_t>(capacity.nodes);
        blocks = arena.take<TetBlock>(static_cast<size_t>(capacity.blocks()));
        rotations = arena.take<Mat3L>(static_cast<size_t>(capacity.blocks()));
        node_id = arena.take<int32_t>(n);
        x_start = arena.take<double>(3 * n);
        x_end = arena.take<double>(3 * n);
        inverse_mass = arena.take<double>(n);
        mass = arena.take<double>(n);
        triangles = arena.take<int32_t>(3 * static_cast<size_t>(capacity.triangles()));
        edges = arena.take<int32_t>(2 * static_cast<size_t>(capacity.edges()));
        triangle_size = arena.take<double>(static_cast<size_t>(capacity.triangles()));
        edge_size = arena.take<double>(static_cast<size_t>(capacity.edges()));
        surface_nodes = arena.take<int32_t>(n);
        held = arena.take<int32_t>(n);
        held_offset = arena.take<double>(3 * n);
    }
};

}  // namespace sh
