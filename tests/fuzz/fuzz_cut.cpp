// libFuzzer target: sh_body_cut on small bodies, interleaved with sh_world_step. Each input runs
// in a fresh world holding two bodies made from one structured box (0.125 x 0.125 x 0.09375 m,
// 4 x 4 x 3 cubes of 6 tets: 100 nodes, 288 tets; the nodes at z = 0 fixed, gravity on): an FEM
// body and a mass-spring body on the box's edges. They do not touch each other (body contact is
// opt-in), so they share one place.
//
// Input: a setup byte, then up to kMaxOps operations. The setup byte's bit 0 steps the FEM body
// with implicit Euler (else symplectic Euler), bits 1-2 choose its material model (sh_material
// _model). An operation is a control byte c and what it needs:
// - c % 4 = 0, 1 (FEM body) or 2 (mass-spring body): a cut of that body with 1 + (c >> 2) % 8
//   triangles; bit 5 passes a NULL report. A triangle is a shape byte s and its three corners:
//   bits 2k, 2k + 1 of s say where corner k comes from: 0 read here (three coordinates), 1-3 the
//   last, second-last or third-last corner of this cut (repeated corners: degenerate triangles,
//   or triangles welded along an edge, such as a quad's two halves), read here too if the cut
//   has fewer corners so far. A coordinate is one byte b: below 0xF0 the grid coordinate
//   (b - 56) / 1024 m (exact: the box's node planes are at b = 56, 88, 120, ...; the range
//   reaches 0.05 m past the box on each side); 0xF0 and up a special value (kSpecial below: NaN,
//   infinities, huge, tiny, subnormal, -0; a grid value nudged by 1e-13, an ulp or 1e-9,
//   halfway to the next, or scaled by 1e-3 (one more byte); any double (eight more bytes,
//   little-endian)).
// - c % 4 = 3: one sh_world_step of kStepDt[(c >> 2) % 4] (at most kMaxSteps per input).
// An input that ends inside an operation stops there.
//
// After every cut (tests/fuzz/fuzz_check.hpp's violated() aborts otherwise):
// - the status is SH_OK or SH_ERR_INVALID_ARGUMENT: the latter whenever a corner is not finite,
//   never when every triangle is plainly valid (finite, |coordinate| <= 1e3, area well above
//   zero: plainly_valid), and with a message naming "triangles[";
// - refused: the body is as it was (node and element counts, topology_version, mass, positions
//   bit for bit, elements, surface);
// - done: the total mass is the body's initial one (1e-9 relative); no node is lost and the
//   existing ones have not moved (unless the report says nodes_moved); the report's counts match
//   the body's; topology_version grows when the counts change; node parents are -1 for the
//   body's own nodes and below their own index for the others; positions are finite; tets and
//   springs index nodes, a tet's four nodes differ; the surface indexes nodes and is closed (each
//   directed edge matched by its reverse). FEM: the signed volume of the tets at the positions
//   right after the cut (which interpolate the current configuration, the rest shape is not
//   exposed) is what it was (1e-9 of the total absolute volume): a split tet's pieces fill it;
//   and if no tet was near-flat or inverted before the cut, none is after (every piece is an
//   affine image of a piece of positive rest volume).
// After every step: SH_OK or SH_ERR_UNSTABLE, positions finite, masses unchanged.
// Seeds: corpus/cut/ (README.md says what each is).
#include "fuzz_check.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

namespace {

using namespace softhap_fuzz;

constexpr int kCells[3] = {4, 4, 3};      // cubes along x, y, z
constexpr double kCube = 1.0 / 32;        // m: a cube's side, a power of two so node planes are exact
constexpr double kGridStep = 1.0 / 1024;  // m per grid coordinate step
constexpr int kGridOrigin = 56;           // the byte of coordinate 0
constexpr int kMaxOps = 8;
constexpr int kMaxSteps = 3;
constexpr int kBodies = 2;
constexpr double kStepDt[4] = {1e-3, 4e-3, 1.0 / 60.0, 1e-2};  // s
constexpr double kTolerance = 1e-9;       // relative, for mass and volume
constexpr double kFlat = 1e-3;            // a tet with 6 sqrt(2) V / l_rms^3 below this is near-flat

const char* const kBodyNames[kBodies] = {"FEM body", "mass-spring body"};

// ---------------------------------------------------------------------------------------------
// Scene

/// Destroys a world.
struct WorldDeleter {
    void operator()(sh_world* world) const { sh_world_destroy(world); }
};
using WorldPtr = std::unique_ptr<sh_world, WorldDeleter>;

/// Requires status SH_OK from a call that builds the scene or reads a body.
void require_ok(sh_status status, const char* what) {
    if (status != SH_OK) violated(what, std::string(sh_status_string(status)) + ": " + sh_last_error_message());
}

/// The box mesh, made once: node (i, j, k) at kCube (i, j, k), index (k (ny + 1) + j) (nx + 1) + i;
/// each cube split into 6 tets around its diagonal from corner 0 to corner 6 (as
/// tests/support/box_mesh.c does, so neighbouring cubes conform).
const sh_mesh* box_mesh() {
    static const MeshPtr mesh = [] {
        const int px = kCells[0] + 1, py = kCells[1] + 1, pz = kCells[2] + 1;
        std::vector<double> nodes;
        for (int k = 0; k < pz; ++k)
            for (int j = 0; j < py; ++j)
                for (int i = 0; i < px; ++i)
                    for (const int c : {i, j, k}) nodes.push_back(kCube * c);
        static const int kKuhn[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
        std::vector<int32_t> tets;
        for (int k = 0; k < kCells[2]; ++k)
            for (int j = 0; j < kCells[1]; ++j)
                for (int i = 0; i < kCells[0]; ++i) {
                    const int32_t o = (k * py + j) * px + i, up = px * py;
                    const int32_t corner[8] = {o, o + 1, o + px + 1, o + px, o + up, o + up + 1, o + up + px + 1, o + up + px};
                    for (const auto& tet : kKuhn)
                        for (const int c : tet) tets.push_back(corner[c]);
                }
        sh_mesh* made = nullptr;
        require_ok(sh_mesh_create(nodes.data(), px * py * pz, tets.data(), static_cast<int32_t>(tets.size() / 4), &made),
                   "cannot make the box mesh");
        return MeshPtr(made);
    }();
    return mesh.get();
}

/// The world and its bodies (the FEM body, the mass-spring body), with what a cut must keep: each
/// body's mass and its own node count.
struct Scene {
    WorldPtr world;
    sh_body_id bodies[kBodies] = {};
    double mass[kBodies] = {};
    int32_t own_nodes[kBodies] = {};
};

/// Fixes the box's nodes at z = 0 (the first (nx + 1) (ny + 1)) of body.
void fix_base(sh_world* world, sh_body_id body) {
    std::vector<int32_t> base(static_cast<size_t>((kCells[0] + 1) * (kCells[1] + 1)));
    for (size_t i = 0; i < base.size(); ++i) base[i] = static_cast<int32_t>(i);
    require_ok(sh_body_fix_nodes(world, body, base.data(), static_cast<int32_t>(base.size())), "cannot fix the base");
}

/// A fresh world with the two bodies (see the header); setup is the input's first byte.
Scene make_scene(uint8_t setup) {
    Scene scene;
    sh_world_def world_def;
    sh_world_def_default(&world_def);
    sh_world* world = nullptr;
    require_ok(sh_world_create(&world_def, &world), "cannot make the world");
    scene.world.reset(world);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = box_mesh();
    def.integrator = setup & 1 ? SH_INTEGRATOR_IMPLICIT_EULER : SH_INTEGRATOR_SYMPLECTIC_EULER;
    def.material.model = static_cast<sh_material_model>((setup >> 1) % SH_MATERIAL_COUNT);
    require_ok(sh_fem_body_create(world, &def, &scene.bodies[0]), "cannot make the FEM body");
    sh_spring_body_def springs;
    sh_spring_body_def_default(&springs);
    springs.mesh = box_mesh();
    require_ok(sh_spring_body_create(world, &springs, &scene.bodies[1]), "cannot make the mass-spring body");
    for (int b = 0; b < kBodies; ++b) {
        fix_base(world, scene.bodies[b]);
        sh_body_info info;
        require_ok(sh_body_get_info(world, scene.bodies[b], &info), "cannot read a body's info");
        scene.mass[b] = info.total_mass;
        scene.own_nodes[b] = info.node_count;
    }
    return scene;
}

// ---------------------------------------------------------------------------------------------
// Decoding

/// Reads the input front to back; a read past its end fails.
class Reader {
public:
    Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}

    /// The next byte, if any.
    bool byte(uint8_t& out) {
        if (at_ == size_) return false;
        out = data_[at_++];
        return true;
    }

    /// The next n bytes, if there are that many.
    bool bytes(void* out, size_t n) {
        if (size_ - at_ < n) return false;
        std::memcpy(out, data_ + at_, n);
        at_ += n;
        return true;
    }

private:
    const uint8_t* data_;
    size_t size_, at_ = 0;
};

/// The grid coordinate of byte b (m).
double grid(uint8_t b) { return (b - kGridOrigin) * kGridStep; }

/// Special coordinates, bytes 0xF0 to 0xF9.
const double kSpecial[] = {std::numeric_limits<double>::quiet_NaN(), INFINITY, -INFINITY, 1e300, -1e300, 1e-300,
                           std::numeric_limits<double>::denorm_min(), -0.0, DBL_MAX, 1e6};

/// One coordinate (see the header): 0xFA-0xFE read one byte more, 0xFF eight.
bool coordinate(Reader& in, double& out) {
    uint8_t b = 0, next = 0;
    if (!in.byte(b)) return false;
    if (b < 0xF0) {
        out = grid(b);
        return true;
    }
    if (b < 0xFA) {
        out = kSpecial[b - 0xF0];
        return true;
    }
    if (b == 0xFF) return in.bytes(&out, sizeof out);
    if (!in.byte(next)) return false;
    switch (b) {
        case 0xFA: out = grid(next) + 1e-13; break;                  // a hair past a grid value
        case 0xFB: out = std::nextafter(grid(next), -INFINITY); break; // one ulp below it
        case 0xFC: out = grid(next) - 1e-9; break;
        case 0xFD: out = grid(next) + kGridStep * 0.5; break;        // between two grid values
        default: out = grid(next) * 1e-3; break;                     // 0xFE: near the origin
    }
    return true;
}

/// Reads the triangles of one cut (count of them, 9 doubles each) into triangles.
bool read_triangles(Reader& in, int count, std::vector<double>& triangles) {
    std::vector<std::array<double, 3>> corners;  // of this cut, in order
    for (int t = 0; t < count; ++t) {
        uint8_t shape = 0;
        if (!in.byte(shape)) return false;
        for (int k = 0; k < 3; ++k) {
            const int source = (shape >> (2 * k)) & 3;
            std::array<double, 3> p{};
            if (source > 0 && static_cast<size_t>(source) <= corners.size()) {
                p = corners[corners.size() - static_cast<size_t>(source)];
            } else {
                for (double& c : p)
                    if (!coordinate(in, c)) return false;
            }
            corners.push_back(p);
            triangles.insert(triangles.end(), p.begin(), p.end());
        }
    }
    return true;
}

// ---------------------------------------------------------------------------------------------
// Body state

/// What a body looks like at one moment, through the C API.
struct Snapshot {
    sh_body_info info{};
    std::vector<double> x;          // positions
    std::vector<int32_t> elements;  // tets (4 each) or springs (2 each)
    std::vector<int32_t> surface;   // FEM: surface triangles
};

/// Reads body's info, positions, elements and surface.
Snapshot snapshot(const sh_world* world, sh_body_id body) {
    Snapshot s;
    require_ok(sh_body_get_info(world, body, &s.info), "cannot read a body's info");
    const int32_t n = s.info.node_count, e = s.info.element_count;
    s.x.resize(3 * static_cast<size_t>(n));
    require_ok(sh_body_get_positions(world, body, s.x.data(), n), "cannot read positions");
    s.elements.resize((s.info.is_fem ? 4 : 2) * static_cast<size_t>(e));
    if (s.info.is_fem) {
        require_ok(sh_body_get_tets(world, body, s.elements.data(), e), "cannot read the tets");
        s.surface.resize(3 * static_cast<size_t>(s.info.surface_triangle_count));
        require_ok(sh_body_get_surface_triangles(world, body, s.surface.data(), s.info.surface_triangle_count),
                   "cannot read the surface");
    } else {
        require_ok(sh_body_get_springs(world, body, s.elements.data(), e), "cannot read the springs");
        if (s.info.surface_triangle_count != 0) violated("a mass-spring body has surface triangles", "");
    }
    return s;
}

/// Signed volume of tet t of s (m^3).
double tet_volume(const Snapshot& s, size_t t, double* rms_edge) {
    const double* p[4];
    for (int a = 0; a < 4; ++a) p[a] = &s.x[3 * static_cast<size_t>(s.elements[4 * t + a])];
    double e[3][3], squares = 0.0;
    for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) e[a][k] = p[a + 1][k] - p[0][k];
    for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b)
            for (int k = 0; k < 3; ++k) squares += (p[b][k] - p[a][k]) * (p[b][k] - p[a][k]);
    *rms_edge = std::sqrt(squares / 6.0);
    return (e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
            e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) / 6.0;
}

/// Totals of the tets' signed volumes at s's positions.
struct Volumes {
    double sum = 0.0, absolute = 0.0;
    double min_quality = INFINITY;  // 6 sqrt(2) V / l_rms^3, negative for an inverted tet
    size_t worst = 0;               // the tet of min_quality
};

/// The volumes of s's tets.
Volumes volumes(const Snapshot& s) {
    Volumes v;
    for (size_t t = 0; t < s.elements.size() / 4; ++t) {
        double rms = 0.0;
        const double volume = tet_volume(s, t, &rms);
        v.sum += volume;
        v.absolute += std::fabs(volume);
        const double quality = 6.0 * std::sqrt(2.0) * volume / (rms * rms * rms);
        if (!(quality >= v.min_quality)) v.min_quality = quality, v.worst = t;
    }
    return v;
}

// ---------------------------------------------------------------------------------------------
// Checks

/// Body b's name and the detail of a violation.
std::string about(int b, const std::string& detail) { return std::string(kBodyNames[b]) + ": " + detail; }

/// Every position finite.
void check_finite(int b, const Snapshot& s) {
    for (size_t i = 0; i < s.x.size(); ++i)
        if (!std::isfinite(s.x[i])) violated("a position is not finite", about(b, "node " + std::to_string(i / 3)));
}

/// The body's mass is its initial one.
void check_mass(const Scene& scene, int b, const Snapshot& s) {
    if (!(std::fabs(s.info.total_mass - scene.mass[b]) <= kTolerance * scene.mass[b]))
        violated("the total mass changed", about(b, std::to_string(scene.mass[b]) + " kg became " + std::to_string(s.info.total_mass)));
}

/// Elements index nodes; a tet's four nodes differ, as do a spring's two.
void check_elements(int b, const Snapshot& s) {
    const size_t per = s.info.is_fem ? 4 : 2;
    for (size_t e = 0; e < s.elements.size(); e += per)
        for (size_t a = 0; a < per; ++a) {
            const int32_t node = s.elements[e + a];
            if (node < 0 || node >= s.info.node_count)
                violated("an element indexes no node", about(b, "element " + std::to_string(e / per) + ": " + std::to_string(node)));
            for (size_t c = 0; c < a; ++c)
                if (s.elements[e + c] == node) violated("an element repeats a node", about(b, "element " + std::to_string(e / per)));
        }
}

/// The surface indexes nodes and is closed: every directed edge a->b is matched by as many b->a.
void check_surface(int b, const Snapshot& s) {
    std::vector<std::pair<int32_t, int32_t>> forward, backward;
    for (size_t t = 0; t < s.surface.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const int32_t from = s.surface[t + k], to = s.surface[t + (k + 1) % 3];
            if (from < 0 || from >= s.info.node_count)
                violated("a surface triangle indexes no node", about(b, std::to_string(from)));
            forward.emplace_back(from, to);
            backward.emplace_back(to, from);
        }
    std::sort(forward.begin(), forward.end());
    std::sort(backward.begin(), backward.end());
    if (forward != backward) violated("the surface is not closed", about(b, std::to_string(s.surface.size() / 3) + " triangles"));
}

/// Node parents: -1 for the body's own nodes, in [0, own index) for the nodes a cut made.
void check_parents(const Scene& scene, int b, const Snapshot& s) {
    std::vector<int32_t> parents(static_cast<size_t>(s.info.node_count));
    require_ok(sh_body_get_node_parents(scene.world.get(), scene.bodies[b], parents.data(), s.info.node_count),
               "cannot read node parents");
    for (int32_t i = 0; i < s.info.node_count; ++i) {
        const int32_t p = parents[static_cast<size_t>(i)];
        const bool ok = i < scene.own_nodes[b] ? p == -1 : p >= 0 && p < i;
        if (!ok) violated("a node's parent is wrong", about(b, "node " + std::to_string(i) + " has parent " + std::to_string(p)));
    }
}

/// A refused cut left the body as it was.
void check_unchanged(int b, const Snapshot& before, const Snapshot& after) {
    const bool same = before.info.node_count == after.info.node_count &&
                      before.info.element_count == after.info.element_count &&
                      before.info.topology_version == after.info.topology_version &&
                      before.info.surface_triangle_count == after.info.surface_triangle_count &&
                      std::memcmp(&before.info.total_mass, &after.info.total_mass, sizeof(double)) == 0 &&
                      std::memcmp(before.x.data(), after.x.data(), before.x.size() * sizeof(double)) == 0 &&
                      before.elements == after.elements && before.surface == after.surface;
    if (!same) violated("a refused cut changed the body", kBodyNames[b]);
}

/// The report of a cut matches what happened to the body.
void check_report(int b, const Snapshot& before, const Snapshot& after, const sh_cut_report& r) {
    const int32_t nodes_added = after.info.node_count - before.info.node_count;
    const int32_t elements_added = after.info.element_count - before.info.element_count;
    const bool counts = r.nodes_added == nodes_added && (before.info.is_fem ? r.tets_added == elements_added && r.springs_cut == 0
                                                                           : r.springs_cut == -elements_added && r.tets_added == 0);
    if (!counts)
        violated("the cut report's counts are not the body's",
                 about(b, "report nodes +" + std::to_string(r.nodes_added) + " tets +" + std::to_string(r.tets_added) +
                              " springs -" + std::to_string(r.springs_cut) + "; body nodes +" + std::to_string(nodes_added) +
                              " elements +" + std::to_string(elements_added)));
    if (!(r.min_quality > 0.0 && r.min_quality <= 1.0 + 1e-12) || !(r.seconds >= 0.0 && std::isfinite(r.seconds)) ||
        r.faces_separated < 0 || r.nodes_moved < 0 || r.reserved != 0)
        violated("the cut report is out of range", about(b, "min_quality " + std::to_string(r.min_quality) + ", seconds " +
                                                                std::to_string(r.seconds)));
}

/// Node and element counts move the right way, topology_version with them, old nodes stay put.
void check_growth(int b, const Snapshot& before, const Snapshot& after, const sh_cut_report* r) {
    const sh_body_info &i0 = before.info, &i1 = after.info;
    if (i1.node_count < i0.node_count || (i0.is_fem ? i1.element_count < i0.element_count : i1.element_count > i0.element_count) ||
        (!i0.is_fem && i1.node_count != i0.node_count))
        violated("a cut lost nodes or tets, or added springs", kBodyNames[b]);
    const bool changed = i1.node_count != i0.node_count || i1.element_count != i0.element_count;
    if (i1.topology_version < i0.topology_version || (changed && i1.topology_version == i0.topology_version))
        violated("topology_version did not follow the cut", about(b, std::to_string(i0.topology_version) + " -> " +
                                                                        std::to_string(i1.topology_version)));
    if ((!r || r->nodes_moved == 0) && std::memcmp(before.x.data(), after.x.data(), before.x.size() * sizeof(double)) != 0)
        violated("a cut moved existing nodes", kBodyNames[b]);
}

/// FEM: the tets still fill the same signed volume, and none is inverted unless one was before.
void check_volumes(int b, const Snapshot& before, const Snapshot& after) {
    const Volumes v0 = volumes(before), v1 = volumes(after);
    if (!(std::fabs(v1.sum - v0.sum) <= kTolerance * v0.absolute))
        violated("a cut changed the tets' signed volume", about(b, std::to_string(v0.sum) + " m^3 became " + std::to_string(v1.sum)));
    if (v0.min_quality >= kFlat && !(v1.min_quality > 0.0))
        violated("a cut of a body with no flat or inverted tet made an inverted tet",
                 about(b, "tet " + std::to_string(v1.worst) + ", quality " + std::to_string(v1.min_quality)));
}

/// Everything a cut that returned SH_OK must leave (see the header).
void check_done(const Scene& scene, int b, const Snapshot& before, const Snapshot& after, const sh_cut_report* r) {
    check_mass(scene, b, after);
    check_growth(b, before, after, r);
    if (r) check_report(b, before, after, *r);
    check_parents(scene, b, after);
    check_finite(b, after);
    check_elements(b, after);
    if (after.info.is_fem) {
        check_surface(b, after);
        check_volumes(b, before, after);
    }
}

/// True if every triangle is finite, within 1e3 m of the origin and far from degenerate: a cut
/// with it must be accepted.
bool plainly_valid(const std::vector<double>& triangles) {
    for (size_t t = 0; t < triangles.size(); t += 9) {
        const double* p = &triangles[t];
        double e[3][3], longest = 0.0;
        for (int a = 0; a < 3; ++a) {
            for (int k = 0; k < 3; ++k) {
                if (!(std::fabs(p[3 * a + k]) <= 1e3)) return false;
                e[a][k] = p[3 * ((a + 1) % 3) + k] - p[3 * a + k];
            }
            longest = std::max(longest, e[a][0] * e[a][0] + e[a][1] * e[a][1] + e[a][2] * e[a][2]);
        }
        const double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                             e[0][0] * e[1][1] - e[0][1] * e[1][0]};
        if (!(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) >= 1e-6 * longest && longest >= 1e-12)) return false;
    }
    return true;
}

/// The status fits the triangles: SH_OK or SH_ERR_INVALID_ARGUMENT, the latter iff a corner is
/// not finite, or for some triangle that is not plainly valid.
void check_status(int b, sh_status status, const std::vector<double>& triangles) {
    const std::string detail = about(b, std::string(sh_status_string(status)) + ": " + sh_last_error_message());
    if (status != SH_OK && status != SH_ERR_INVALID_ARGUMENT) violated("a cut failed with a status other than invalid argument", detail);
    const bool finite = std::all_of(triangles.begin(), triangles.end(), [](double c) { return std::isfinite(c); });
    if (!finite && status == SH_OK) violated("a cut with a non-finite corner was accepted", kBodyNames[b]);
    if (status == SH_ERR_INVALID_ARGUMENT && plainly_valid(triangles)) violated("a cut with plainly valid triangles was refused", detail);
    if (status == SH_ERR_INVALID_ARGUMENT && std::string(sh_last_error_message()).find("triangles[") == std::string::npos)
        violated("a refused cut's message does not name the triangle", detail);
}

// ---------------------------------------------------------------------------------------------
// Operations

/// One cut of body b (see the header for c), checked. False if the input ended first.
bool cut(Scene& scene, int b, uint8_t c, Reader& in) {
    std::vector<double> triangles;
    if (!read_triangles(in, 1 + (c >> 2) % 8, triangles)) return false;
    const Snapshot before = snapshot(scene.world.get(), scene.bodies[b]);
    sh_cut_report report{};
    const bool want_report = ((c >> 5) & 1) == 0;
    const sh_status status = sh_body_cut(scene.world.get(), scene.bodies[b], triangles.data(),
                                         static_cast<int32_t>(triangles.size() / 9), want_report ? &report : nullptr);
    check_status(b, status, triangles);
    const Snapshot after = snapshot(scene.world.get(), scene.bodies[b]);
    if (status == SH_OK)
        check_done(scene, b, before, after, want_report ? &report : nullptr);
    else
        check_unchanged(b, before, after);
    return true;
}

/// One step of the world, checked.
void step(Scene& scene, double dt) {
    const sh_status status = sh_world_step(scene.world.get(), dt, nullptr);
    if (status != SH_OK && status != SH_ERR_UNSTABLE)
        violated("a step failed with a status other than unstable",
                 std::string(sh_status_string(status)) + ": " + sh_last_error_message());
    for (int b = 0; b < kBodies; ++b) {
        const Snapshot s = snapshot(scene.world.get(), scene.bodies[b]);
        check_finite(b, s);
        check_mass(scene, b, s);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    Reader in(data, size);
    uint8_t setup = 0, c = 0;
    if (!in.byte(setup)) return 0;
    Scene scene = make_scene(setup);
    int steps = 0;
    for (int op = 0; op < kMaxOps && in.byte(c); ++op) {
        if (c % 4 == 3) {
            if (steps++ < kMaxSteps) step(scene, kStepDt[(c >> 2) % 4]);
        } else if (!cut(scene, c % 4 == 2 ? 1 : 0, c, in)) {
            break;
        }
    }
    return 0;
}
