// Every law's energy density at small strain against linear elasticity's,
// psi_lin = mu |sym(e)|^2 + lambda/2 tr(e)^2, which each law matches to first order in the
// strain: psi(I + e A) / psi_lin(e A) = 1 + O(e), and every rotation-invariant law also at
// R (I + e A). The ratio is checked from e = 1e-2 down to
// 1e-10, where the O(mu e) terms a law's formula may cancel near rest are 1e10 times its
// energy: a formula that lets them cancel in floating point (rather than by hand) is off by
// eps / e ~ 1e-6 there, and an implicit step of a stiff body at rest then sees energy noise
// above its round-off estimate.
#include "material/material_table.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

constexpr double kLambda = 4.0e4, kMu = 1.0e4;

/// Linear elasticity's energy density at displacement gradient G (the independent reference).
double linear_energy(const double (&G)[3][3]) {
    double tr = 0.0, ee = 0.0;
    for (int i = 0; i < 3; ++i) {
        tr += G[i][i];
        for (int j = 0; j < 3; ++j) {
            const double e = 0.5 * (G[i][j] + G[j][i]);
            ee += e * e;
        }
    }
    return kMu * ee + 0.5 * kLambda * tr * tr;
}

template <class Law>
void check_law(int row) {
    std::mt19937_64 rng(7 + static_cast<unsigned>(row));
    std::uniform_real_distribution<double> entry(-1.0, 1.0);
    for (double e = 1e-2; e >= 1e-10; e *= 0.1) {
        double G[sh::kLanes][3][3];
        sh::Mat3L F;
        for (int l = 0; l < sh::kLanes; ++l)
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    F.m[i][j][l] = (i == j ? 1.0 : 0.0) + e * entry(rng);
                    G[l][i][j] = F.m[i][j][l] - (i == j ? 1.0 : 0.0);  // exact: what F holds
                }
        const sh::Lanes psi = Law::energy(F, sh::splat(kLambda), sh::splat(kMu));
        double worst = 0.0;
        for (int l = 0; l < sh::kLanes; ++l) worst = std::max(worst, std::abs(psi[l] / linear_energy(G[l]) - 1.0));
        std::printf("model %d, strain %.0e: largest |psi / psi_lin - 1| = %.2e\n", static_cast<int>(Law::kModel), e, worst);
        // O(e) from the law's nonlinearity (at most a few times e for these moduli), plus
        // round-off relative to psi itself; a law that rotates takes its strain from a polar
        // rotation whose entries carry eps each, which is eps / e of the strain.
        const double roundoff = Law::kRotates ? 64.0 * std::numeric_limits<double>::epsilon() / e : 1e-12;
        assert_true(worst <= 8.0 * e + roundoff);
    }
}

/// q - log(1 + q) in long double: its Taylor series for |q| < 0.1 (where the difference
/// cancels), the difference itself elsewhere.
long double reference_q_minus_log1p(long double q) {
    if (std::fabs(q) >= 0.1L) return q - std::log1p(q);
    long double sum = 0.0L, power = q;
    for (int k = 2; k <= 40; ++k) {
        power *= -q;
        sum += power / k;  // (-1)^k q^k / k
    }
    return -sum;
}

/// The lanes run together, so that lanes of the series (|q| < 1/4) and of the difference itself
/// share batches.
void neo_hookean_log_term_is_accurate_near_zero(void**) {
    std::vector<double> xs;
    for (double q = -0.75; q <= 10.0; q += 1.0 / 64.0 + 1e-3)
        for (double scale : {1.0, 1e-3, 1e-6, 1e-9, 1e-12})
            if (q * scale != 0.0) xs.push_back(q * scale);
    double worst = 0.0;
    for (size_t first = 0; first < xs.size(); first += sh::kLanes) {
        sh::Lanes q = sh::splat(xs[first]);
        for (int l = 0; l < sh::kLanes && first + static_cast<size_t>(l) < xs.size(); ++l) q[l] = xs[first + static_cast<size_t>(l)];
        const sh::Lanes value = sh::NeoHookeanMaterial::q_minus_log1p(q);
        for (int l = 0; l < sh::kLanes; ++l) {
            const long double ref = reference_q_minus_log1p(q[l]);
            worst = std::max(worst, static_cast<double>(std::fabs((value[l] - ref) / ref)));
        }
    }
    std::printf("q - log(1 + q): largest relative error %.2e over [-0.75, 10] scaled down to 1e-12\n", worst);
    assert_true(worst <= 8.0 * std::numeric_limits<double>::epsilon());
}

/// A rotation per lane (random unit quaternions).
void random_rotations(std::mt19937_64& rng, double (&R)[sh::kLanes][3][3]) {
    std::normal_distribution<double> normal;
    for (int l = 0; l < sh::kLanes; ++l) {
        double q[4], n = 0.0;
        for (double& c : q) {
            c = normal(rng);
            n += c * c;
        }
        for (double& c : q) c /= std::sqrt(n);
        const double w = q[0], x = q[1], y = q[2], z = q[3];
        const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                                {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                                {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) R[l][i][j] = r[i][j];
    }
}

/// The same at F = R (I + e A), a turned body: every rotation-invariant law's energy is
/// linear elasticity's at e sym(A) to O(e). F's own rounding (eps per entry, on entries of
/// size one) is eps / e of the strain, so the bound is that, not psi's round-off: a law whose
/// formula cancels O(mu) terms there (the neo-Hookean energy written in H = F - I) is off by
/// eps / e^2 instead.
template <class Law>
void check_turned(int row) {
    if constexpr (Law::kModel == SH_MATERIAL_LINEAR) return;  // not rotation invariant
    std::mt19937_64 rng(17 + static_cast<unsigned>(row));
    std::uniform_real_distribution<double> entry(-1.0, 1.0);
    for (double e = 1e-2; e >= 1e-8; e *= 0.1) {
        double G[sh::kLanes][3][3], R[sh::kLanes][3][3];
        random_rotations(rng, R);
        sh::Mat3L F;
        for (int l = 0; l < sh::kLanes; ++l) {
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) G[l][i][j] = e * entry(rng);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    double f = R[l][i][j];
                    for (int k = 0; k < 3; ++k) f += R[l][i][k] * G[l][k][j];
                    F.m[i][j][l] = f;
                }
        }
        const sh::Lanes psi = Law::energy(F, sh::splat(kLambda), sh::splat(kMu));
        double worst = 0.0;
        for (int l = 0; l < sh::kLanes; ++l) worst = std::max(worst, std::abs(psi[l] / linear_energy(G[l]) - 1.0));
        std::printf("model %d turned, strain %.0e: largest |psi / psi_lin - 1| = %.2e\n", static_cast<int>(Law::kModel), e, worst);
        assert_true(worst <= 8.0 * e + 64.0 * std::numeric_limits<double>::epsilon() / e);
    }
}

void every_law_matches_linear_elasticity_at_small_strain(void**) {
    sh::for_each_material([&](auto law, int row) { check_law<decltype(law)>(row); });
}

void every_invariant_law_matches_it_turned(void**) {
    sh::for_each_material([&](auto law, int row) { check_turned<decltype(law)>(row); });
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {cmocka_unit_test(every_law_matches_linear_elasticity_at_small_strain),
                                cmocka_unit_test(every_invariant_law_matches_it_turned),
                                cmocka_unit_test(neo_hookean_log_term_is_accurate_near_zero)};
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
