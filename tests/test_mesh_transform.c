/* sh_mesh_transform: a scaled and translated copy (e.g. a file in centimetres to metres). */
#include "test_support.h"

#include <stdlib.h>
#include <string.h>

static void test_scale_and_translate(void** state) {
    (void)state;
    sh_mesh* liver = NULL;
    assert_ok(sh_mesh_load(SH_TEST_MESH("liver.msh"), &liver));
    const double t[3] = {0.5, -1.0, 2.0};
    sh_mesh* moved = NULL;
    assert_ok(sh_mesh_transform(liver, 0.01, t, &moved));
    sh_mesh_info a, b;
    assert_ok(sh_mesh_get_info(liver, &a));
    assert_ok(sh_mesh_get_info(moved, &b));
    assert_int_equal(b.node_count, a.node_count);
    assert_int_equal(b.tet_count, a.tet_count);
    assert_int_equal(b.surface_triangle_count, a.surface_triangle_count);
    assert_close(b.volume / 1e-6, a.volume, 1e-12); /* volume scales by s^3 */
    double* x = malloc(sizeof(double) * 3 * a.node_count);
    double* y = malloc(sizeof(double) * 3 * a.node_count);
    assert_ok(sh_mesh_get_nodes(liver, x, a.node_count));
    assert_ok(sh_mesh_get_nodes(moved, y, a.node_count));
    for (int k = 0; k < 3 * a.node_count; ++k) assert_close(y[k], 0.01 * x[k] + t[k % 3], 1e-15);
    for (int k = 0; k < 3; ++k) assert_close(b.bounds_min[k], 0.01 * a.bounds_min[k] + t[k], 1e-14);
    free(x);
    free(y);
    assert_ok(sh_mesh_destroy(moved));
    assert_status(sh_mesh_transform(liver, 0.0, NULL, &moved), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "scale"));
    assert_null(moved);
    assert_ok(sh_mesh_destroy(liver));
    assert_status(sh_mesh_transform(liver, 1.0, NULL, &moved), SH_ERR_INVALID_HANDLE);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_scale_and_translate)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
