// How a Newton update that ends far from the potential's minimum along it is moved towards it
// (move_update_towards_line_minimum in solver/newton_problem.hpp), on potentials of one
// variable s (the update's scale) whose minimisers are known by hand.
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

    /// Extends, then checks that the update ends at `expected` (to 1e-12) after `tries` moves
    /// (-1: any number).
    void settles_at(double expected, int tries) {
        extend();
        assert_true(std::fabs(at - expected) < 1e-12);
        if (tries >= 0) assert_int_equal(moves, tries);
    }

    void extend(double roundoff = 1e-15) {
        sh::move_update_towards_line_minimum(
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
    line.settles_at(2.0, 1);
}

// (s - 10)^2 / 10: the secant through slopes -2 at 0 and -1.8 at 1 points at the minimiser 10
// updates out, but a try goes at most 8 times further than the last point: it stops at 8,
// where the slope (-0.4) is flatter than a quarter of the start's, so no second try.
void test_far_minimiser_is_approached_in_a_stride_of_eight(void**) {
    Line line{[](double s) { return (s - 10.0) * (s - 10.0) / 10.0; }, [](double s) { return (s - 10.0) / 5.0; }};
    line.settles_at(8.0, 1);
}

// phi = -s up to a wall at s = 1.5 (1 just past it, non-finite beyond 1.6): the slope stays -1,
// so the try doubles the update, lands past the wall where the potential rose, is refused,
// and the update goes back to the full one.
void test_refused_try_goes_back_to_the_full_update(void**) {
    Line line{[](double s) { return s <= 1.5 ? -s : (s < 1.6 ? 1.0 : NAN); },
              [](double s) { return s <= 1.5 ? -1.0 : 1.0; }};
    line.settles_at(1.0, -1);
}

// (s - 0.5)^2: the update went twice as far as the minimiser (slope +1 at 1 against -1 at 0,
// as from a tangent half as stiff as the potential along it): one secant back lands on 0.5.
void test_update_past_the_minimiser_comes_back_to_it(void**) {
    Line line{[](double s) { return (s - 0.5) * (s - 0.5); }, [](double s) { return 2.0 * (s - 0.5); }};
    line.settles_at(0.5, 1);
}

// phi = -s + 20 max(0, s - 0.9)^2: falling at slope -1 up to a wall at 0.9, rising at slope 3
// at the full update. The secant's zero (0.25) lies back on the straight part, where the
// potential (-0.25) is above the full update's (-0.8): refused, the update stays full.
void test_update_past_a_wall_stays_where_lower(void**) {
    Line line{[](double s) { return -s + 20.0 * std::fmax(0.0, s - 0.9) * std::fmax(0.0, s - 0.9); },
              [](double s) { return -1.0 + 40.0 * std::fmax(0.0, s - 0.9); }};
    line.settles_at(1.0, 2);  // the try, and the way back
}

// A Newton update near convergence ends flat (slope ratio below a quarter): no try at all.
void test_flat_end_takes_no_try(void**) {
    Line line{[](double s) { return (s - 1.1) * (s - 1.1); }, [](double s) { return 2.0 * (s - 1.1); }};
    line.settles_at(1.0, 0);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_way_update_lands_on_the_minimiser),
        cmocka_unit_test(test_far_minimiser_is_approached_in_a_stride_of_eight),
        cmocka_unit_test(test_refused_try_goes_back_to_the_full_update),
        cmocka_unit_test(test_update_past_the_minimiser_comes_back_to_it),
        cmocka_unit_test(test_update_past_a_wall_stays_where_lower),
        cmocka_unit_test(test_flat_end_takes_no_try),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
