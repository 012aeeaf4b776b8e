/* The log callback: installed before any object, it receives the step's and the mesh's
 * messages on the calling (sim) thread; it cannot change while objects are alive. */
#include "test_support.h"

#include <stdio.h>
#include <string.h>

typedef struct log_record {
    int count[SH_LOG_COUNT];
    char last[SH_LOG_COUNT][512];
} log_record;

static void record(sh_log_level level, const char* message, void* user) {
    log_record* r = (log_record*)user;
    ++r->count[level];
    strncpy(r->last[level], message, sizeof r->last[level] - 1);
}

static void test_step_and_mesh_messages_reach_the_callback(void** state) {
    (void)state;
    log_record r;
    memset(&r, 0, sizeof r);
    assert_ok(sh_set_log_callback(record, &r));
    /* A mesh with its one tet inverted: reoriented, and said so. */
    const double nodes[12] = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01};
    const int32_t inverted[4] = {0, 2, 1, 3};
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_create(nodes, 4, inverted, 1, &mesh));
    assert_int_equal(r.count[SH_LOG_INFO], 1);
    assert_non_null(strstr(r.last[SH_LOG_INFO], "1 inverted tets reoriented"));
    /* An explicit step 10x its critical step: split into sub-steps, said so (with the count). */
    sh_world* world = sh_test_world(-9.81);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    sh_step_report report;
    assert_ok(sh_world_step(world, 10.0 * info.dt_critical, &report));
    assert_true(report.substeps > 1);
    char expected[64];
    snprintf(expected, sizeof expected, "split into %d sub-steps", report.substeps);
    assert_int_equal(r.count[SH_LOG_INFO], 2);
    assert_non_null(strstr(r.last[SH_LOG_INFO], expected));
    /* Objects alive: the callback stays. */
    assert_int_equal(sh_set_log_callback(NULL, NULL), SH_ERR_BUSY);
    sh_world_destroy(world);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_set_log_callback(NULL, NULL));
    /* Removed: nothing more arrives. */
    assert_ok(sh_mesh_create(nodes, 4, inverted, 1, &mesh));
    assert_int_equal(r.count[SH_LOG_INFO], 2);
    assert_ok(sh_mesh_destroy(mesh));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_step_and_mesh_messages_reach_the_callback),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
