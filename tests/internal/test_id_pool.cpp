// The generation-checked id pool of core/id_pool.hpp and the sub-step count of
// solver/substeps.hpp, through the library's internal headers: ids keep the encoding the C API
// documents, a released id stays invalid after its slot is reused, and the sub-step count
// matches the rule every sub-stepping place used before it was shared (ceil of dt over the
// longest sub-step, one if the step fits, the cap if clamped).
#include "core/id_pool.hpp"
#include "solver/substeps.hpp"

#include <cmath>
#include <cstdint>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

// An id is generation << 32 | (index + 1), and 0 names nothing.
void test_id_encoding(void**) {
    assert_true(sh::pack_id(0, 1) == ((uint64_t{1} << 32) | 1));
    assert_true(sh::id_index(sh::pack_id(7, 9)) == 7);
    assert_true(sh::id_generation(sh::pack_id(7, 9)) == 9);
    assert_true(sh::id_generation(sh::kNullId) == 0);
    assert_true(sh::next_generation() != 0);
}

// Allocate, find, release and reuse: the old id never names the slot's new value.
void test_pool_reuses_slots_under_new_generations(void**) {
    sh::IdPool<int*> pool;
    int a = 1, b = 2;
    const sh::Id ia = pool.allocate(&a);
    assert_true(pool.contains(ia));
    assert_ptr_equal(*pool.find(ia), &a);
    assert_null(pool.find(sh::kNullId));
    assert_null(pool.find(ia ^ (uint64_t{1} << 32)));
    assert_ptr_equal(pool.release(ia), &a);
    assert_false(pool.contains(ia));
    assert_int_equal(pool.live_count(), 0);
    const sh::Id ib = pool.allocate(&b);
    assert_int_equal(sh::id_index(ib), sh::id_index(ia));  // the slot is reused
    assert_true(ib != ia);
    assert_null(pool.find(ia));
    assert_ptr_equal(*pool.find(ib), &b);
    int visited = 0;
    pool.for_each([&](int* p) { visited += *p; });
    assert_int_equal(visited, 2);
}

// Two pools never accept each other's ids (one generation counter).
void test_pools_do_not_share_ids(void**) {
    sh::IdPool<int> first, second;
    const sh::Id id = first.allocate(5);
    second.allocate(6);
    assert_false(second.contains(id));
}

// The counts of the former hand-written rules: explicit (ceil(dt / dt_crit) when dt exceeds
// it), contact (tool travel over half its inner radius) and haptic (a limit of 0 is the cap).
void test_substep_count(void**) {
    const sh::SubstepCount fits = sh::substep_count(1e-3, 2e-3, 64);
    assert_int_equal(fits.count, 1);
    assert_false(fits.clamped);
    const sh::SubstepCount three = sh::substep_count(1e-3, 0.4e-3, 64);
    assert_int_equal(three.count, 3);
    assert_false(three.clamped);
    const sh::SubstepCount capped = sh::substep_count(1.0, 1e-3, sh::kMaxHapticSubsteps);
    assert_int_equal(capped.count, sh::kMaxHapticSubsteps);
    assert_true(capped.clamped);
    assert_true(sh::substep_count(1e-3, 0.0, 64).clamped);
    assert_int_equal(sh::substep_count(NAN, 1e-3, 64).count, 1);
    assert_int_equal(sh::substep_count(1e-3, NAN, 64).count, 1);
    assert_int_equal(sh::substep_count(0.0, 0.0, sh::kMaxContactSubsteps).count, 1);
    assert_false(sh::substep_count(16.0, 1.0, 16).clamped);  // a retry within max_substeps
    assert_true(sh::substep_count(32.0, 1.0, 16).clamped);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_id_encoding),
        cmocka_unit_test(test_pool_reuses_slots_under_new_generations),
        cmocka_unit_test(test_pools_do_not_share_ids),
        cmocka_unit_test(test_substep_count),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
