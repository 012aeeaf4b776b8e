// TetMesh: validated tetrahedral mesh with its topology (surface triangles, edges).
#pragma once

#include "core/memory.hpp"

#include <cstdint>
#include <string>

namespace sh {

/// Raw mesh as a loader or the host provides it, before validation.
struct MeshData {
    vec<double> nodes;          ///< 3 per node (m)
    vec<int32_t> tets;          ///< 4 zero-based node indices per tet
    vec<int32_t> tet_lines;     ///< optional: file line of each tet (for messages), or empty
    int32_t skipped_elements = 0;  ///< non-tet elements the loader skipped
};

/// A validated mesh: every tet has positive volume; orphan nodes are kept.
struct TetMesh {
    vec<double> nodes;              ///< 3 per node (m)
    vec<int32_t> tets;              ///< 4 per tet, positively oriented
    vec<int32_t> surface_triangles; ///< 3 per boundary face, outward (counter-clockwise)
    vec<int32_t> edges;             ///< 2 per unique edge, (min, max), sorted
    vec<uint8_t> node_used;         ///< 1 if a tet uses the node, 0 for orphans
    int32_t orphan_node_count = 0;
    int32_t reoriented_tet_count = 0;
    int32_t skipped_element_count = 0;
    double volume = 0.0;
    double bounds_min[3] = {0, 0, 0};
    double bounds_max[3] = {0, 0, 0};

    int32_t node_count() const { return static_cast<int32_t>(nodes.size() / 3); }
    int32_t tet_count() const { return static_cast<int32_t>(tets.size() / 4); }
};

/// Validates data and builds the topology. origin prefixes messages (a file name or
/// "sh_mesh_create"). Throws SH_ERR_DEGENERATE_MESH naming the tet (and its file line) or
/// node for non-finite coordinates, out-of-range or repeated indices, duplicate or
/// zero-volume tets; flips inverted tets and counts them.
TetMesh build_tet_mesh(MeshData data, const std::string& origin);

/// The faces of a tet (corners 0..3) as corner triples, outward for a positively oriented tet.
constexpr int kTetFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

/// The faces of tets[0..tet_count) (4 node indices each, positively oriented) that belong to
/// one tet only, 3 node indices each, outward (counter-clockwise seen from outside).
vec<int32_t> boundary_triangles(const int32_t* tets, size_t tet_count);

/// Shape quality of the tet (a, b, c, d): 6 sqrt(2) V / l_rms^3, 1 for a regular tet, falling
/// to 0 as it flattens, negative when inverted (l_rms: root mean square of its six edges).
double tet_quality(const double* a, const double* b, const double* c, const double* d);

/// Signed volume of the tet (a, b, c, d): positive when (b-a, c-a, d-a) is right-handed.
double signed_tet_volume(const double* a, const double* b, const double* c, const double* d);

}  // namespace sh
