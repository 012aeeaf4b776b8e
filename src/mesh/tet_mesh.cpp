#include "mesh/tet_mesh.hpp"

#include "core/error.hpp"
#include "core/log.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace sh {
namespace {

std::string tet_name(const MeshData& data, size_t t) {
    if (t < data.tet_lines.size() && data.tet_lines[t] > 0)
        return format("tet %zu (line %d)", t, data.tet_lines[t]);
    return format("tet %zu", t);
}


void build_edges(TetMesh& mesh) {
    const int32_t tet_count = mesh.tet_count();
    vec<std::array<int32_t, 2>> edges;
    edges.reserve(static_cast<size_t>(tet_count) * 6);
    for (int32_t t = 0; t < tet_count; ++t) {
        const int32_t* tet = &mesh.tets[4 * static_cast<size_t>(t)];
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b)
                edges.push_back({std::min(tet[a], tet[b]), std::max(tet[a], tet[b])});
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    mesh.edges.reserve(edges.size() * 2);
    for (const auto& e : edges) mesh.edges.insert(mesh.edges.end(), e.begin(), e.end());
}

}  // namespace

vec<int32_t> boundary_triangles(const int32_t* tets, size_t tet_count) {
    struct Face {
        std::array<int32_t, 3> key;   // sorted node indices
        std::array<int32_t, 3> nodes; // outward order
    };
    vec<Face> faces;
    faces.reserve(tet_count * 4);
    for (size_t t = 0; t < tet_count; ++t) {
        const int32_t* tet = &tets[4 * t];
        for (const auto& f : kTetFaces) {
            Face face{{tet[f[0]], tet[f[1]], tet[f[2]]}, {tet[f[0]], tet[f[1]], tet[f[2]]}};
            std::sort(face.key.begin(), face.key.end());
            faces.push_back(face);
        }
    }
    std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.key < b.key; });
    vec<int32_t> boundary;
    for (size_t i = 0; i < faces.size();) {
        size_t j = i + 1;
        while (j < faces.size() && faces[j].key == faces[i].key) ++j;
        if (j - i == 1) boundary.insert(boundary.end(), faces[i].nodes.begin(), faces[i].nodes.end());
        i = j;
    }
    return boundary;
}

double tet_quality(const double* a, const double* b, const double* c, const double* d) {
    const double* p[4] = {a, b, c, d};
    double sum_squares = 0.0;
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
            for (int k = 0; k < 3; ++k) sum_squares += (p[i][k] - p[j][k]) * (p[i][k] - p[j][k]);
    const double rms = std::sqrt(sum_squares / 6.0);
    // A regular tet of edge l has volume l^3 / (6 sqrt 2).
    return rms > 0.0 ? 6.0 * std::sqrt(2.0) * signed_tet_volume(a, b, c, d) / (rms * rms * rms) : 0.0;
}

double signed_tet_volume(const double* a, const double* b, const double* c, const double* d) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
            u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0;
}

namespace {

// What building the mesh changed or left out, for the host's log.
void log_repairs(const TetMesh& mesh, const std::string& origin) {
    if (!logging()) return;
    if (mesh.reoriented_tet_count > 0)
        log_message(SH_LOG_INFO, "%s: %d inverted tets reoriented", origin.c_str(), mesh.reoriented_tet_count);
    if (mesh.skipped_element_count > 0)
        log_message(SH_LOG_INFO, "%s: %d elements that are not tets skipped", origin.c_str(), mesh.skipped_element_count);
    if (mesh.orphan_node_count > 0)
        log_message(SH_LOG_INFO, "%s: %d nodes belong to no tet (they stay, with no mass)", origin.c_str(),
                    mesh.orphan_node_count);
}

}  // namespace

TetMesh build_tet_mesh(MeshData data, const std::string& origin) {
    require(data.nodes.size() % 3 == 0 && data.tets.size() % 4 == 0, SH_ERR_INTERNAL,
            origin + ": node or tet array has a partial entry");
    require(data.nodes.size() / 3 <= static_cast<size_t>(std::numeric_limits<int32_t>::max()) &&
                data.tets.size() / 4 <= static_cast<size_t>(std::numeric_limits<int32_t>::max()),
            SH_ERR_DEGENERATE_MESH, origin + ": too many nodes or tets for int32 indices");
    TetMesh mesh;
    mesh.skipped_element_count = data.skipped_elements;
    const int32_t node_count = static_cast<int32_t>(data.nodes.size() / 3);
    const size_t tet_count = data.tets.size() / 4;
    require(tet_count > 0, SH_ERR_DEGENERATE_MESH, origin + ": the mesh has no tetrahedra");

    for (int32_t n = 0; n < node_count; ++n)
        for (int k = 0; k < 3; ++k)
            SH_REQUIRE(std::isfinite(data.nodes[3 * static_cast<size_t>(n) + k]), SH_ERR_DEGENERATE_MESH, "%s: node %d has a non-finite coordinate", origin.c_str(), n);

    // Scale for the zero-volume test: relative to the mesh's bounding box.
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t n = 0; n < node_count; ++n)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], data.nodes[3 * static_cast<size_t>(n) + k]);
            hi[k] = std::max(hi[k], data.nodes[3 * static_cast<size_t>(n) + k]);
        }

    mesh.node_used.assign(static_cast<size_t>(node_count), 0);
    vec<std::array<int32_t, 5>> sorted;  // sorted nodes + tet index, for duplicate detection
    sorted.reserve(tet_count);
    for (size_t t = 0; t < tet_count; ++t) {
        int32_t* tet = &data.tets[4 * t];
        for (int a = 0; a < 4; ++a)
            SH_REQUIRE(tet[a] >= 0 && tet[a] < node_count, SH_ERR_DEGENERATE_MESH, "%s: %s: node index %d out of range [0, %d)", origin.c_str(),
                           tet_name(data, t).c_str(), tet[a], node_count);
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b)
                SH_REQUIRE(tet[a] != tet[b], SH_ERR_DEGENERATE_MESH, "%s: %s repeats node %d", origin.c_str(), tet_name(data, t).c_str(), tet[a]);
        const double* p[4];
        for (int a = 0; a < 4; ++a) p[a] = &data.nodes[3 * static_cast<size_t>(tet[a])];
        double longest = 0.0;
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) {
                const double dx = p[a][0] - p[b][0], dy = p[a][1] - p[b][1], dz = p[a][2] - p[b][2];
                longest = std::max(longest, dx * dx + dy * dy + dz * dz);
            }
        longest = std::sqrt(longest);
        double volume = signed_tet_volume(p[0], p[1], p[2], p[3]);
        // A tet is degenerate when its volume is negligible against a cube of its longest edge.
        SH_REQUIRE(std::fabs(volume) > 1e-12 * longest * longest * longest, SH_ERR_DEGENERATE_MESH, "%s: %s has zero volume (nodes %d %d %d %d)", origin.c_str(),
                       tet_name(data, t).c_str(), tet[0], tet[1], tet[2], tet[3]);
        if (volume < 0) {
            std::swap(tet[2], tet[3]);
            volume = -volume;
            ++mesh.reoriented_tet_count;
        }
        mesh.volume += volume;
        std::array<int32_t, 5> key{tet[0], tet[1], tet[2], tet[3], static_cast<int32_t>(t)};
        std::sort(key.begin(), key.begin() + 4);
        sorted.push_back(key);
        for (int a = 0; a < 4; ++a) mesh.node_used[static_cast<size_t>(tet[a])] = 1;
    }
    std::sort(sorted.begin(), sorted.end());
    for (size_t i = 1; i < sorted.size(); ++i)
        SH_REQUIRE(!std::equal(sorted[i].begin(), sorted[i].begin() + 4, sorted[i - 1].begin()),
                SH_ERR_DEGENERATE_MESH, "%s: %s duplicates %s", origin.c_str(),
                       tet_name(data, static_cast<size_t>(std::max(sorted[i][4], sorted[i - 1][4]))).c_str(),
                       tet_name(data, static_cast<size_t>(std::min(sorted[i][4], sorted[i - 1][4]))).c_str());

    for (int32_t n = 0; n < node_count; ++n) mesh.orphan_node_count += mesh.node_used[static_cast<size_t>(n)] ? 0 : 1;
    for (int k = 0; k < 3; ++k) {
        mesh.bounds_min[k] = node_count ? lo[k] : 0.0;
        mesh.bounds_max[k] = node_count ? hi[k] : 0.0;
    }
    mesh.nodes = std::move(data.nodes);
    mesh.tets = std::move(data.tets);
    mesh.surface_triangles = boundary_triangles(mesh.tets.data(), mesh.tets.size() / 4);
    build_edges(mesh);
    log_repairs(mesh, origin);
    return mesh;
}

}  // namespace sh
