/* One tetrahedron against hand-derived forces, and rigid-motion invariance of the nonlinear
 * materials. Rest tet: X0 = 0, Xa = s e_a, so Dm = s I, Bm = I/s, V0 = s^3/6 and the nodal
 * forces are f_a = -(s^2/6) P e_a (a = 1..3), f_0 = -(f_1 + f_2 + f_3). */
#include "test_support.h"

#include <math.h>
#include <string.h>

static const double kSide = 0.1;      /* s (m) */
static const double kYoung = 1.0e4;   /* Pa */
static const double kPoisson = 0.3;

static double lame_lambda(void) { return kYoung * kPoisson / ((1 + kPoisson) * (1 - 2 * kPoisson)); }
static double lame_mu(void) { return kYoung / (2 * (1 + kPoisson)); }

typedef struct {
    sh_world* world;
    sh_mesh* mesh;
    sh_body_id body;
} tet_scene;

static tet_scene make_tet(sh_material_model model) {
    tet_scene s;
    s.world = sh_test_world(0.0);
    s.mesh = sh_test_unit_tet(kSide);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = s.mesh;
    def.material.model = model;
    def.material.young = kYoung;
    def.material.poisson = kPoisson;
    def.material.density = 1000.0;
    assert_ok(sh_fem_body_create(s.world, &def, &s.body));
    return s;
}

static void free_tet(tet_scene* s) {
    assert_ok(sh_world_destroy(s->world));
    assert_ok(sh_mesh_destroy(s->mesh));
}

/* Positions x = F X of the rest tet. */
static void deform(const double F[3][3], double x[12]) {
    const double X[4][3] = {{0, 0, 0}, {kSide, 0, 0}, {0, kSide, 0}, {0, 0, kSide}};
    for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) x[3 * a + i] = F[i][0] * X[a][0] + F[i][1] * X[a][1] + F[i][2] * X[a][2];
}

/* Expected forces from a first Piola stress P (hand-derived per material in each test). */
static void forces_from_stress(const double P[3][3], double f[12]) {
    const double w = -kSide * kSide / 6.0;
    for (int i = 0; i < 3; ++i) f[i] = 0.0;
    for (int a = 1; a < 4; ++a)
        for (int i = 0; i < 3; ++i) {
            f[3 * a + i] = w * P[i][a - 1];
            f[i] -= f[3 * a + i];
        }
}

/* Puts the body in the shape x = F X and reads its elastic forces. */
static void forces_at(tet_scene* s, const double F[3][3], double x[12], double f[12]) {
    deform(F, x);
    assert_ok(sh_body_set_positions(s->world, s->body, x, 4));
    assert_ok(sh_body_get_elastic_forces(s->world, s->body, f, 4));
}

static void assert_forces(tet_scene* s, const double F[3][3], const double P[3][3]) {
    double x[12], got[12], expected[12];
    forces_at(s, F, x, got);
    forces_from_stress(P, expected);
    const double scale = kYoung * kSide * kSide;
    for (int k = 0; k < 12; ++k) assert_close(got[k] / scale, expected[k] / scale, 1e-12);
}

/* Uniaxial stretch F = diag(1+e, 1, 1). */
static void test_uniaxial_stretch(void** state) {
    (void)state;
    const double e = 0.05, lambda = lame_lambda(), mu = lame_mu();
    const double F[3][3] = {{1 + e, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    /* StVK: E11 = e + e^2/2, S = diag(l+2m, l, l) E11, P = F S. */
    const double E11 = e + 0.5 * e * e;
    const double P_stvk[3][3] = {{(1 + e) * (lambda + 2 * mu) * E11, 0, 0}, {0, lambda * E11, 0}, {0, 0, lambda * E11}};
    tet_scene s = make_tet(SH_MATERIAL_STVK);
    assert_forces(&s, F, P_stvk);
    double energy;
    assert_ok(sh_body_get_elastic_energy(s.world, s.body, &energy));
    assert_close(energy, kSide * kSide * kSide / 6.0 * (mu + 0.5 * lambda) * E11 * E11, 1e-12);
    free_tet(&s);
    /* Linear: eps = diag(e, 0, 0), P = diag(l+2m, l, l) e. */
    const double P_lin[3][3] = {{(lambda + 2 * mu) * e, 0, 0}, {0, lambda * e, 0}, {0, 0, lambda * e}};
    s = make_tet(SH_MATERIAL_LINEAR);
    assert_forces(&s, F, P_lin);
    free_tet(&s);
}

/* Simple shear F = I + g e1 e2^T. */
static void test_simple_shear(void** state) {
    (void)state;
    const double g = 0.1, lambda = lame_lambda(), mu = lame_mu();
    const double F[3][3] = {{1, g, 0}, {0, 1, 0}, {0, 0, 1}};
    /* Linear: eps = g/2 (e1e2^T + e2e1^T), tr eps = 0, P = mu g (e1e2^T + e2e1^T). */
    const double P_lin[3][3] = {{0, mu * g, 0}, {mu * g, 0, 0}, {0, 0, 0}};
    tet_scene s = make_tet(SH_MATERIAL_LINEAR);
    assert_forces(&s, F, P_lin);
    free_tet(&s);
    /* StVK: E12 = g/2, E22 = g^2/2, tr E = g^2/2; S = l trE I + 2 mu E; P = F S. */
    const double tr = 0.5 * g * g;
    const double S11 = lambda * tr, S22 = lambda * tr + mu * g * g, S33 = lambda * tr, S12 = mu * g;
    const double P_stvk[3][3] = {{S11 + g * S12, S12 + g * S22, 0}, {S12, S22, 0}, {0, 0, S33}};
    s = make_tet(SH_MATERIAL_STVK);
    assert_forces(&s, F, P_stvk);
    free_tet(&s);
}

/* A rotation matrix from a unit quaternion. */
static void rotation(double w, double x, double y, double z, double R[3][3]) {
    const double n = sqrt(w * w + x * x + y * y + z * z);
    w /= n, x /= n, y /= n, z /= n;
    const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                            {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                            {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    memcpy(R, r, sizeof r);
}

/* Under x -> R x + t: zero force for the rest shape; for a deformed shape the energy is
 * unchanged (1e-12 relative) and the forces rotate with R. */
static void check_rigid_invariance(sh_material_model model) {
    const double quaternions[3][4] = {{0.3, -0.5, 0.7, 0.2}, {-0.9, 0.1, 0.2, -0.4}, {0.05, 0.99, -0.3, 0.6}};
    const double t[3] = {0.37, -1.25, 2.5};
    const double F0[3][3] = {{1.12, 0.07, -0.03}, {0.02, 0.91, 0.05}, {-0.06, 0.04, 1.04}};
    tet_scene s = make_tet(model);
    double x0[12], f0[12], e0;
    forces_at(&s, F0, x0, f0);
    assert_ok(sh_body_get_elastic_energy(s.world, s.body, &e0));
    assert_true(e0 > 0.0);
    const double identity[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const double force_scale = kYoung * kSide * kSide;
    for (int q = 0; q < 3; ++q) {
        double R[3][3];
        rotation(quaternions[q][0], quaternions[q][1], quaternions[q][2], quaternions[q][3], R);
        for (int deformed = 0; deformed < 2; ++deformed) {
            double x[12], ref[12], f[12], e;
            deform(identity, ref);
            if (deformed) memcpy(ref, x0, sizeof ref);
            for (int a = 0; a < 4; ++a)
                for (int i = 0; i < 3; ++i)
                    x[3 * a + i] = R[i][0] * ref[3 * a] + R[i][1] * ref[3 * a + 1] + R[i][2] * ref[3 * a + 2] + t[i];
            assert_ok(sh_body_set_positions(s.world, s.body, x, 4));
            assert_ok(sh_body_get_elastic_forces(s.world, s.body, f, 4));
            assert_ok(sh_body_get_elastic_energy(s.world, s.body, &e));
            for (int a = 0; a < 4; ++a)
                for (int i = 0; i < 3; ++i) {
                    double expected = 0.0;
                    if (deformed)
                        expected = R[i][0] * f0[3 * a] + R[i][1] * f0[3 * a + 1] + R[i][2] * f0[3 * a + 2];
                    assert_true(fabs(f[3 * a + i] - expected) <= 1e-12 * force_scale);
                }
            if (deformed)
                assert_true(fabs(e - e0) <= 1e-12 * e0);
            else
                assert_true(fabs(e) <= 1e-12 * e0);
        }
    }
    free_tet(&s);
}

static void test_rigid_invariance_stvk(void** state) { (void)state; check_rigid_invariance(SH_MATERIAL_STVK); }
static void test_rigid_invariance_corotational(void** state) { (void)state; check_rigid_invariance(SH_MATERIAL_COROTATIONAL); }
static void test_rigid_invariance_neohookean(void** state) { (void)state; check_rigid_invariance(SH_MATERIAL_NEOHOOKEAN); }

/* Every model reduces to linear elasticity at small strain: forces agree to O(strain^2). */
static void test_small_strain_limit(void** state) {
    (void)state;
    const double e = 1e-6;
    const double F[3][3] = {{1 + e, 0.5 * e, 0}, {-0.3 * e, 1 - 0.2 * e, 0.7 * e}, {0.1 * e, 0, 1 + 0.4 * e}};
    double reference[12];
    const sh_material_model models[4] = {SH_MATERIAL_LINEAR, SH_MATERIAL_STVK, SH_MATERIAL_COROTATIONAL, SH_MATERIAL_NEOHOOKEAN};
    for (int m = 0; m < 4; ++m) {
        tet_scene s = make_tet(models[m]);
        double x[12], f[12];
        forces_at(&s, F, x, f);
        if (m == 0) memcpy(reference, f, sizeof f);
        const double scale = kYoung * kSide * kSide * e;  /* size of the linear force */
        for (int k = 0; k < 12; ++k) assert_true(fabs(f[k] - reference[k]) <= 1e-4 * scale);
        free_tet(&s);
    }
}

/* Forces are minus the energy gradient (central differences), for every model. */
static void test_forces_are_energy_gradient(void** state) {
    (void)state;
    const double F[3][3] = {{1.2, 0.1, 0.0}, {-0.05, 0.85, 0.1}, {0.03, 0.02, 1.1}};
    const sh_material_model models[4] = {SH_MATERIAL_LINEAR, SH_MATERIAL_STVK, SH_MATERIAL_COROTATIONAL, SH_MATERIAL_NEOHOOKEAN};
    for (int m = 0; m < 4; ++m) {
        tet_scene s = make_tet(models[m]);
        double x[12], f[12];
        forces_at(&s, F, x, f);
        const double h = 1e-6 * kSide;
        for (int k = 0; k < 12; ++k) {
            double xp[12], ep, em;
            memcpy(xp, x, sizeof x);
            xp[k] += h;
            assert_ok(sh_body_set_positions(s.world, s.body, xp, 4));
            assert_ok(sh_body_get_elastic_energy(s.world, s.body, &ep));
            xp[k] -= 2 * h;
            assert_ok(sh_body_set_positions(s.world, s.body, xp, 4));
            assert_ok(sh_body_get_elastic_energy(s.world, s.body, &em));
            const double gradient = (ep - em) / (2 * h);
            assert_true(fabs(f[k] + gradient) <= 1e-6 * kYoung * kSide * kSide);
        }
        free_tet(&s);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_uniaxial_stretch),
        cmocka_unit_test(test_simple_shear),
        cmocka_unit_test(test_rigid_invariance_stvk),
        cmocka_unit_test(test_rigid_invariance_corotational),
        cmocka_unit_test(test_rigid_invariance_neohookean),
        cmocka_unit_test(test_small_strain_limit),
        cmocka_unit_test(test_forces_are_energy_gradient),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
