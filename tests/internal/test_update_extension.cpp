// The extension of a Newton update along which the potential still falls steeply
// (extend_update_while_falling in solver/newton_problem.hpp), on potentials of one variable s
// (the update's scale) whose minimisers are known by hand.
#include "solver/newton_problem.hpp"

#include <cmath>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

/// A potential along an update, with its slope, where the extension is.
struct Line {
    double (*phi)(double);
    double (*slope)(double);
    double at = 1.0;  // the full update: where the extension starts
    int moves = 0;

    void extend(double roundoff = 1e-15) {
        sh::extend_update_while_falling(
            slope(0.0), phi(1.0), roundoff, [&] { return slope(at); },
            [&](double s) {
                at = s;
                ++moves;
                return phi(s);
            });
    }
};

// (s - 2)^2: the update reached half way to the minimiser (slope -2 at 1 against -4 at 0, a
// ratio of one half, which the doubling rule before the secant never extended): one secant
// lands on s = 2 exactly, and the next try is not taken (the slope there is 0).
void test_half_way_update_lands_on_the_minimiser(void**) {
    Line line{[](double s) { return (s - 2.0) * (s - 2.0); }, [](double s) { return 2.0 * (s - 2.0); }};
    line.extend();
    assert_true(std::fabs(line.at - 2.0) < 1e-12);
    assert_int_equal(line.moves, 1);
}

// (s - 10)^2 / 10: the secant through slopes -2 at 0 and -1.8 at 1 points at the minimiser 10
// updates out, but a try goes at most 8 times further than the last point: it stops at 8,
// where the slope (-0.4) is flatter than a quarter of the start's, so no second try.
void test_far_minimiser_is_approached_in_a_stride_of_eight(void**) {
    Line line{[](double s) { return (s - 10.0) * (s - 10.0) / 10.0; }, [](double s) { return (s - 10.0) / 5.0; }};
    line.extend();
    assert_true(line.at == 8.0);
    assert_int_equal(line.moves, 1);
}

// phi = -s up to a wall at s = 1.5 (1 just past it, non-finite beyond 1.6): the slope stays -1,
// so the try doubles the update, lands past the wall where the potential rose, is refused,
// and the update goes back to the full one.
void test_refused_try_goes_back_to_the_full_update(void**) {
    Line line{[](double s) { return s <= 1.5 ? -s : (s < 1.6 ? 1.0 : NAN); },
              [](double s) { return s <= 1.5 ? -1.0 : 1.0; }};
    line.extend();
    assert_true(line.at == 1.0);
}

// A Newton update near convergence ends flat (slope ratio below a quarter): no try at all.
void test_flat_end_takes_no_try(void**) {
    Line line{[](double s) { return (s - 1.1) * (s - 1.1); }, [](double s) { return 2.0 * (s - 1.1); }};
    line.extend();
    assert_true(line.at == 1.0);
    assert_int_equal(line.moves, 0);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_way_update_lands_on_the_minimiser),
        cmocka_unit_test(test_far_minimiser_is_approached_in_a_stride_of_eight),
        cmocka_unit_test(test_refused_try_goes_back_to_the_full_update),
        cmocka_unit_test(test_flat_end_takes_no_try),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
