/* Hertz contact: a rigid sphere (R = 10 mm) pressed into a linear elastic block (E = 10 kPa,
 * nu = 0.3) with its bottom fixed, on a structured tet mesh graded towards the contact.
 *
 * The library's answer is sh_world_solve_static with a sphere tool (penalty contact, exponent 1,
 * no damping, no friction) posed at indentations d with d / R < 0.1. It is compared with
 *  - Hertz's half-space law F = 4/3 E* sqrt(R) d^(3/2), E* = E / (1 - nu^2) (within 15 %: linear
 *    tets are stiffer than the continuum and the block is finite with a fixed bottom), and
 *  - an exact frictionless contact solve on the same mesh written here (within 5 %): minimise
 *    1/2 u^T K u with u = 0 on the bottom and n_i . u_i >= g_i on the top nodes under the sphere
 *    (n_i = (X_i - c) / |X_i - c|, g_i = R - |X_i - c|: "outside the sphere" linearised), by an
 *    active-set method whose equality-constrained subproblems are solved by projected
 *    conjugate gradients, block-Jacobi preconditioned with the node blocks of K assembled here
 *    from the linear tet's element stiffness. The library serves only as the operator
 *    K v = -(elastic force at X + v) of a second, contact-free copy of the body. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ---- Problem ------------------------------------------------------------------------------ */

#define RADIUS 0.01  /* sphere radius R (m) */
#define YOUNG 1e4    /* E (Pa) */
#define POISSON 0.3  /* nu */
#define PENALTY 1e4  /* contact stiffness per node (N/m), exponent 1 */

/* Indentations d (m), d / R < 0.1; each static solve starts from the previous one's state. */
static const double kIndentations[] = {0.2e-3, 0.5e-3, 0.8e-3};
#define INDENTATION_COUNT ((int)(sizeof kIndentations / sizeof kIndentations[0]))

/* Mesh: cells of H_FINE for |x|, |y| <= CORE (the contact radius sqrt(R d) reaches 2.83 mm) and
 * for z >= -CORE_DEPTH, then growing by at most GROWTH per cell out to the block
 * [-HALF_WIDTH, HALF_WIDTH]^2 x [-DEPTH, 0]: 34 x 34 x 11 cells, 76k tets, about 40 s here with
 * the library's static solves taking most of it. Measured exact-solve F / Hertz at d = 0.2 ..
 * 0.8 mm while choosing it: the block's size matters most, the fixed bottom stiffening the larger
 * contacts most (this mesh in 40 x 40 x 20 mm: 1.14 .. 1.23; 120 x 120 x 60: 1.10 .. 1.13;
 * 240 x 240 x 120: 1.09 .. 1.11), the growth ratio next (1.3 instead of 1.5: 1.08 .. 1.10, at
 * twice the tets), the fine spacing least (on a 60 x 60 x 30 mm block, 0.25 -> 0.35 -> 0.5 mm
 * raised it by under 1 % each). */
#define H_FINE 0.4e-3
#define CORE 2.8e-3
#define CORE_DEPTH 0.4e-3
#define GROWTH 1.5
#define HALF_WIDTH 60e-3
#define DEPTH 60e-3

/* Static solve tolerance (N: no load is applied, so the residual is absolute) and the exact
 * solve's projected-residual tolerance relative to its contact reactions. */
#define STATIC_TOL 1e-7
#define EXACT_TOL 1e-6

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* ---- Graded grid ---------------------------------------------------------------------------- */

/* Node positions 0 = p[0] < p[1] < ... < p[n] = length along one direction: cells of h (adjusted
 * down so that a whole number of them fills `core`), then cells h q, h q^2, ... with q <= growth
 * the smallest ratio for which the fewest such cells end exactly at `length`. Writes at most
 * capacity positions and returns the cell count n. */
static int graded_positions(double h, double core, double growth, double length, double* p, int capacity) {
    const int core_cells = (int)ceil(core / h - 1e-9);
    const double hc = core / core_cells;
    int n = 0;
    p[0] = 0.0;
    for (int i = 1; i <= core_cells; ++i) p[++n] = core * i / core_cells;
    const double rest = length - core;
    if (rest <= 0.0) return n;
    /* Fewest cells m with hc (q + ... + q^m) >= rest at q = growth; then q in [1, growth] by
     * bisection so that the sum is exactly rest. */
    int m = 1;
    for (double sum = hc * growth, term = hc * growth; sum < rest; ++m) {
        term *= growth;
        sum += term;
    }
    double lo = 1.0, hi = growth;
    for (int it = 0; it < 200; ++it) {
        const double q = 0.5 * (lo + hi);
        double sum = 0.0, term = hc;
        for (int k = 0; k < m; ++k) sum += (term *= q);
        if (sum < rest) lo = q;
        else hi = q;
    }
    const double q = 0.5 * (lo + hi);
    double term = hc;
    for (int k = 1; k <= m; ++k) {
        assert_true(n + 1 < capacity);
        term *= q;
        p[n + 1] = k == m ? length : p[n] + term;
        ++n;
    }
    return n;
}

typedef struct {
    double* nodes;  /* node_count x 3 rest positions */
    int32_t* tets;
    int32_t node_count, tet_count;
    sh_mesh* mesh;
} block_mesh;

/* The block [-HALF_WIDTH, HALF_WIDTH]^2 x [-DEPTH, 0], graded towards the top centre. */
static block_mesh make_block(void) {
    enum { kCap = 512 };
    double side[kCap], down[kCap], xs[2 * kCap], zs[kCap];
    const int ns = graded_positions(H_FINE, CORE, GROWTH, HALF_WIDTH, side, kCap);
    const int nz = graded_positions(H_FINE, CORE_DEPTH, GROWTH, DEPTH, down, kCap);
    for (int i = 0; i <= ns; ++i) {
        xs[ns - i] = -side[i];
        xs[ns + i] = side[i];
    }
    for (int k = 0; k <= nz; ++k) zs[nz - k] = -down[k];
    block_mesh b;
    sh_test_grid_arrays(xs, 2 * ns, xs, 2 * ns, zs, nz, &b.nodes, &b.node_count, &b.tets, &b.tet_count);
    assert_non_null(b.nodes);
    assert_non_null(b.tets);
    assert_ok(sh_mesh_create(b.nodes, b.node_count, b.tets, b.tet_count, &b.mesh));
    return b;
}

static void free_block(block_mesh* b) {
    assert_ok(sh_mesh_destroy(b->mesh));
    free(b->nodes);
    free(b->tets);
}

static sh_body_id add_block_body(sh_world* world, const block_mesh* b) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = b->mesh;
    def.material.model = SH_MATERIAL_LINEAR;
    def.material.young = YOUNG;
    def.material.poisson = POISSON;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    return body;
}

/* ---- Exact frictionless contact on the mesh ------------------------------------------------ */

typedef struct {
    const block_mesh* mesh;
    sh_world* world;   /* contact-free copy of the body: the stiffness operator */
    sh_body_id body;
    int n;             /* nodes */
    unsigned char* fixed;   /* bottom nodes */
    double* block_inverse;  /* n x 9: inverses of the 3x3 node blocks of K (0 on fixed nodes) */
    double* f0;             /* elastic forces at the rest positions (round-off) */
    double* x;              /* scratch positions */
    double* force;          /* scratch forces */
    int candidate_count;
    int32_t* candidates;    /* top nodes that may touch the sphere */
    unsigned char* active;  /* per candidate */
    double* normal;         /* per candidate, 3 */
    double* gap;            /* per candidate */
    double* u;              /* n x 3 displacement, the solution */
    long matvecs;
} exact_solver;

/* Inverse of the 3x3 matrix a (row-major) into out; returns its determinant. */
static double inverse3(const double* a, double* out) {
    const double c00 = a[4] * a[8] - a[5] * a[7], c01 = a[5] * a[6] - a[3] * a[8], c02 = a[3] * a[7] - a[4] * a[6];
    const double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    out[0] = c00 / det;
    out[1] = (a[2] * a[7] - a[1] * a[8]) / det;
    out[2] = (a[1] * a[5] - a[2] * a[4]) / det;
    out[3] = c01 / det;
    out[4] = (a[0] * a[8] - a[2] * a[6]) / det;
    out[5] = (a[2] * a[3] - a[0] * a[5]) / det;
    out[6] = c02 / det;
    out[7] = (a[1] * a[6] - a[0] * a[7]) / det;
    out[8] = (a[0] * a[4] - a[1] * a[3]) / det;
    return det;
}

/* Node blocks of the linear tet stiffness: with the shape-function gradients b_a and volume V,
 * K_aa = V ((lambda + mu) b_a b_a^T + mu |b_a|^2 I), summed over the tets of each node. */
static void assemble_block_inverse(exact_solver* s) {
    const double lambda = YOUNG * POISSON / ((1 + POISSON) * (1 - 2 * POISSON));
    const double mu = YOUNG / (2 * (1 + POISSON));
    double* blocks = calloc(9 * (size_t)s->n, sizeof(double));
    const double* X = s->mesh->nodes;
    for (int t = 0; t < s->mesh->tet_count; ++t) {
        const int32_t* tet = &s->mesh->tets[4 * t];
        double e[3][3];  /* edge vectors X_a - X_0, a = 1..3, as rows */
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < 3; ++k) e[a][k] = X[3 * tet[a + 1] + k] - X[3 * tet[0] + k];
        double inv[9];
        const double det = inverse3(&e[0][0], inv);
        const double volume = det / 6.0;
        assert_true(volume > 0.0);
        /* grad N_a (a = 1..3) is column a-1 of inv(E) for E with rows e_a; grad N_0 = -sum. */
        double b[4][3];
        for (int k = 0; k < 3; ++k) {
            b[1][k] = inv[3 * k + 0];
            b[2][k] = inv[3 * k + 1];
            b[3][k] = inv[3 * k + 2];
            b[0][k] = -(b[1][k] + b[2][k] + b[3][k]);
        }
        for (int a = 0; a < 4; ++a) {
            double* blk = &blocks[9 * tet[a]];
            const double bb = b[a][0] * b[a][0] + b[a][1] * b[a][1] + b[a][2] * b[a][2];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    blk[3 * i + j] += volume * ((lambda + mu) * b[a][i] * b[a][j] + (i == j ? mu * bb : 0.0));
        }
    }
    for (int i = 0; i < s->n; ++i) {
        if (s->fixed[i]) {
            memset(&s->block_inverse[9 * i], 0, 9 * sizeof(double));
            continue;
        }
        assert_true(inverse3(&blocks[9 * i], &s->block_inverse[9 * i]) > 0.0);
    }
    free(blocks);
}

/* out = K v through the library: -(f(X + v) - f(X)) with v scaled to a largest component of
 * 1 mm (so that X + v keeps v's digits) and the result scaled back. */
static void apply_k(exact_solver* s, const double* v, double* out) {
    const int n3 = 3 * s->n;
    double vmax = 0.0;
    for (int i = 0; i < n3; ++i) vmax = fmax(vmax, fabs(v[i]));
    if (vmax == 0.0) {
        memset(out, 0, sizeof(double) * n3);
        return;
    }
    const double scale = 1e-3 / vmax;
    for (int i = 0; i < n3; ++i) s->x[i] = s->mesh->nodes[i] + scale * v[i];
    assert_ok(sh_body_set_positions(s->world, s->body, s->x, s->n));
    assert_ok(sh_body_get_elastic_forces(s->world, s->body, s->force, n3 / 3));
    for (int i = 0; i < n3; ++i) out[i] = -(s->force[i] - s->f0[i]) / scale;
    ++s->matvecs;
}

/* Projection onto the free directions: zero on fixed nodes and along n on active nodes. */
static void project(const exact_solver* s, double* v) {
    for (int i = 0; i < s->n; ++i)
        if (s->fixed[i]) v[3 * i] = v[3 * i + 1] = v[3 * i + 2] = 0.0;
    for (int c = 0; c < s->candidate_count; ++c) {
        if (!s->active[c]) continue;
        double* w = &v[3 * s->candidates[c]];
        const double* nn = &s->normal[3 * c];
        const double d = w[0] * nn[0] + w[1] * nn[1] + w[2] * nn[2];
        for (int k = 0; k < 3; ++k) w[k] -= d * nn[k];
    }
}

static double dot(const double* a, const double* b, int n) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += a[i] * b[i];
    return sum;
}

static exact_solver make_exact_solver(const block_mesh* mesh) {
    exact_solver s;
    memset(&s, 0, sizeof s);
    s.mesh = mesh;
    s.n = mesh->node_count;
    s.world = sh_test_world(0.0);
    s.body = add_block_body(s.world, mesh);
    const int n3 = 3 * s.n;
    s.fixed = calloc(s.n, 1);
    s.block_inverse = malloc(sizeof(double) * 9 * s.n);
    s.f0 = malloc(sizeof(double) * n3);
    s.x = malloc(sizeof(double) * n3);
    s.force = malloc(sizeof(double) * n3);
    s.u = calloc(n3, sizeof(double));
    s.candidates = malloc(sizeof(int32_t) * s.n);
    for (int i = 0; i < s.n; ++i) {
        const double* p = &mesh->nodes[3 * i];
        s.fixed[i] = p[2] < -DEPTH + 1e-12;
        /* Top nodes within 0.6 R of the axis: the contact radius sqrt(R d) stays below 0.32 R. */
        if (p[2] > -1e-12 && p[0] * p[0] + p[1] * p[1] < 0.36 * RADIUS * RADIUS) {
            s.candidates[s.candidate_count++] = i;
        }
    }
    s.active = calloc(s.candidate_count, 1);
    s.normal = malloc(sizeof(double) * 3 * s.candidate_count);
    s.gap = malloc(sizeof(double) * s.candidate_count);
    assert_ok(sh_body_set_positions(s.world, s.body, mesh->nodes, s.n));
    assert_ok(sh_body_get_elastic_forces(s.world, s.body, s.f0, n3 / 3));
    assemble_block_inverse(&s);
    return s;
}

static void free_exact_solver(exact_solver* s) {
    assert_ok(sh_world_destroy(s->world));
    free(s->fixed);
    free(s->block_inverse);
    free(s->f0);
    free(s->x);
    free(s->force);
    free(s->u);
    free(s->candidates);
    free(s->active);
    free(s->normal);
    free(s->gap);
}

/* Sets u's normal components on active nodes to their gaps and u = 0 on fixed nodes. */
static void impose_constraints(exact_solver* s) {
    for (int i = 0; i < s->n; ++i)
        if (s->fixed[i]) s->u[3 * i] = s->u[3 * i + 1] = s->u[3 * i + 2] = 0.0;
    for (int c = 0; c < s->candidate_count; ++c) {
        if (!s->active[c]) continue;
        double* w = &s->u[3 * s->candidates[c]];
        const double* nn = &s->normal[3 * c];
        const double d = w[0] * nn[0] + w[1] * nn[1] + w[2] * nn[2] - s->gap[c];
        for (int k = 0; k < 3; ++k) w[k] -= d * nn[k];
    }
}

/* Projected preconditioned conjugate gradients on the current active set, from s->u (which must
 * satisfy the constraints): stops when the projected residual is below tol * ref. ku receives
 * K u. Returns the iterations. */
static int projected_pcg(exact_solver* s, double* ku, double* r, double* z, double* p, double* q, double tol) {
    const int n3 = 3 * s->n;
    apply_k(s, s->u, ku);
    double ref = 0.0;  /* size of the loads: the active nodes' reactions */
    for (int c = 0; c < s->candidate_count; ++c)
        if (s->active[c]) ref += dot(&ku[3 * s->candidates[c]], &ku[3 * s->candidates[c]], 3);
    ref = sqrt(ref);
    for (int i = 0; i < n3; ++i) r[i] = -ku[i];
    project(s, r);
    int it = 0;
    double rz = 0.0;
    for (; it < 20000; ++it) {
        if (sqrt(dot(r, r, n3)) <= tol * ref) break;
        for (int i = 0; i < s->n; ++i) {
            const double* m = &s->block_inverse[9 * i];
            const double* ri = &r[3 * i];
            for (int k = 0; k < 3; ++k) z[3 * i + k] = m[3 * k] * ri[0] + m[3 * k + 1] * ri[1] + m[3 * k + 2] * ri[2];
        }
        project(s, z);
        const double rz_new = dot(r, z, n3);
        if (it == 0) memcpy(p, z, sizeof(double) * n3);
        else
            for (int i = 0; i < n3; ++i) p[i] = z[i] + rz_new / rz * p[i];
        rz = rz_new;
        apply_k(s, p, q);
        project(s, q);
        const double alpha = rz / dot(p, q, n3);
        for (int i = 0; i < n3; ++i) {
            s->u[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
    }
    assert_true(it < 20000);
    apply_k(s, s->u, ku);  /* the true K u, not the recurrence's */
    return it;
}

typedef struct {
    double force;        /* z force on the sphere (N) */
    int active_count;    /* nodes in contact */
    int set_changes;     /* active-set iterations */
    int cg_iterations;   /* over all of them */
    double radius;       /* largest distance of a node in contact from the axis (m) */
} exact_result;

/* The exact contact solve at indentation d (sphere centre (0, 0, R - d)), warm-started from
 * s->u. The first active set is the candidates inside the sphere at rest, within `radius` of the
 * axis (a guess from the previous indentation; INFINITY for none). Each set's subproblem is
 * solved loosely until the set settles, then tightly, and the set checked again. */
static exact_result exact_contact(exact_solver* s, double d, double radius, double tol) {
    const double c[3] = {0.0, 0.0, RADIUS - d};
    for (int k = 0; k < s->candidate_count; ++k) {
        const double* X = &s->mesh->nodes[3 * s->candidates[k]];
        const double v[3] = {X[0] - c[0], X[1] - c[1], X[2] - c[2]};
        const double len = sqrt(dot(v, v, 3));
        for (int a = 0; a < 3; ++a) s->normal[3 * k + a] = v[a] / len;
        s->gap[k] = RADIUS - len;
        s->active[k] = s->gap[k] > 0.0 && X[0] * X[0] + X[1] * X[1] <= radius * radius;
    }
    const int n3 = 3 * s->n;
    double* ku = malloc(sizeof(double) * n3);
    double* r = malloc(sizeof(double) * n3);
    double* z = malloc(sizeof(double) * n3);
    double* p = malloc(sizeof(double) * n3);
    double* q = malloc(sizeof(double) * n3);
    exact_result res;
    memset(&res, 0, sizeof res);
    const double gap_tol = 1e-6 * d, loose = 1e-3;
    double cg_tol = loose;
    for (;;) {
        impose_constraints(s);
        res.cg_iterations += projected_pcg(s, ku, r, z, p, q, cg_tol);
        ++res.set_changes;
        assert_true(res.set_changes < 100);
        int changed = 0;
        for (int k = 0; k < s->candidate_count; ++k) {
            const int i = s->candidates[k];
            const double* nn = &s->normal[3 * k];
            if (s->active[k]) {
                if (dot(&ku[3 * i], nn, 3) < 0.0) { /* pulling: release */
                    s->active[k] = 0;
                    changed = 1;
                }
            } else {
                const double violation = s->gap[k] - dot(&s->u[3 * i], nn, 3);
                if (violation > gap_tol) {
                    s->active[k] = 1;
                    changed = 1;
                }
            }
        }
        if (!changed) {
            if (cg_tol == tol) break;
            cg_tol = tol; /* settled loosely: polish and check again */
        }
    }
    res.force = 0.0;
    res.radius = 0.0;
    for (int k = 0; k < s->candidate_count; ++k)
        if (s->active[k]) {
            const double* X = &s->mesh->nodes[3 * s->candidates[k]];
            res.force -= ku[3 * s->candidates[k] + 2];
            res.radius = fmax(res.radius, sqrt(X[0] * X[0] + X[1] * X[1]));
            ++res.active_count;
        }
    free(ku);
    free(r);
    free(z);
    free(p);
    free(q);
    return res;
}

/* ---- The test ------------------------------------------------------------------------------- */

/* The library's answer at each indentation: the force on the sphere, the deepest penetration and
 * the contact count of a static solve with penalty contact. */
typedef struct {
    double force[INDENTATION_COUNT];
    double depth[INDENTATION_COUNT];
    int contacts[INDENTATION_COUNT];
    double seconds; /* in the static solves */
} penalty_result;

/* The block with its bottom fixed and a sphere tool posed at indentation d (static solve each);
 * checks at each that the push is straight up and that the fixed bottom carries it. */
static penalty_result penalty_indentations(const block_mesh* mesh) {
    penalty_result r = {{0}, {0}, {0}, 0.0};
    sh_world* world = sh_test_world(0.0);
    const sh_body_id body = add_block_body(world, mesh);
    int32_t* bottom = malloc(sizeof(int32_t) * mesh->node_count);
    const int bottom_count = sh_test_nodes_at(mesh->nodes, mesh->node_count, 2, -DEPTH, bottom);
    assert_true(bottom_count > 0);
    assert_ok(sh_body_fix_nodes(world, body, bottom, bottom_count));
    sh_collider_def cd;
    sh_collider_def_default(&cd);
    cd.shape.kind = SH_SHAPE_SPHERE;
    cd.shape.radius = RADIUS;
    cd.contact.exponent = 1.0;
    cd.contact.stiffness = PENALTY;
    cd.contact.damping = 0.0;
    cd.contact.static_friction = cd.contact.dynamic_friction = 0.0;
    cd.position[2] = RADIUS + 1e-3; /* clear of the block */
    sh_tool_id tool;
    assert_ok(sh_tool_create(world, &cd, &tool));
    sh_static_def sd;
    sh_static_def_default(&sd);
    sd.tolerance = STATIC_TOL;
    double* elastic = malloc(sizeof(double) * 3 * mesh->node_count);
    for (int j = 0; j < INDENTATION_COUNT; ++j) {
        const double d = kIndentations[j];
        const double position[3] = {0.0, 0.0, RADIUS - d}, orientation[4] = {1, 0, 0, 0};
        assert_ok(sh_tool_set_pose(world, tool, position, orientation));
        sh_static_report report;
        const sh_status status = sh_world_solve_static(world, &sd, &report);
        printf("  penalty d = %.1f mm: %s, %d Newton iterations, %.1f s\n", 1e3 * d, sh_status_string(status),
               report.iterations, report.wall_seconds);
        assert_ok(status);
        r.seconds += report.wall_seconds;
        sh_contact_state cs;
        assert_ok(sh_tool_get_contact(world, tool, &cs));
        r.force[j] = cs.force[2];
        r.depth[j] = cs.max_depth;
        r.contacts[j] = cs.contact_count;
        /* The body pushes the sphere up, straight: the mesh is symmetric but for its Kuhn split. */
        assert_true(cs.force[2] > 0.0);
        assert_true(fabs(cs.force[0]) < 1e-3 * cs.force[2] && fabs(cs.force[1]) < 1e-3 * cs.force[2]);
        /* In equilibrium the fixed bottom carries what the sphere pushes: the elastic forces on
         * the free nodes balance the contact forces, and they sum to zero over all nodes. */
        assert_ok(sh_body_get_elastic_forces(world, body, elastic, mesh->node_count));
        double bottom_z = 0.0;
        for (int i = 0; i < bottom_count; ++i) bottom_z += elastic[3 * bottom[i] + 2];
        assert_close(-bottom_z / cs.force[2], 1.0, 1e-2);
    }
    free(elastic);
    free(bottom);
    assert_ok(sh_world_destroy(world));
    return r;
}

/* The exact solver's operator is linear, symmetric and positive: v^T K v > 0 and w^T K v =
 * v^T K w (this fixes the sign convention of the elastic forces), and zero at rest. */
static void check_exact_operator(exact_solver* s) {
    const int n3 = 3 * s->n;
    double f0_max = 0.0;
    for (int i = 0; i < n3; ++i) f0_max = fmax(f0_max, fabs(s->f0[i]));
    assert_true(f0_max < 1e-12);
    double* v = malloc(sizeof(double) * n3);
    double* w = malloc(sizeof(double) * n3);
    double* kv = malloc(sizeof(double) * n3);
    double* kw = malloc(sizeof(double) * n3);
    for (int i = 0; i < n3; ++i) {
        v[i] = 1e-4 * sin(0.37 * i + 0.1);
        w[i] = 1e-4 * cos(0.23 * i);
    }
    project(s, v);
    project(s, w);
    apply_k(s, v, kv);
    apply_k(s, w, kw);
    assert_true(dot(v, kv, n3) > 0.0);
    assert_close(dot(w, kv, n3) / dot(v, kv, n3), dot(v, kw, n3) / dot(v, kv, n3), 1e-9);
    free(v);
    free(w);
    free(kv);
    free(kw);
}

/* The exact contact solve of s at each indentation, warm-started from the previous one: its
 * solution scaled to the new indentation, its contact radius grown as sqrt(d) (Hertz's
 * a = sqrt(R d)) and by a cell for the first active set. */
static void exact_indentations(exact_solver* s, exact_result exact[INDENTATION_COUNT]) {
    for (int j = 0; j < INDENTATION_COUNT; ++j) {
        const double d = kIndentations[j], previous_d = j > 0 ? kIndentations[j - 1] : 0.0;
        double guess = INFINITY;
        if (j > 0) {
            for (int i = 0; i < 3 * s->n; ++i) s->u[i] *= d / previous_d;
            guess = exact[j - 1].radius * sqrt(d / previous_d) + H_FINE;
        }
        exact[j] = exact_contact(s, d, guess, EXACT_TOL);
        printf("  exact   d = %.1f mm: %d nodes in contact, %d active sets, %d CG iterations\n", 1e3 * d,
               exact[j].active_count, exact[j].set_changes, exact[j].cg_iterations);
    }
}

/* Prints the three answers side by side; returns the largest penetration over d. */
static double print_indentation_table(const penalty_result* p, const exact_result exact[INDENTATION_COUNT],
                                      const double hertz[INDENTATION_COUNT]) {
    printf("  d (mm)  F_penalty (N)  F_exact (N)  F_hertz (N)  pen/hertz  exact/hertz  pen/exact  contacts pen/exact"
           "  depth/d\n");
    double worst_depth = 0.0;
    for (int j = 0; j < INDENTATION_COUNT; ++j) {
        printf("  %6.1f  %13.6f  %11.6f  %11.6f  %9.4f  %11.4f  %9.4f  %9d / %-5d  %7.1e\n", 1e3 * kIndentations[j],
               p->force[j], exact[j].force, hertz[j], p->force[j] / hertz[j], exact[j].force / hertz[j],
               p->force[j] / exact[j].force, p->contacts[j], exact[j].active_count, p->depth[j] / kIndentations[j]);
        worst_depth = fmax(worst_depth, p->depth[j] / kIndentations[j]);
    }
    return worst_depth;
}

static void test_sphere_indentation(void** state) {
    (void)state;
#ifndef SOFTHAP_TEST_WITH_CHOLMOD
    /* Eigen's LDLT on 76 k tets would take minutes per solve: the check runs with CHOLMOD. */
    skip();
#endif
    const double t_start = now_seconds();
    block_mesh mesh = make_block();
    printf("  mesh: %d nodes, %d tets, block %.0f x %.0f x %.0f mm, finest cell %.2f mm, growth %.1f\n",
           mesh.node_count, mesh.tet_count, 2e3 * HALF_WIDTH, 2e3 * HALF_WIDTH, 1e3 * DEPTH, 1e3 * H_FINE, GROWTH);
    const penalty_result penalty = penalty_indentations(&mesh);

    const double t_exact_start = now_seconds();
    exact_solver s = make_exact_solver(&mesh);
    check_exact_operator(&s);
    exact_result exact[INDENTATION_COUNT];
    exact_indentations(&s, exact);
    const long matvecs = s.matvecs;
    free_exact_solver(&s);
    const double t_exact = now_seconds() - t_exact_start;

    const double e_star = YOUNG / (1 - POISSON * POISSON);
    double hertz[INDENTATION_COUNT];
    for (int j = 0; j < INDENTATION_COUNT; ++j) hertz[j] = 4.0 / 3.0 * e_star * sqrt(RADIUS) * pow(kIndentations[j], 1.5);
    const double worst_depth = print_indentation_table(&penalty, exact, hertz);
    printf("  largest penetration %.1e d; static solves %.1f s, exact solves %.1f s (%ld operator applications), "
           "total %.1f s\n", worst_depth, penalty.seconds, t_exact, matvecs, now_seconds() - t_start);
    for (int j = 0; j < INDENTATION_COUNT; ++j) {
        assert_true(penalty.depth[j] < 1e-3 * kIndentations[j]);
        assert_true(fabs(penalty.force[j] / hertz[j] - 1.0) < 0.15);
        assert_true(fabs(penalty.force[j] / exact[j].force - 1.0) < 0.05);
    }
    free_block(&mesh);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_indentation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
