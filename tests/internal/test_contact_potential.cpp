// The contact potential of contact/shape_contact.hpp on fixed surface patches, through the
// library's internal functions: forces are minus the gradient of the potential (central
// differences), a tool smaller than the triangles feels exactly the law lambda d^n at its depth
// on a face, an edge or a vertex of a flat patch (a sphere, and a capsule lying on it), a
// contact the mesh resolves is its nodes' own laws, the energy follows the forces' work along
// random paths, a sphere or a capsule sliding at constant height over a curved patch feels a
// force that changes smoothly, a tilting capsule hands its push from one end to the other
// smoothly, and the capsule's tangent matches the forces' slope. Boxes and convex hulls take
// the balls of their largest inscribed capsule between nodes: its size is checked against the
// shape's geometry, and a plate lying between nodes feels the law as the capsule does.
#include "contact/ball_mix.hpp"
#include "contact/collider.hpp"
#include "contact/hunt_crossley.hpp"
#include "contact/shape_contact.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

using sh::Collider;
using sh::ContactPoint;

// A surface patch: nodes, outward triangles, and its edges and nodes, each once.
struct Patch {
    std::vector<double> x;
    std::vector<int32_t> tris, edges, nodes;
};

// Edges and nodes of the triangles, each once.
void finish_patch(Patch& p) {
    for (size_t t = 0; t < p.tris.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            int32_t a = p.tris[t + k], b = p.tris[t + (k + 1) % 3];
            if (a > b) std::swap(a, b);
            bool seen = false;
            for (size_t e = 0; e < p.edges.size(); e += 2) seen |= p.edges[e] == a && p.edges[e + 1] == b;
            if (!seen) {
                p.edges.push_back(a);
                p.edges.push_back(b);
            }
        }
    for (int32_t i = 0; i < static_cast<int32_t>(p.x.size() / 3); ++i) p.nodes.push_back(i);
}

// A hexagonal fan of six triangles of circumradius r around a centre raised by bump (m),
// in the plane z = 0 (bump 0: flat), outward +z.
Patch hexagon(double r, double bump) {
    Patch p;
    p.x = {0.0, 0.0, bump};
    for (int k = 0; k < 6; ++k) {
        p.x.push_back(r * std::cos(k * M_PI / 3.0));
        p.x.push_back(r * std::sin(k * M_PI / 3.0));
        p.x.push_back(0.0);
    }
    for (int k = 0; k < 6; ++k) {
        p.tris.push_back(0);
        p.tris.push_back(1 + k);
        p.tris.push_back(1 + (k + 1) % 6);
    }
    finish_patch(p);
    return p;
}

// Height of the patch over (px, py) (its triangles' linear interpolation), 0 off it.
double surface_height(const Patch& p, double px, double py) {
    for (size_t t = 0; t < p.tris.size(); t += 3) {
        const double* a = &p.x[3 * static_cast<size_t>(p.tris[t])];
        const double* b = &p.x[3 * static_cast<size_t>(p.tris[t + 1])];
        const double* c = &p.x[3 * static_cast<size_t>(p.tris[t + 2])];
        const double det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        const double u = ((px - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (py - a[1])) / det;
        const double v = ((b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1])) / det;
        if (u >= -1e-12 && v >= -1e-12 && u + v <= 1.0 + 1e-12) return a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]);
    }
    return 0.0;
}

// A tilted orientation, so that boxes and capsules meet the patch off their axes.
const double kTilted[4] = {std::cos(0.3), std::sin(0.3) * 0.6, std::sin(0.3) * 0.8, 0.0};

Collider make_collider(sh_shape_kind kind, const double position[3], double size, const double* orientation = kTilted) {
    static const double cube[8][3] = {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1},
                                      {-1, -1, 1},  {1, -1, 1},  {-1, 1, 1},  {1, 1, 1}};
    static double points[8][3];
    sh_collider_def def{};
    def.shape.kind = kind;
    def.shape.radius = size;
    def.shape.half_length = kind == SH_SHAPE_CAPSULE ? 2.0 * size : 0.0;
    for (int k = 0; k < 3; ++k) def.shape.half_extents[k] = size;
    for (int i = 0; i < 8; ++i)
        for (int k = 0; k < 3; ++k) points[i][k] = size * cube[i][k];
    def.shape.points = &points[0][0];
    def.shape.point_count = 8;
    for (int k = 0; k < 3; ++k) def.position[k] = position[k];
    for (int k = 0; k < 4; ++k) def.orientation[k] = orientation[k];
    def.contact.stiffness = 1e4;
    def.contact.exponent = 1.5;
    def.contact.damping = 0.0;
    def.contact.slip_velocity = 1e-3;
    def.contact.capacity = 4096;
    return Collider(def, true);
}

// Calls visit(nodes, count, weight) for each edge (count 2) and triangle (count 3) of the
// patch, with its excess weight from its size in the patch as given (the reference shape).
template <class Visit>
void each_feature(const Collider& c, const Patch& p, Visit&& visit) {
    auto weight = [&](const int32_t* nodes, int count) {
        double size = 0.0;
        for (int a = 0; a < count; ++a) {
            double e = 0.0;
            for (int k = 0; k < 3; ++k) {
                const double d = p.x[3 * static_cast<size_t>(nodes[a]) + k] - p.x[3 * static_cast<size_t>(nodes[(a + 1) % count]) + k];
                e += d * d;
            }
            size = std::max(size, std::sqrt(e));
        }
        return sh::excess_weight(c, size);
    };
    for (size_t e = 0; e < p.edges.size(); e += 2) visit(&p.edges[e], 2, weight(&p.edges[e], 2));
    for (size_t t = 0; t < p.tris.size(); t += 3) visit(&p.tris[t], 3, weight(&p.tris[t], 3));
}

// The collider's BallMix over the patch at x (used by colliders of several balls).
void mix_over(const Collider& c, const Patch& p, const sh::StepLaw& law, const double* x, sh::BallMix& mix) {
    mix.reserve(c.shape.ball_count());
    mix.sum(c, [&](auto&& add) {
        each_feature(c, p, [&](const int32_t* nodes, int count, double weight) { add(law, x, nodes, count, weight); });
    });
}

// Calls visit(point) for every acting term of the patch's potential against the collider, at
// rest: node terms with their law applied, excess terms as excess_shape_contact gives them.
template <class Visit>
void each_term(const Collider& c, const Patch& p, const double* x, Visit&& visit) {
    const sh::StepLaw law = sh::hunt_crossley_step_law(c.params, 0.0, 0.0);
    for (const int32_t node : p.nodes) {
        ContactPoint point;
        if (!sh::node_shape_contact(c, x, node, point)) continue;
        sh::apply_normal_law(c.params, nullptr, point);
        point.energy = sh::hunt_crossley_step_energy(c.params, law, point.depth);
        visit(point);
    }
    sh::BallMix mix;
    mix_over(c, p, law, x, mix);
    each_feature(c, p, [&](const int32_t* nodes, int count, double weight) {
        ContactPoint point;
        if (sh::excess_shape_contact(c, law, x, nodes, count, weight, &mix, point)) visit(point);
    });
}

double potential(const Collider& c, const Patch& p, const double* x) {
    double e = 0.0;
    each_term(c, p, x, [&](const ContactPoint& q) { e += q.energy; });
    return e;
}

// Force on each node (3 per node) and in total.
std::vector<double> forces(const Collider& c, const Patch& p, const double* x, double total[3]) {
    std::vector<double> f(p.x.size(), 0.0);
    for (int k = 0; k < 3; ++k) total[k] = 0.0;
    each_term(c, p, x, [&](const ContactPoint& q) {
        for (int a = 0; a < q.count; ++a)
            for (int k = 0; k < 3; ++k) {
                f[3 * static_cast<size_t>(q.nodes[a]) + k] += q.node_force[a][k];
                total[k] += q.node_force[a][k];
            }
    });
    return f;
}

// Largest gap between the forces and minus the potential's central-difference gradient,
// relative to the largest force.
double gradient_error(const Collider& c, const Patch& p) {
    double total[3];
    const std::vector<double> f = forces(c, p, p.x.data(), total);
    double largest = 0.0, gap = 0.0;
    for (const double v : f) largest = std::max(largest, std::fabs(v));
    std::vector<double> x = p.x;
    const double h = 1e-8;
    for (size_t i = 0; i < x.size(); ++i) {
        const double keep = x[i];
        x[i] = keep + h;
        const double up = potential(c, p, x.data());
        x[i] = keep - h;
        const double down = potential(c, p, x.data());
        x[i] = keep;
        gap = std::max(gap, std::fabs(f[i] + (up - down) / (2.0 * h)));
    }
    return largest > 0.0 ? gap / largest : 0.0;
}

void test_forces_are_the_potentials_gradient(void**) {
    const Patch cap = hexagon(0.01, 0.002);
    const sh_shape_kind kinds[] = {SH_SHAPE_SPHERE, SH_SHAPE_CAPSULE, SH_SHAPE_BOX, SH_SHAPE_CONVEX};
    const char* names[] = {"sphere", "capsule", "box", "convex"};
#ifdef SOFTHAP_WITH_CCD
    const int kind_count = 4;
#else
    const int kind_count = 3;  // convex shapes need libccd
#endif
    // Over the centre node, over a face, over an edge; small and large tools.
    const double spots[3][2] = {{0.0005, 0.0003}, {0.004, 0.002}, {0.0045, 0.0}};
    for (int s = 0; s < kind_count; ++s)
        for (const double size : {0.0015, 0.006})
            for (const auto& spot : spots) {
                // The tool's lowest point 0.8 mm below the surface (less than its radius).
                double position[3] = {spot[0], spot[1], 0.0};
                Collider c = make_collider(kinds[s], position, size);
                const double down[3] = {0.0, 0.0, -1.0};
                double lowest[3];
                c.shape.support(c.pose, down, lowest);
                position[2] = surface_height(cap, lowest[0], lowest[1]) - 0.0008 - lowest[2];
                c = make_collider(kinds[s], position, size);
                double total[3];
                forces(c, cap, cap.x.data(), total);
                const double error = gradient_error(c, cap);
                printf("%-8s size %.1f mm at (%.1f, %.1f) mm: |F| %.4g N, gradient error %.2e\n", names[s],
                       1e3 * size, 1e3 * spot[0], 1e3 * spot[1], std::sqrt(total[0] * total[0] + total[1] * total[1] + total[2] * total[2]), error);
                // A tilted box's or hull's lowest corner may lie outside its inscribed capsule.
                assert_true(total[2] < 0.0 || s > 1);
                assert_true(error < 1e-5);
            }
}

// A sphere smaller than the triangles of a flat patch, between its nodes: whether its deepest
// point is over a face, on an edge or near a vertex (not reaching it), the force is the law's
// lambda d^n at its depth d, along the normal.
void test_small_sphere_feels_the_law_on_faces_edges_and_vertices(void**) {
    const Patch flat = hexagon(0.01, 0.0);
    const double radius = 0.001, depth = 0.0004;
    const double spots[4][2] = {{0.004, 0.002}, {0.005, 0.0}, {0.0025, 0.0043301}, {0.0016, 0.0002}};
    for (const auto& spot : spots) {
        const double position[3] = {spot[0], spot[1], radius - depth};
        const Collider c = make_collider(SH_SHAPE_SPHERE, position, radius);
        double total[3];
        forces(c, flat, flat.x.data(), total);
        const double law = c.params.stiffness * std::pow(depth, c.params.exponent);
        printf("sphere at (%.2f, %.2f) mm: F (%.3g, %.3g, %.6g) N, lambda d^n %.6g N\n", 1e3 * spot[0], 1e3 * spot[1],
               total[0], total[1], total[2], law);
        assert_true(std::fabs(total[2] + law) < 1e-9 * law);
        assert_true(std::fabs(total[0]) + std::fabs(total[1]) < 1e-9 * law);
    }
}

// A sphere more than twice as large as a flat patch's triangles: the mesh resolves the
// contact, and the force is the nodes' own laws, lambda d_i^n along each node's radial
// direction.
void test_resolved_contact_is_the_nodes_own(void**) {
    const Patch flat = hexagon(0.005, 0.0);
    const double radius = 0.02, press = 0.003;
    const double position[3] = {0.0004, 0.0003, radius - press};
    const Collider c = make_collider(SH_SHAPE_SPHERE, position, radius);
    double total[3], expected[3] = {0.0, 0.0, 0.0};
    forces(c, flat, flat.x.data(), total);
    for (size_t i = 0; i < flat.x.size(); i += 3) {
        double d[3];
        for (int k = 0; k < 3; ++k) d[k] = flat.x[i + k] - position[k];
        const double rho = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double depth = radius - rho;
        assert_true(depth > 0.0);
        for (int k = 0; k < 3; ++k) expected[k] += c.params.stiffness * std::pow(depth, c.params.exponent) * d[k] / rho;
    }
    printf("20 mm sphere 3 mm into 7 nodes 5 mm apart: F (%.9g %.9g %.9g) N, their laws (%.9g %.9g %.9g) N\n", total[0], total[1],
           total[2], expected[0], expected[1], expected[2]);
    for (int k = 0; k < 3; ++k) assert_true(std::fabs(total[k] - expected[k]) < 1e-12 * std::fabs(expected[2]));
}

// The unit quaternion (w, x, y, z) turning local z onto the unit direction `axis`.
void orientation_along(const double axis[3], double q[4]) {
    const double c = axis[2], s = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1]);
    const double angle = std::atan2(s, c);
    const double kx = s > 0.0 ? -axis[1] / s : 1.0, ky = s > 0.0 ? axis[0] / s : 0.0;  // z x axis
    q[0] = std::cos(0.5 * angle);
    q[1] = std::sin(0.5 * angle) * kx;
    q[2] = std::sin(0.5 * angle) * ky;
    q[3] = 0.0;
}

// A 2 mm sphere, and a capsule of that radius lying level, slid at constant height across a
// bumped patch (over faces, edges and the raised centre node) in 10 um steps: the force's
// change per step stays within what the law changes for a 10 um change of depth (at the
// smallest depth on the path), so there is no jump where the contact passes from a face to an
// edge, a vertex or a node.
void test_sliding_force_is_smooth(void**) {
    const Patch cap = hexagon(0.006, 0.0008);
    const double radius = 0.001, height = 0.0008 + radius - 0.0005;
    const double axis[3] = {std::cos(1.0), std::sin(1.0), 0.0};
    double level[4];
    orientation_along(axis, level);
    for (const sh_shape_kind kind : {SH_SHAPE_SPHERE, SH_SHAPE_CAPSULE}) {
        double previous[3] = {0.0, 0.0, 0.0};
        double worst = 0.0, smallest = INFINITY, largest = 0.0;
        const int steps = 500;
        for (int i = 0; i <= steps; ++i) {
            const double s = -0.0025 + 0.005 * i / steps;
            const double position[3] = {s, 0.3 * s + 0.0002, height};
            const Collider c = make_collider(kind, position, radius, level);
            double total[3];
            forces(c, cap, cap.x.data(), total);
            const double magnitude = std::sqrt(total[0] * total[0] + total[1] * total[1] + total[2] * total[2]);
            if (i > 0) {
                double change[3];
                for (int k = 0; k < 3; ++k) change[k] = total[k] - previous[k];
                const double jump = std::sqrt(change[0] * change[0] + change[1] * change[1] + change[2] * change[2]) / magnitude;
                worst = std::max(worst, jump);
            }
            smallest = std::min(smallest, magnitude);
            largest = std::max(largest, magnitude);
            for (int k = 0; k < 3; ++k) previous[k] = total[k];
        }
        printf("%s slide: |F| %.4g..%.4g N, largest change per 10 um step %.3f %%\n",
               kind == SH_SHAPE_SPHERE ? "sphere" : "capsule", smallest, largest, 100.0 * worst);
        assert_true(smallest > 0.0);
        assert_true(worst < 0.05);
    }
}

// The potential along a straight path through random node positions, a sphere pressing a
// bumped patch whose nodes come in and out of it: the energy's change over each step of the
// path matches the forces' work (midpoint rule) to 1 %, so there is no jump or kink that a
// line search would trip on.
void test_potential_is_smooth_along_paths(void**) {
    for (const sh_shape_kind kind : {SH_SHAPE_SPHERE, SH_SHAPE_CAPSULE})
    for (const double radius : {0.001, 0.003})
        for (const double exponent : {1.0, 1.5}) {
            Patch cap = hexagon(0.0025, 0.0003);
            srand(3);
            std::vector<double> direction(cap.x.size());
            for (double& v : direction) v = (rand() / static_cast<double>(RAND_MAX) - 0.5) * 1e-3;
            for (double& v : cap.x) v += (rand() / static_cast<double>(RAND_MAX) - 0.5) * 2e-4;
            const double position[3] = {0.0003, 0.0002, 0.0003 + radius - 0.6 * radius};
            Collider c = make_collider(kind, position, radius);
            c.params.exponent = exponent;
            const int steps = 4000;
            std::vector<double> x = cap.x;
            double previous = potential(c, cap, x.data()), worst = 0.0, largest = 0.0;
            std::vector<double> gaps;
            for (int i = 1; i <= steps; ++i) {
                for (size_t j = 0; j < x.size(); ++j) x[j] = cap.x[j] + (i - 0.5) / steps * direction[j];
                double total[3];
                const std::vector<double> f = forces(c, cap, x.data(), total);
                double work = 0.0;  // minus the forces' work over the step
                for (size_t j = 0; j < x.size(); ++j) work -= f[j] * direction[j] / steps;
                for (size_t j = 0; j < x.size(); ++j) x[j] = cap.x[j] + static_cast<double>(i) / steps * direction[j];
                const double e = potential(c, cap, x.data());
                worst = std::max(worst, std::fabs(e - previous - work));
                largest = std::max(largest, std::fabs(work));
                previous = e;
            }
            printf("%s %.0f mm on 2.5 mm triangles, n %.1f: largest step energy %.3g J, largest gap to the work %.3g J\n",
                   kind == SH_SHAPE_SPHERE ? "sphere" : "capsule", 1e3 * radius, exponent, largest, worst);
            assert_true(largest > 0.0);
            assert_true(worst < 0.01 * largest);
        }
}

// A capsule of radius r and half axis 2r lying along heading (radians, in the plane z = 0)
// tilted by tilt (radians, its +z end down), whose lowest point is depth below z = 0 at its
// centre's (cx, cy).
Collider lying_capsule(double cx, double cy, double heading, double tilt, double radius, double depth) {
    const double axis[3] = {std::cos(tilt) * std::cos(heading), std::cos(tilt) * std::sin(heading), -std::sin(tilt)};
    double q[4];
    orientation_along(axis, q);
    const double lowest = -2.0 * radius * std::fabs(std::sin(tilt)) - radius;  // below the centre
    const double position[3] = {cx, cy, -depth - lowest};
    return make_collider(SH_SHAPE_CAPSULE, position, radius, q);
}

// Moment (N m) of the forces on the patch's nodes about point c.
void moment_about(const Collider& c, const Patch& p, const double centre[3], double out[3]) {
    double total[3];
    const std::vector<double> f = forces(c, p, p.x.data(), total);
    out[0] = out[1] = out[2] = 0.0;
    for (size_t i = 0; i < f.size(); i += 3) {
        const double r[3] = {p.x[i] - centre[0], p.x[i + 1] - centre[1], p.x[i + 2] - centre[2]};
        out[0] += r[1] * f[i + 2] - r[2] * f[i + 1];
        out[1] += r[2] * f[i] - r[0] * f[i + 2];
        out[2] += r[0] * f[i + 1] - r[1] * f[i];
    }
}

// A capsule smaller than the triangles of a flat patch, lying on it between its nodes: over
// a face, across an edge, along an edge, across the fan of faces around a node it does not
// reach. The whole ridge is equally deep, so the force is the law lambda d^n at its depth d,
// along the normal, and (the ridge pressing evenly) its centre of pressure is the capsule's
// centre: no moment about its foot.
void test_small_capsule_lying_between_nodes_feels_the_law(void**) {
    const Patch flat = hexagon(0.01, 0.0);
    const double radius = 0.001, depth = 0.0004;
    const double spots[4][3] = {{0.004, 0.002, 0.3}, {0.005, 0.0, M_PI / 2}, {0.005, 0.0, 0.0}, {0.0, 0.0016, 0.0}};
    for (const auto& spot : spots) {
        const Collider c = lying_capsule(spot[0], spot[1], spot[2], 0.0, radius, depth);
        double total[3], moment[3];
        forces(c, flat, flat.x.data(), total);
        const double foot[3] = {spot[0], spot[1], 0.0};
        moment_about(c, flat, foot, moment);
        const double law = c.params.stiffness * std::pow(depth, c.params.exponent);
        const double arm = std::sqrt(moment[0] * moment[0] + moment[1] * moment[1]) / law;
        printf("lying capsule at (%.1f, %.1f) mm, heading %.2f: F (%.3g, %.3g, %.6g) N, lambda d^n %.6g N, centre of pressure off by %.3g mm\n",
               1e3 * spot[0], 1e3 * spot[1], spot[2], total[0], total[1], total[2], law, 1e3 * arm);
        assert_true(std::fabs(total[2] + law) < 1e-3 * law);
        assert_true(std::fabs(total[0]) + std::fabs(total[1]) < 1e-9 * law);
        assert_true(arm < 0.02 * radius);
    }
}

// The same capsule over a face, tilted through lying flat by 0.1 rad either way (its lowest
// point kept at the same depth): the force stays within the law at that depth (a mean cannot
// exceed its largest ball) and at most 16 % below it (the bound README documents for order 4;
// 0.849 measured), and its centre of pressure goes over from the lower end to the other in
// steps of at most 5 % of the way: the exact maximum's would jump from end to end at once.
void test_tilting_capsule_hands_over_smoothly(void**) {
    const Patch flat = hexagon(0.01, 0.0);
    const double radius = 0.001, depth = 0.0004;
    double previous_force = 0.0, previous_centre = 0.0, worst_force = 0.0, worst_centre = 0.0;
    double lowest = INFINITY, highest = 0.0, first_centre = 0.0;
    const int steps = 400;
    for (int i = 0; i <= steps; ++i) {
        const double tilt = (-0.1 + 0.2 * i / steps);
        const Collider c = lying_capsule(0.004, 0.002, 0.3, tilt, radius, depth);
        double total[3], moment[3];
        forces(c, flat, flat.x.data(), total);
        const double foot[3] = {0.004, 0.002, 0.0};
        moment_about(c, flat, foot, moment);
        const double law = c.params.stiffness * std::pow(depth, c.params.exponent);
        const double force = -total[2] / law;
        // Centre of pressure along the heading: moment about the foot over the force.
        const double centre = (moment[0] * std::sin(0.3) - moment[1] * std::cos(0.3)) / -total[2];
        if (i > 0) {
            worst_force = std::max(worst_force, std::fabs(force - previous_force));
            worst_centre = std::max(worst_centre, std::fabs(centre - previous_centre));
        } else {
            first_centre = centre;
        }
        lowest = std::min(lowest, force);
        highest = std::max(highest, force);
        previous_force = force;
        previous_centre = centre;
    }
    const double ends = 4.0 * radius;  // the axis from end to end
    printf("tilting capsule: force %.4f..%.4f of lambda d^n, largest change per step %.3f %% of it; centre of pressure "
           "from %.3f to %.3f mm, largest step %.3f mm\n",
           lowest, highest, 100.0 * worst_force, 1e3 * first_centre, 1e3 * previous_centre, 1e3 * worst_centre);
    assert_true(highest < 1.0 + 1e-6 && lowest > 0.84);
    assert_true(worst_force < 0.02);
    assert_true(first_centre * previous_centre < 0.0);  // from one end to the other
    assert_true(std::fabs(first_centre) > 0.45 * ends && std::fabs(previous_centre) > 0.45 * ends);
    assert_true(worst_centre < 0.05 * ends);
}

// The vertical stiffness the full model's tangent takes from a capsule (its node terms
// k g g^T, and the mix's tangent across its excess terms, BallMix::tangent) over the nodes of
// a patch under a capsule lying between them, against the slope of the forces (central
// differences): over a face, flat and tilted, across an edge, and over the faces around a node
// it does not reach. Within 3 % of the largest entry. The smooth maximum's own curvature
// dominates it (it stiffens a face against tilting): a tangent of the law's curvature alone is
// far off, and Newton then converges linearly. (With nodes inside the balls the tangent leaves
// out their own curvature and the fade, as a sphere's does: a static solve still converges,
// tests/python/test_contact.py.)
void test_capsule_tangent_matches_the_forces_slope(void**) {
    const Patch flat = hexagon(0.01, 0.0);
    const size_t n = flat.x.size() / 3;
    const double poses[5][4] = {{0.004, 0.002, 0.3, 0.0},
                                {0.004, 0.002, 0.3, 0.002},
                                {0.004, 0.002, 0.3, 0.02},
                                {0.005, 0.0, M_PI / 2, 0.0},
                                {0.0, 0.0016, 0.0, 0.0}};
    for (const auto& pose : poses) {
        const Collider c = lying_capsule(pose[0], pose[1], pose[2], pose[3], 0.001, 0.0004);
        std::vector<double> tangent(n * n, 0.0), slope(n * n, 0.0);
        each_term(c, flat, flat.x.data(), [&](const ContactPoint& q) {
            for (int a = 0; a < q.count; ++a)
                for (int b = 0; b < q.count; ++b)
                    tangent[static_cast<size_t>(q.nodes[a]) * n + static_cast<size_t>(q.nodes[b])] +=
                        q.mixed ? 0.0 : q.stiffness * q.gradient[a][2] * q.gradient[b][2];
        });
        const sh::StepLaw law = sh::hunt_crossley_step_law(c.params, 0.0, 0.0);
        sh::BallMix mix;
        mix_over(c, flat, law, flat.x.data(), mix);
        mix.begin_tangent();
        each_feature(c, flat, [&](const int32_t* nodes, int count, double weight) {
            mix.add_tangent_term(c, law, flat.x.data(), nodes, count, weight);
        });
        mix.tangent([&](int32_t a, int32_t b, const double* block) {
            tangent[static_cast<size_t>(a) * n + static_cast<size_t>(b)] += block[8];
            if (a != b) tangent[static_cast<size_t>(b) * n + static_cast<size_t>(a)] += block[8];
        });
        std::vector<double> x = flat.x;
        const double h = 1e-8;
        double largest = 0.0, gap = 0.0;
        for (size_t j = 0; j < n; ++j) {
            double total[3];
            x[3 * j + 2] += h;
            const std::vector<double> up = forces(c, flat, x.data(), total);
            x[3 * j + 2] -= 2.0 * h;
            const std::vector<double> down = forces(c, flat, x.data(), total);
            x[3 * j + 2] += h;
            for (size_t i = 0; i < n; ++i) slope[i * n + j] = -(up[3 * i + 2] - down[3 * i + 2]) / (2.0 * h);
        }
        for (size_t k = 0; k < n * n; ++k) {
            largest = std::max(largest, std::fabs(slope[k]));
            gap = std::max(gap, std::fabs(slope[k] - tangent[k]));
        }
        printf("capsule at (%.1f, %.1f) mm heading %.2f tilted %.3f rad: largest stiffness %.4g N/m, largest gap to the "
               "forces' slope %.3g N/m\n", 1e3 * pose[0], 1e3 * pose[1], pose[2], pose[3], largest, gap);
        assert_true(largest > 0.0);
        assert_true(gap < 0.03 * largest);
    }
}

}  // namespace

// A capsule (1 mm, 4 mm axis) lying along an edge of a flat patch of 2.5 mm triangles, 0.3 mm
// beside it, pressed down 0.9 mm in 1 um steps: the edge's nodes come into it one after the
// other, the centre node first, and its balls' terms over the faces and the edge between them
// hand over to the nodes' own terms. No step changes the force by more than 1 % of its largest
// (0.19 % measured): the balls' terms fade over their radius as the last node comes in, not
// within a fiftieth of it as a sphere's do, where the fade's slope (a force on that node alone)
// spikes (2.3 %, and a rendered buzz on liver2). The hand-over still loses some of the force
// while that node's own law grows from zero: at most 8 % of the largest (6.4 % measured; 11 %
// with the narrow band).
void test_capsule_pressed_onto_nodes_hands_over_smoothly(void**) {
    const Patch flat = hexagon(0.0025, 0.0);
    const double radius = 0.001;
    double level[4];
    const double axis[3] = {1.0, 0.0, 0.0};
    orientation_along(axis, level);
    double previous = 0.0, largest = 0.0, worst_fall = 0.0, worst_step = 0.0;
    const int steps = 900;
    for (int i = 0; i <= steps; ++i) {
        const double depth = 0.0009 * i / steps;
        const double position[3] = {0.0, 0.0003, radius - depth};
        const Collider c = make_collider(SH_SHAPE_CAPSULE, position, radius, level);
        double total[3];
        forces(c, flat, flat.x.data(), total);
        const double force = -total[2];
        largest = std::max(largest, force);
        worst_fall = std::max(worst_fall, largest - force);
        if (i > 0) worst_step = std::max(worst_step, std::fabs(force - previous));
        previous = force;
    }
    printf("capsule pressed onto an edge's nodes: force up to %.4g N, largest fall %.2f %% and step %.3f %% of it\n",
           largest, 100.0 * worst_fall / largest, 100.0 * worst_step / largest);
    assert_true(largest > 0.0);
    assert_true(worst_fall < 0.08 * largest);
    assert_true(worst_step < 0.01 * largest);
}

// The balls a box takes between nodes: its largest inscribed capsule, along its longest axis,
// of its smallest half width, ending that far short of its ends (the depth along the axis is
// min(r, h_long - |t|)); a cube's is its inscribed ball. A convex hull of the box's corners is
// the box; a triangular prism (equilateral section of inradius rho, length 2 l) has the capsule
// of radius rho ending rho short of its ends.
void expect_core(const sh::Shape& shape, double radius, const double end[3], const char* what) {
    double a[3], b[3];
    const sh::Pose identity;
    const int count = shape.ball_count();
    shape.ball_centre(identity, 0, a);
    shape.ball_centre(identity, count - 1, b);
    const double length = std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
    printf("%s: %d balls of radius %.6g mm from (%.4g, %.4g, %.4g) to (%.4g, %.4g, %.4g) mm\n", what, count,
           1e3 * shape.ball_radius(), 1e3 * a[0], 1e3 * a[1], 1e3 * a[2], 1e3 * b[0], 1e3 * b[1], 1e3 * b[2]);
    const double half = std::sqrt(end[0] * end[0] + end[1] * end[1] + end[2] * end[2]);
    assert_true(std::fabs(shape.ball_radius() - radius) < 1e-9 * radius);
    assert_true(std::fabs(0.5 * length - half) < 1e-9 * half);
    // Centred, along the expected axis (either way round).
    for (int k = 0; k < 3; ++k) {
        assert_true(std::fabs(a[k] + b[k]) < 1e-9 * half);
        assert_true(std::fabs(std::fabs(b[k]) - std::fabs(end[k])) < 1e-9 * half);
    }
    assert_true(count - 1 >= 4.0 * half / radius && count - 2 < 4.0 * half / radius);  // half a radius apart
}

void test_box_and_hull_take_their_inscribed_capsule(void**) {
    sh_shape box{};
    box.kind = SH_SHAPE_BOX;
    box.half_extents[0] = 0.003;
    box.half_extents[1] = 0.012;
    box.half_extents[2] = 0.001;
    const double box_end[3] = {0.0, 0.011, 0.0};
    expect_core(sh::Shape(box), 0.001, box_end, "box 6 x 24 x 2 mm");
    // A cube's is its inscribed ball: one ball, however round-off places its axis.
    sh_shape cube = box;
    for (int k = 0; k < 3; ++k) cube.half_extents[k] = 0.003;
    const sh::Shape cube_shape(cube);
    printf("cube 6 mm: %d ball of radius %.6g mm\n", cube_shape.ball_count(), 1e3 * cube_shape.ball_radius());
    assert_int_equal(cube_shape.ball_count(), 1);
    assert_true(std::fabs(cube_shape.ball_radius() - 0.003) < 1e-12);
#ifdef SOFTHAP_WITH_CCD
    double corners[8][3];
    for (int c = 0; c < 8; ++c)
        for (int k = 0; k < 3; ++k) corners[c][k] = (c >> k & 1) ? box.half_extents[k] : -box.half_extents[k];
    sh_shape hull{};
    hull.kind = SH_SHAPE_CONVEX;
    hull.points = &corners[0][0];
    hull.point_count = 8;
    expect_core(sh::Shape(hull), 0.001, box_end, "hull of its corners");
    const double rho = 0.0005, l = 0.004;
    double prism[6][3];
    for (int i = 0; i < 6; ++i) {
        const double angle = M_PI / 2 + 2.0 * M_PI * (i % 3) / 3.0;
        prism[i][0] = i < 3 ? -l : l;
        prism[i][1] = 2.0 * rho * std::cos(angle);  // circumradius: twice the inradius
        prism[i][2] = 2.0 * rho * std::sin(angle) + 0.002;  // off the local origin
    }
    hull.points = &prism[0][0];
    hull.point_count = 6;
    const sh::Shape shape(hull);
    const double prism_end[3] = {l - rho, 0.0, 0.0};
    // On the prism's axis (2 mm above the local origin), ending rho short of its ends.
    double first[3], last[3];
    shape.ball_centre(sh::Pose{}, 0, first);
    shape.ball_centre(sh::Pose{}, shape.ball_count() - 1, last);
    printf("prism: radius %.6g mm (inradius %.6g), axis from (%.6g, %.3g, %.6g) to (%.6g, %.3g, %.6g) mm\n",
           1e3 * shape.ball_radius(), 1e3 * rho, 1e3 * first[0], 1e3 * first[1], 1e3 * first[2], 1e3 * last[0],
           1e3 * last[1], 1e3 * last[2]);
    assert_true(std::fabs(shape.ball_radius() - rho) < 1e-9 * rho);
    for (const double* end : {first, last})
        assert_true(std::fabs(std::fabs(end[0]) - prism_end[0]) < 1e-9 * l && std::fabs(end[1]) < 1e-12 &&
                    std::fabs(end[2] - 0.002) < 1e-12);
    assert_true(first[0] * last[0] < 0.0);
#endif
}

// A plate (a box 4 x 1.6 x 1 mm, and its corners' hull) lying flat 0.4 mm deep between the
// nodes of a flat patch: its bottom face is as deep as its inscribed capsule's ridge, so it
// feels the law lambda d^n at that depth along the normal, as the lying capsule does, with no
// sideways force.
void test_plate_lying_between_nodes_feels_the_law(void**) {
    const Patch flat = hexagon(0.01, 0.0);
    const double half[3] = {0.002, 0.0008, 0.0005}, depth = 0.0004;
    double corners[8][3];
    for (int c = 0; c < 8; ++c)
        for (int k = 0; k < 3; ++k) corners[c][k] = (c >> k & 1) ? half[k] : -half[k];
    const double spots[3][3] = {{0.004, 0.002, 0.3}, {0.005, 0.0, M_PI / 2}, {0.0, 0.0018, 0.0}};
#ifdef SOFTHAP_WITH_CCD
    const int kinds = 2;
#else
    const int kinds = 1;
#endif
    for (int kind = 0; kind < kinds; ++kind)
        for (const auto& spot : spots) {
            sh_collider_def def{};
            def.shape.kind = kind == 0 ? SH_SHAPE_BOX : SH_SHAPE_CONVEX;
            for (int k = 0; k < 3; ++k) def.shape.half_extents[k] = half[k];
            def.shape.points = &corners[0][0];
            def.shape.point_count = 8;
            def.position[0] = spot[0];
            def.position[1] = spot[1];
            def.position[2] = half[2] - depth;
            def.orientation[0] = std::cos(0.5 * spot[2]);  // turned about z by the heading
            def.orientation[3] = std::sin(0.5 * spot[2]);
            def.contact.stiffness = 1e4;
            def.contact.exponent = 1.5;
            def.contact.slip_velocity = 1e-3;
            def.contact.capacity = 4096;
            const Collider c(def, true);
            double total[3];
            forces(c, flat, flat.x.data(), total);
            const double law = c.params.stiffness * std::pow(depth, c.params.exponent);
            printf("lying %s at (%.1f, %.1f) mm, heading %.2f: F (%.3g, %.3g, %.6g) N, lambda d^n %.6g N\n",
                   kind == 0 ? "box" : "hull", 1e3 * spot[0], 1e3 * spot[1], spot[2], total[0], total[1], total[2], law);
            assert_true(std::fabs(total[2] + law) < 1e-3 * law);
            assert_true(std::fabs(total[0]) + std::fabs(total[1]) < 1e-6 * law);
        }
}

int main() {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_forces_are_the_potentials_gradient),
        cmocka_unit_test(test_small_sphere_feels_the_law_on_faces_edges_and_vertices),
        cmocka_unit_test(test_resolved_contact_is_the_nodes_own),
        cmocka_unit_test(test_sliding_force_is_smooth),
        cmocka_unit_test(test_potential_is_smooth_along_paths),
        cmocka_unit_test(test_small_capsule_lying_between_nodes_feels_the_law),
        cmocka_unit_test(test_tilting_capsule_hands_over_smoothly),
        cmocka_unit_test(test_capsule_tangent_matches_the_forces_slope),
        cmocka_unit_test(test_capsule_pressed_onto_nodes_hands_over_smoothly),
        cmocka_unit_test(test_box_and_hull_take_their_inscribed_capsule),
        cmocka_unit_test(test_plate_lying_between_nodes_feels_the_law),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
