/* minimal.c: the smallest complete softhap program. A 1 cm cube of soft tissue (8 nodes,
 * 6 tets) hangs from its top face under gravity for 0.1 s. */
#include <softhap/softhap.h>

#include <stdio.h>

#define CHECK(call)                                                                        \
    do {                                                                                   \
        sh_status status_ = (call);                                                        \
        if (status_ != SH_OK) {                                                            \
            fprintf(stderr, "%s: %s\n  %s\n", #call, sh_status_string(status_),            \
                    sh_last_error_message());                                              \
            goto done;                                                                     \
        }                                                                                  \
    } while (0)

int main(void) {
    static const double nodes[8 * 3] = {0, 0, 0,    0.01, 0, 0,    0.01, 0.01, 0,    0, 0.01, 0,
                                        0, 0, 0.01, 0.01, 0, 0.01, 0.01, 0.01, 0.01, 0, 0.01, 0.01};
    static const int32_t tets[6 * 4] = {0, 1, 2, 6, 0, 2, 3, 6, 0, 3, 7, 6,
                                        0, 7, 4, 6, 0, 4, 5, 6, 0, 5, 1, 6};
    static const int32_t top[4] = {4, 5, 6, 7}; /* the nodes at z = 1 cm */
    sh_world* world = NULL;
    sh_mesh* mesh = NULL;
    sh_world_def world_def;
    sh_fem_body_def body_def;
    sh_body_id body;
    sh_step_report report;
    double x[8 * 3], lowest = 1.0;
    int exit_code = 1, i;

    sh_world_def_default(&world_def); /* gravity (0, 0, -9.81) m/s^2 */
    CHECK(sh_world_create(&world_def, &world));
    CHECK(sh_mesh_create(nodes, 8, tets, 6, &mesh));
    sh_fem_body_def_default(&body_def); /* StVK, E = 3 kPa, nu = 0.45, rho = 1000 kg/m^3 */
    body_def.mesh = mesh;
    body_def.damping_mass = 5.0; /* 1/s */
    CHECK(sh_fem_body_create(world, &body_def, &body));
    CHECK(sh_body_fix_nodes(world, body, top, 4));

    for (i = 0; i < 100; ++i) CHECK(sh_world_step(world, 0.001, &report)); /* 100 x 1 ms */

    CHECK(sh_body_get_positions(world, body, x, 8));
    for (i = 0; i < 8; ++i) lowest = x[3 * i + 2] < lowest ? x[3 * i + 2] : lowest;
    printf("lowest node z = %.6f m (rest 0)\n", lowest);
    printf("energies: kinetic %.3e J, elastic %.3e J, potential %.3e J (dt_crit %.2e s)\n",
           report.kinetic_energy, report.elastic_energy, report.potential_energy, report.dt_critical);
    exit_code = 0;
done:
    sh_world_destroy(world); /* NULL is fine */
    sh_mesh_destroy(mesh);
    return exit_code;
}
