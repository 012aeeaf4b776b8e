// The contact potential of contact/shape_contact.hpp on a small closed surface (a regular
// tetrahedron, 1 cm edges: faces, sharp convex edges and vertices): its node forces are minus
// its energy's gradient (central differences), and its energy and force change continuously as
// a tool slides from a face over an edge and a vertex. An internal test: the library exports
// only sh_* symbols, so it is compiled with the contact sources themselves.
#include "contact/collider.hpp"
#include "contact/shape_contact.hpp"

#include <softhap/softhap.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
}

namespace {

constexpr double kEdge = 0.01;  // m
constexpr double kExponent = 1.5;

struct Surface {
    std::vector<double> x;          // 3 per node
    std::vector<int32_t> triangles;  // 3 per face, outward
    std::vector<int32_t> edges;      // 4 per convex edge: a, b, own third, the one across
};

// A regular tetrahedron with outward faces and its six edges.
Surface tetrahedron() {
    Surface s;
    const double h = kEdge / std::sqrt(2.0) / 2.0;
    s.x = {h, h, h, h, -h, -h, -h, h, -h, -h, -h, h};
    s.triangles = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    const int32_t* t = s.triangles.data();
    for (int f = 0; f < 4; ++f)
        for (int k = 0; k < 3; ++k) {
            const int32_t a = t[3 * f + k], b = t[3 * f + (k + 1) % 3], c = t[3 * f + (k + 2) % 3];
            for (int g = f + 1; g < 4; ++g)  // the face across (b, a): each edge once
                for (int m = 0; m < 3; ++m)
                    if (t[3 * g + m] == b && t[3 * g + (m + 1) % 3] == a)
                        s.edges.insert(s.edges.end(), {a, b, c, sh::third_node(&t[3 * g], a, b)});
        }
    return s;
}

sh::Collider make_tool(sh_shape_kind kind, const double position[3], const double orientation[4]) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = kind;
    def.shape.radius = 0.002;
    def.shape.half_length = 0.003;
    def.shape.half_extents[0] = 0.003;
    def.shape.half_extents[1] = 0.002;
    def.shape.half_extents[2] = 0.0025;
    def.contact.exponent = kExponent;
    def.contact.stiffness = 1.0;
    for (int k = 0; k < 3; ++k) def.position[k] = position[k];
    for (int k = 0; k < 4; ++k) def.orientation[k] = orientation[k];
    return sh::Collider(def, true);
}

// The potential's energy sum law_scale e^(n+1) / (n + 1) over the touching nodes, edges and
// faces, in the order the full model and the haptic step use (nodes first); when force is not
// null, minus its gradient (the analytic one) is added to it per node.
double potential(const sh::Collider& tool, const Surface& s, const double* x, double* force) {
    const size_t n = s.x.size() / 3;
    std::vector<sh::NodeDepth> depths(n);
    double energy = 0.0;
    auto add = [&](const sh::ContactPoint& p) {
        const double e = p.depth;
        energy += p.law_scale * std::pow(e, kExponent + 1.0) / (kExponent + 1.0);
        if (!force) return;
        for (int a = 0; a < p.count; ++a)
            for (int k = 0; k < 3; ++k) force[3 * p.nodes[a] + k] += p.law_scale * std::pow(e, kExponent) * p.gradient[a][k];
    };
    for (size_t i = 0; i < n; ++i) {
        sh::ContactPoint p;
        if (!sh::node_shape_contact(tool, x, static_cast<int32_t>(i), p)) continue;
        depths[i] = sh::node_depth_of(tool, p);
        add(p);
    }
    for (size_t e = 0; e < s.edges.size(); e += 4) {
        sh::ContactPoint p;
        if (sh::edge_shape_contact(tool, x, &s.edges[e], depths.data(), p)) add(p);
    }
    for (size_t f = 0; f < s.triangles.size(); f += 3) {
        sh::ContactPoint p;
        if (sh::face_shape_contact(tool, x, &s.triangles[f], depths.data(), p)) add(p);
    }
    return energy;
}

// Largest difference between the analytic node forces and minus the central-difference
// gradient of the energy, over the force's largest component; 0 if nothing touches.
double gradient_error(const sh::Collider& tool, const Surface& s) {
    std::vector<double> x = s.x, analytic(x.size(), 0.0);
    potential(tool, s, x.data(), analytic.data());
    double largest = 0.0, error = 0.0;
    for (double f : analytic) largest = std::max(largest, std::fabs(f));
    if (!(largest > 0.0)) return 0.0;
    const double h = 1e-8;  // m: 1e-6 of the edge
    for (size_t j = 0; j < x.size(); ++j) {
        const double saved = x[j];
        x[j] = saved + h;
        const double up = potential(tool, s, x.data(), nullptr);
        x[j] = saved - h;
        const double down = potential(tool, s, x.data(), nullptr);
        x[j] = saved;
        error = std::max(error, std::fabs(-(up - down) / (2.0 * h) - analytic[j]));
    }
    return error / largest;
}

// Poses just outside the tetrahedron's surface, looking at faces, edges and vertices: the
// tool's centre at a distance from the centroid chosen so that it overlaps the surface.
void check_gradients(sh_shape_kind kind, double reach) {
    const Surface s = tetrahedron();
    unsigned seed = 12345u;
    auto uniform = [&] {
        seed = seed * 1664525u + 1013904223u;
        return (seed >> 8) / 16777216.0;
    };
    int touching = 0;
    double worst = 0.0;
    for (int trial = 0; trial < 400; ++trial) {
        double d[3] = {2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1};
        const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double distance = reach * (0.6 + 0.8 * uniform());
        const double position[3] = {distance * d[0] / norm, distance * d[1] / norm, distance * d[2] / norm};
        double q[4] = {uniform() + 0.2, uniform() - 0.5, uniform() - 0.5, uniform() - 0.5};
        const sh::Collider tool = make_tool(kind, position, q);
        std::vector<double> none(s.x.size(), 0.0);
        if (potential(tool, s, s.x.data(), none.data()) > 0.0) ++touching;
        worst = std::max(worst, gradient_error(tool, s));
    }
    std::printf("shape %d: %d of 400 poses touch, worst relative gradient error %.2e\n", kind, touching, worst);
    assert_true(touching > 200);
    assert_true(worst < 1e-5);
}

void test_sphere_forces_are_the_energy_gradient(void**) { check_gradients(SH_SHAPE_SPHERE, 0.005); }
void test_capsule_forces_are_the_energy_gradient(void**) { check_gradients(SH_SHAPE_CAPSULE, 0.0065); }
void test_box_forces_are_the_energy_gradient(void**) { check_gradients(SH_SHAPE_BOX, 0.0065); }

// A shallow hexagonal cap (apex 2 mm over a 1 cm ring, 11 degree slopes): six faces, six
// convex edges meeting at the apex.
Surface cap() {
    Surface s;
    s.x = {0.0, 0.0, 0.002};
    for (int i = 0; i < 6; ++i) s.x.insert(s.x.end(), {0.01 * std::cos(i * M_PI / 3), 0.01 * std::sin(i * M_PI / 3), 0.0});
    // Triangle (0, a, b) per sector; edge (0, a) between it and the sector before, (0, prev,
    // a), whose third node is prev.
    for (int i = 0; i < 6; ++i) s.triangles.insert(s.triangles.end(), {0, 1 + i, 1 + (i + 1) % 6});
    for (int i = 0; i < 6; ++i) {
        const int32_t a = 1 + i, b = 1 + (i + 1) % 6, prev = 1 + (i + 5) % 6;
        s.edges.insert(s.edges.end(), {0, a, b, prev});
    }
    return s;
}

// A 2 mm sphere glides over the cap about 0.5 mm deep along a line 0.3 mm beside the apex,
// over a face, three edges and the apex's neighbourhood: the force on the tool changes by at
// most 2 % of its largest value between samples 10 um apart (a hand-over that switched
// contacts on or off would jump), and the tool never loses contact.
void test_sliding_over_features_is_continuous(void**) {
    const Surface s = cap();
    const double identity[4] = {1, 0, 0, 0};
    const int samples = 1200;
    double previous = -1.0, worst = 0.0, largest = 0.0, least = INFINITY;
    for (int i = 0; i <= samples; ++i) {
        const double xc = -0.006 + 0.012 * i / samples, yc = 0.0003;
        const double below = 0.002 * (1.0 - std::sqrt(xc * xc + yc * yc) / 0.01);  // the cap's height there
        const double position[3] = {xc, yc, below + 0.002 - 0.0005};
        const sh::Collider tool = make_tool(SH_SHAPE_SPHERE, position, identity);
        std::vector<double> f(s.x.size(), 0.0);
        potential(tool, s, s.x.data(), f.data());
        double total[3] = {0, 0, 0};
        for (size_t j = 0; j < f.size(); ++j) total[j % 3] += f[j];
        const double magnitude = std::sqrt(total[0] * total[0] + total[1] * total[1] + total[2] * total[2]);
        largest = std::max(largest, magnitude);
        least = std::min(least, magnitude);
        if (previous >= 0.0) worst = std::max(worst, std::fabs(magnitude - previous));
        previous = magnitude;
    }
    std::printf("slide: force %.3e .. %.3e, largest change between samples %.2f %%\n", least, largest,
                100.0 * worst / largest);
    assert_true(least > 0.0);
    assert_true(worst <= 0.02 * largest);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_forces_are_the_energy_gradient),
        cmocka_unit_test(test_capsule_forces_are_the_energy_gradient),
        cmocka_unit_test(test_box_forces_are_the_energy_gradient),
        cmocka_unit_test(test_sliding_over_features_is_continuous),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
