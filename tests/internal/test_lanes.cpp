// The lane arithmetic (material/lanes.hpp) against the standard library's, lane by lane: the
// inverse square root over the doubles' range, where the vectorised estimate and its Newton
// steps must come within a few ulp of 1 / std::sqrt, and at zero, denormals and NaN, where it
// must take the exact path.
#include "material/lanes.hpp"

#include <cmath>
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

/// lanes_rsqrt of values, kLanes at a time (the last batch padded with 1), against 1 / sqrt:
/// relative error at most 4 ulp, or the same non-finite value.
void check_rsqrt(const std::vector<double>& values) {
    for (size_t first = 0; first < values.size(); first += sh::kLanes) {
        sh::Lanes a = sh::splat(1.0);
        for (int l = 0; l < sh::kLanes && first + static_cast<size_t>(l) < values.size(); ++l) a[l] = values[first + static_cast<size_t>(l)];
        const sh::Lanes y = sh::lanes_rsqrt(a);
        for (int l = 0; l < sh::kLanes; ++l) {
            const double expected = 1.0 / std::sqrt(a[l]);
            if (!std::isfinite(expected)) {
                assert_true(std::isnan(expected) ? std::isnan(y[l]) : y[l] == expected);
                continue;
            }
            assert_true(std::fabs(y[l] - expected) <= 4.0 * std::numeric_limits<double>::epsilon() * expected);
        }
    }
}

/// Random values over the whole normal range, in full batches and mixed with the exact
/// path's inputs (a batch holding one of those takes the exact path for all its lanes).
void inverse_square_root(void**) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> exponent(-300.0, 300.0), mantissa(1.0, 10.0);
    std::vector<double> values;
    for (int n = 0; n < 4096; ++n) values.push_back(mantissa(rng) * std::pow(10.0, exponent(rng)));
    check_rsqrt(values);
    const std::vector<double> edges = {0.0, 4.9e-324, 1e-310, 2.2250738585072014e-308, 1e-290, 1e-289, 1.0,
                                       1.7976931348623157e308, std::numeric_limits<double>::quiet_NaN(),
                                       std::numeric_limits<double>::infinity(), 0.25, 4.0};
    check_rsqrt(edges);
}

}  // namespace

int main(void) {
    const CMUnitTest tests[] = {cmocka_unit_test(inverse_square_root)};
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
