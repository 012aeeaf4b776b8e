// The excess of a ball's contact potential over an edge or a triangle (ball_excess), against
// an independent search: the excess psi(R - |x - c|) - sum_a w_a e_a evaluated directly on a
// fine barycentric grid, and its derivatives by central differences at the returned maximiser.
#include "collision/ball_excess.hpp"
#include "contact/ball_terms.hpp"

#include <algorithm>
#include <cmath>
#include <random>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

constexpr double kRadius = 0.01;  // m
const double kCentre[3] = {0.0, 0.0, 0.0};

struct Law {
    sh_contact_params params{};
    sh::StepLaw step{};
};

// A Hunt-Crossley law of the given exponent; damped, its step law leans on the depth rate
// (law.b > 0) as a step of 1e-4 s from a start 1 mm deep makes it.
Law make_law(double exponent, bool damped) {
    Law law;
    law.params.stiffness = 2e5;
    law.params.exponent = exponent;
    law.params.damping = damped ? 0.5 : 0.0;
    law.step = sh::hunt_crossley_step_law(law.params, damped ? 1e-3 : 0.0, damped ? 1e-4 : 0.0);
    return law;
}

// The excess at point x with weights w, computed from its definition.
double direct_excess(const sh::LocalSimplex& s, const sh::DepthPotential& psi, const double x[3], const double w[3]) {
    const double depth = kRadius - std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    double value = depth > 0.0 ? psi.energy(depth) : 0.0;
    for (int a = 0; a < s.count; ++a) value -= w[a] * s.energy[a];
    return value;
}

// The excess at barycentric weights (1 - u - v, u, v) (v = 0 on an edge).
double excess_at(const sh::LocalSimplex& s, const sh::DepthPotential& psi, double u, double v) {
    const double w[3] = {1.0 - u - v, u, v};
    double x[3];
    for (int k = 0; k < 3; ++k) {
        x[k] = 0.0;
        for (int a = 0; a < s.count; ++a) x[k] += w[a] * s.p[a][k];
    }
    return direct_excess(s, psi, x, w);
}

// The largest excess found by a grid search: a grid of 200 intervals per side over the
// simplex, then grids of 20 intervals over 4 of the last grid's cells around its best point,
// twelve times (down to about 1e-11 of the simplex), clipped to the simplex.
double grid_maximum(const sh::LocalSimplex& s, const sh::DepthPotential& psi) {
    const int v_steps = s.count == 3 ? 1 : 0;
    double best = -INFINITY, best_u = 0.0, best_v = 0.0;
    double lo_u = 0.0, lo_v = 0.0, width = 1.0;
    int n = 200;
    for (int level = 0; level <= 12; ++level) {
        const double cell = width / n;
        for (int i = 0; i <= n; ++i)
            for (int j = 0; j <= n * v_steps; ++j) {
                const double u = lo_u + i * cell, v = lo_v + j * cell;
                if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
                const double value = excess_at(s, psi, u, v);
                if (value > best) best = value, best_u = u, best_v = v;
            }
        width = 4.0 * cell;
        lo_u = best_u - 2.0 * cell;
        lo_v = v_steps ? best_v - 2.0 * cell : 0.0;
        n = 20;
    }
    return best;
}

// A random simplex cutting the ball: nodes spread over 3 radii around the centre's foot on a
// tilted plane at a random height, each with its own potential in the ball (as ball_term
// gives them), so that some lie inside and some outside.
sh::LocalSimplex random_simplex(std::mt19937_64& rng, const sh::DepthPotential& psi, int count) {
    std::uniform_real_distribution<double> spread(-1.5 * kRadius, 1.5 * kRadius), height(0.1 * kRadius, 0.9 * kRadius),
        tilt(-0.5, 0.5);
    const double h = height(rng), tx = tilt(rng), ty = tilt(rng);
    sh::LocalSimplex s{};
    s.count = count;
    for (int a = 0; a < count; ++a) {
        const double px = spread(rng), py = spread(rng);
        const double p[3] = {px, py, -h + tx * px + ty * py};
        const double depth = kRadius - std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (int k = 0; k < 3; ++k) s.p[a][k] = p[k];
        s.energy[a] = depth > 0.0 ? psi.energy(depth) : 0.0;
    }
    return s;
}

// The slope of the excess at the maximiser along the simplex's free directions, by central
// differences: zero where the maximiser lies inside the triangle or inside an edge; -1 where
// it is at a corner (no direction is free).
double free_slope(const sh::LocalSimplex& s, const sh::DepthPotential& psi, const sh::LocalExcess& e) {
    const double delta = 1e-6;  // in barycentric units
    const double inside = 1e-3;
    double largest = -1.0;
    // Directions that keep every weight that is 0 at 0: on an edge, along it.
    const double directions[3][3] = {{-1.0, 1.0, 0.0}, {-1.0, 0.0, 1.0}, {0.0, -1.0, 1.0}};
    for (const auto& d : directions) {
        bool free = true;
        for (int a = 0; a < 3; ++a)
            if (d[a] != 0.0 && (a >= s.count || !(e.w[a] > inside))) free = false;
        if (!free) continue;
        const double u = e.w[1], v = s.count == 3 ? e.w[2] : 0.0;
        const double up = excess_at(s, psi, u + delta * d[1], v + delta * d[2]);
        const double down = excess_at(s, psi, u - delta * d[1], v - delta * d[2]);
        largest = std::max(largest, std::fabs(up - down) / (2.0 * delta));
    }
    return largest;
}

// For many random simplices under each law: the maximiser's value is the excess there, at
// least the grid's best, and a stationary point along the simplex where it is inside it.
void check_against_grid(int count, double exponent, bool damped) {
    std::mt19937_64 rng(count * 1000 + static_cast<int>(exponent * 10) + (damped ? 7 : 0));
    const Law law = make_law(exponent, damped);
    const sh::StepLawPotential psi(law.params, law.step);
    const double scale = psi.energy(kRadius);  // the largest energy a node can have
    int checked = 0, inside = 0;
    for (int trial = 0; trial < 60; ++trial) {
        const sh::LocalSimplex s = random_simplex(rng, psi, count);
        const sh::LocalExcess e = sh::ball_excess(s, psi, kCentre, kRadius);
        const double grid = grid_maximum(s, psi);
        if (!(grid > 1e-9 * scale)) continue;  // no excess worth the name
        ++checked;
        assert_true(std::isfinite(e.value));
        assert_true(std::fabs(direct_excess(s, psi, e.x, e.w) - e.value) <= 1e-13 * scale);
        assert_true(e.value >= grid - 1e-13 * scale);
        // The search ends within about 1e-11 of the maximiser: its best is just below.
        assert_true(e.value - grid <= 1e-9 * scale);
        const double slope = free_slope(s, psi, e);
        // A maximiser found to round-off leaves only the differences' own error (about
        // 1e-10 of the energy scale per barycentric unit); one found to 1e-6 of the rim does
        // not (its slope is about 1e-6 of the scale).
        assert_true(slope <= 1e-8 * scale);
        inside += slope >= 0.0;
    }
    assert_true(checked >= 20);  // the random simplices do reach the interesting cases
    assert_true(inside >= 10);
}

void test_triangle_excess_matches_a_grid_search(void**) {
    for (const double exponent : {1.0, 1.5, 3.0})
        for (const bool damped : {false, true}) check_against_grid(3, exponent, damped);
}

void test_edge_excess_matches_a_grid_search(void**) {
    for (const double exponent : {1.0, 1.5, 3.0})
        for (const bool damped : {false, true}) check_against_grid(2, exponent, damped);
}

// Counts the law's force evaluations (a crossing's scan and refinement make them).
class CountingPotential final : public sh::DepthPotential {
public:
    explicit CountingPotential(const sh::DepthPotential& law) : law_(law) {}
    double energy(double depth) const override { return law_.energy(depth); }
    double force(double depth) const override { return ++count, law_.force(depth); }
    double stiffness(double depth) const override { return law_.stiffness(depth); }
    void force_and_stiffness(double depth, double& force, double& stiffness) const override {
        ++count;
        law_.force_and_stiffness(depth, force, stiffness);
    }
    mutable long count = 0;

private:
    const sh::DepthPotential& law_;
};

// A ball that barely reaches an edge (its centre 1e-2 to 1e-7 of a radius short of it: every
// first touch): the edge's maximiser is found in a bounded number of the law's evaluations (a
// scan of at most 16, then Newton), and it is still the grid search's maximum. Where the depth
// R - |x - c| loses its digits to cancellation, Newton's steps never settle (about 100
// evaluations per crossing).
void test_grazing_ball_costs_a_bounded_number_of_evaluations(void**) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> decade(2.0, 7.0), spread(0.0, 1.0);
    for (const double exponent : {1.0, 1.5, 3.0}) {
        const Law law = make_law(exponent, false);
        const sh::StepLawPotential psi(law.params, law.step);
        const CountingPotential counting(psi);
        long worst = 0;
        for (int trial = 0; trial < 300; ++trial) {
            const double height = kRadius * (1.0 - std::pow(10.0, -decade(rng)));
            const double rim = std::sqrt((kRadius - height) * (kRadius + height));
            sh::LocalSimplex s{};
            s.count = 2;
            const double a[3] = {-2.0 * rim, 0.0, -height}, b[3] = {2.0 * rim, 0.0, -height};
            for (int k = 0; k < 3; ++k) s.p[0][k] = a[k], s.p[1][k] = b[k];
            // Energies whose slope along the edge the bell's slope phi(r) = psi'(R - rho) r / rho
            // reaches (or, in a few, just not), sampled here from its definition.
            double steepest = 0.0;
            for (int k = 1; k <= 256; ++k) {
                const double r = rim * k / 256.0, rho = std::sqrt(height * height + r * r);
                steepest = std::max(steepest, psi.force(kRadius - rho) * r / rho);
            }
            s.energy[0] = 0.0;
            s.energy[1] = 4.0 * rim * steepest * std::pow(spread(rng), 0.3) * 1.02;
            counting.count = 0;
            const sh::LocalExcess e = sh::ball_excess(s, counting, kCentre, kRadius);
            worst = std::max(worst, counting.count);
            const double grid = grid_maximum(s, psi);
            // The grid's own depths R - |x - c| keep about 1e-9 of their value here (the very
            // cancellation the solver avoids): its values are compared to 1e-6 of the largest.
            if (grid > 0.0) assert_true(e.value >= grid - 1e-6 * psi.energy(kRadius - height));
        }
        assert_true(worst <= 50);
    }
}

}  // namespace

int main() {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle_excess_matches_a_grid_search),
        cmocka_unit_test(test_edge_excess_matches_a_grid_search),
        cmocka_unit_test(test_grazing_ball_costs_a_bounded_number_of_evaluations),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
