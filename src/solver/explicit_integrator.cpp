#include "solver/explicit_integrator.hpp"

#include "model/external_field.hpp"
#include "solver/integrator_table.hpp"
#include "solver/node_checks.hpp"
#include "solver/step_support.hpp"
#include "solver/substeps.hpp"

#include <algorithm>
#include <cmath>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace sh {
namespace {

#if defined(__AVX512F__)
// Node loops take eight nodes (24 doubles, three registers) at a time. Per-node values are
// spread to the xyz layout with permutes; r is the register (doubles 8r .. 8r+7 of the chunk).
inline __m512d spread_nodes(__m512d per_node, int r) {
    static const int64_t kIndex[3][8] = {{0, 0, 0, 1, 1, 1, 2, 2}, {2, 3, 3, 3, 4, 4, 4, 5}, {5, 5, 6, 6, 6, 7, 7, 7}};
    return _mm512_permutexvar_pd(_mm512_loadu_si512(kIndex[r]), per_node);
}

// g[k] at the doubles of register r of a chunk.
inline __m512d spread_gravity(const double g[3], int r) {
    alignas(64) double lanes[8];
    for (int l = 0; l < 8; ++l) lanes[l] = g[(8 * r + l) % 3];
    return _mm512_load_pd(lanes);
}

#endif


// One step of h of the explicit Runge-Kutta method t: stage i's state is the start plus h
// times the a[i][j]-weighted earlier stages' derivatives, its derivative (its velocity, the
// accelerations there) is kept, and the end is the start plus h times the b-weighted sum.
void runge_kutta(Body& body, IntegratorWorkspace& w, const ButcherTableau& t, double h, const double g[3]) {
    double* x = body.x.data();
    double* v = body.v.data();
    const size_t n = body.x.size();
    for (int i = 0; i < t.stages; ++i) {
        double* xs = w.xs.data();
        double* vs = w.stage_v[i].data();
        for (size_t k = 0; k < n; ++k) {
            double dx = 0.0, dv = 0.0;
            for (int j = 0; j < i; ++j) {
                dx += t.a[i][j] * w.stage_v[j][k];
                dv += t.a[i][j] * w.stage_a[j][k];
            }
            xs[k] = x[k] + h * dx;
            vs[k] = v[k] + h * dv;
        }
        compute_accelerations(body, xs, vs, g, w.stage_a[i].data());
    }
    for (size_t k = 0; k < n; ++k) {
        double dx = 0.0, dv = 0.0;
        for (int i = 0; i < t.stages; ++i) {
            dx += t.b[i] * w.stage_v[i][k];
            dv += t.b[i] * w.stage_a[i][k];
        }
        x[k] += h * dx;
        v[k] += h * dv;
    }
}

// One symplectic Euler step of h: v += h a(x, v), then x += h v.
void symplectic_euler(Body& body, IntegratorWorkspace& w, double h, const double g[3]) {
    double* a = w.stage_a[0].data();
    compute_accelerations(body, body.x.data(), body.v.data(), g, a);
    for (size_t k = 0; k < body.x.size(); ++k) {
        body.v[k] += h * a[k];
        body.x[k] += h * body.v[k];
    }
}

void integrate(SteppedBody& stepped, double h, const double g[3]) {
    const IntegratorKind& kind = integrator_kind(stepped.settings.integrator);
    if (kind.scheme == StepScheme::RungeKutta)
        runge_kutta(*stepped.body, stepped.workspace, kind.tableau, h, g);
    else if (kind.scheme == StepScheme::SymplecticEuler)
        symplectic_euler(*stepped.body, stepped.workspace, h, g);
}

}  // namespace

void compute_accelerations(const Body& body, const double* x, const double* v, const double g[3], double* a) {
    const size_t n = body.mass.size();
    std::fill(a, a + 3 * n, 0.0);
    body.add_internal_forces(x, v, a);
    if (body.field) body.field->add_forces(x, v, a);
    const double* inv_mass = body.inverse_mass.data();
    const double* fe = body.external_force.data();
    size_t i = 0;
#if defined(__AVX512F__)
    const double alpha = body.damping_mass;
    const bool per_node = !body.node_damping.empty();
    const __m512d gv[3] = {spread_gravity(g, 0), spread_gravity(g, 1), spread_gravity(g, 2)};
    const __m512d zero = _mm512_setzero_pd(), alpha_v = _mm512_set1_pd(alpha);
    for (; i + 8 <= n; i += 8) {
        const __m512d inv8 = _mm512_loadu_pd(inv_mass + i);
        const __m512d c8 = per_node ? _mm512_add_pd(alpha_v, _mm512_loadu_pd(body.node_damping.data() + i)) : alpha_v;
        for (int r = 0; r < 3; ++r) {
            const size_t j = 3 * i + 8 * r;
            const __m512d inv = spread_nodes(inv8, r), c = per_node ? spread_nodes(c8, r) : c8;
            const __m512d load = _mm512_add_pd(_mm512_loadu_pd(a + j), _mm512_loadu_pd(fe + j));
            const __m512d acc = _mm512_fnmadd_pd(c, _mm512_loadu_pd(v + j), _mm512_fmadd_pd(load, inv, gv[r]));
            _mm512_storeu_pd(a + j, _mm512_maskz_mov_pd(_mm512_cmp_pd_mask(inv, zero, _CMP_GT_OQ), acc));
        }
    }
#endif
    for (; i < n; ++i) {
        const double inv_m = inv_mass[i];
        const double c = body.mass_damping(i);
        for (int k = 0; k < 3; ++k) {
            const size_t j = 3 * i + k;
            a[j] = inv_m > 0.0 ? (a[j] + fe[j]) * inv_m + g[k] - c * v[j] : 0.0;
        }
    }
}

namespace {


// One forward or symplectic Euler step of the whole body in one pass over the nodes, from the
// internal forces already in w.a[0]: accelerations as compute_accelerations makes them, the
// update, the start state saved to w.x0/w.v0 (kinematic nodes' velocities are patched by the
// caller), velocities of the nodes that are not integrated zeroed, and the runaway check.
// Non-free nodes are sane afterwards by construction (kinematic ones are put on their finite
// targets by the caller, orphans do not move), so only free nodes are checked.
template <bool Symplectic, bool PerNodeDamping>
struct EulerPass {
    double* __restrict x;
    double* __restrict v;
    double* __restrict x0;
    double* __restrict v0;
    const double* __restrict f;
    const double* __restrict fe;
    const double* __restrict inv_mass;
    const double* __restrict node_damping;
    double alpha, h, limit2, g[3];

    EulerPass(SteppedBody& stepped, double step, const double gravity[3])
        : x(stepped.body->x.data()), v(stepped.body->v.data()), x0(stepped.workspace.x0.data()),
          v0(stepped.workspace.v0.data()), f(stepped.workspace.stage_a[0].data()),
          fe(stepped.body->external_force.data()), inv_mass(stepped.body->inverse_mass.data()),
          node_damping(PerNodeDamping ? stepped.body->node_damping.data() : nullptr), alpha(stepped.body->damping_mass),
          h(step), limit2(stepped.settings.runaway_speed * stepped.settings.runaway_speed),
          g{gravity[0], gravity[1], gravity[2]} {}

    // Node i alone; true if it is free and insane.
    bool node(size_t i) const {
        const double inv_m = inv_mass[i];
        const double c = PerNodeDamping ? alpha + node_damping[i] : alpha;
        const bool is_free = inv_m > 0.0;
        for (int k = 0; k < 3; ++k) {
            const size_t j = 3 * i + k;
            const double xj = x[j], vj = v[j];
            const double acc = is_free ? (f[j] + fe[j]) * inv_m + g[k] - c * vj : 0.0;
            x0[j] = xj;
            v0[j] = vj;
            double xn, vn;
            if (Symplectic) {
                vn = vj + h * acc;
                xn = xj + h * vn;
            } else {
                xn = xj + h * vj;
                vn = vj + h * acc;
            }
            x[j] = xn;
            v[j] = is_free ? vn : 0.0;
        }
        return is_free && node_insane(x, v, i, limit2);
    }

    // All n nodes; true if all free nodes are sane.
    bool run(size_t n) const {
        bool insane = false;
        size_t i = 0;
#if defined(__AVX512F__)
        const __m512d gv[3] = {spread_gravity(g, 0), spread_gravity(g, 1), spread_gravity(g, 2)};
        const __m512d hv = _mm512_set1_pd(h), zero = _mm512_setzero_pd(), alpha_v = _mm512_set1_pd(alpha);
        const __m512d v_bound = _mm512_set1_pd(0.57 * std::sqrt(limit2));
        for (; i + 8 <= n; i += 8) {
            const __m512d inv8 = _mm512_loadu_pd(inv_mass + i);
            const __m512d c8 = PerNodeDamping ? _mm512_add_pd(alpha_v, _mm512_loadu_pd(node_damping + i)) : alpha_v;
            __mmask8 flagged = 0;
            for (int r = 0; r < 3; ++r) {
                const size_t j = 3 * i + 8 * r;
                const __m512d inv = spread_nodes(inv8, r), c = PerNodeDamping ? spread_nodes(c8, r) : c8;
                const __mmask8 is_free = _mm512_cmp_pd_mask(inv, zero, _CMP_GT_OQ);
                const __m512d xj = _mm512_loadu_pd(x + j), vj = _mm512_loadu_pd(v + j);
                const __m512d load = _mm512_add_pd(_mm512_loadu_pd(f + j), _mm512_loadu_pd(fe + j));
                const __m512d acc =
                    _mm512_maskz_mov_pd(is_free, _mm512_fnmadd_pd(c, vj, _mm512_fmadd_pd(load, inv, gv[r])));
                _mm512_storeu_pd(x0 + j, xj);
                _mm512_storeu_pd(v0 + j, vj);
                __m512d xn, vn;
                if (Symplectic) {
                    vn = _mm512_fmadd_pd(hv, acc, vj);
                    xn = _mm512_fmadd_pd(hv, vn, xj);
                } else {
                    xn = _mm512_fmadd_pd(hv, vj, xj);
                    vn = _mm512_fmadd_pd(hv, acc, vj);
                }
                _mm512_storeu_pd(x + j, xn);
                _mm512_storeu_pd(v + j, _mm512_maskz_mov_pd(is_free, vn));
                flagged |= is_free & outside_bounds(xn, vn, v_bound);
            }
            if (flagged)
                for (size_t k = i; k < i + 8; ++k) insane |= inv_mass[k] > 0.0 && node_insane(x, v, k, limit2);
        }
#endif
        for (; i < n; ++i) insane |= node(i);
        return !insane;
    }
};

}  // namespace

namespace {

void roll_back(SteppedBody& stepped, BodyStepResult& result) {
    restore_start_state(stepped);
    result.stable = false;
    result.status = SH_ERR_UNSTABLE;
    result.reason = kRolledBackReason;
}

}  // namespace

BodyStepResult step_explicit(SteppedBody& stepped, double dt, const double g[3]) {
    Body& body = *stepped.body;
    BodyStepResult result;
    result.dt_critical = critical_step(body, stepped.settings.integrator);
    // A step longer than the critical one is sub-stepped, unless the policy rejects it or it
    // would take more sub-steps than the cap.
    const SubstepCount substeps = substep_count(dt, result.dt_critical, kMaxExplicitSubsteps);
    if (substeps.clamped || (dt > result.dt_critical && stepped.settings.on_unstable == SH_UNSTABLE_REJECT)) {
        result.stable = false;
        result.rejected = true;
        result.status = SH_ERR_UNSTABLE;
        return result;
    }
    result.substeps = substeps.count;

    IntegratorWorkspace& w = stepped.workspace;
    const IntegratorKind& kind = integrator_kind(stepped.settings.integrator);
    const bool symplectic = kind.scheme == StepScheme::SymplecticEuler;
    const bool forward_euler = kind.scheme == StepScheme::RungeKutta && kind.tableau.stages == 1;
    if (result.substeps == 1 && (symplectic || forward_euler)) {
        // The real-time case, in two passes over the nodes besides the forces. Kinematic nodes'
        // start velocities wait in w.vs (stage state, unused by the Euler methods).
        for_each_kinematic(body.kinematic, [&](size_t i) {
            for (int k = 0; k < 3; ++k) {
                const size_t j = 3 * i + k;
                w.vs[j] = body.v[j];
                body.v[j] = (body.target[j] - body.x[j]) / dt;
            }
        });
        double* f = w.stage_a[0].data();
        std::fill(f, f + body.x.size(), 0.0);
        body.add_internal_forces(body.x.data(), body.v.data(), f);
        if (body.field) {
            body.field->begin_explicit_step();
            body.field->add_forces(body.x.data(), body.v.data(), f);
        }
        const bool per_node = !body.node_damping.empty();
        const size_t n = body.mass.size();
        const bool sane = symplectic ? (per_node ? EulerPass<true, true>(stepped, dt, g).run(n) : EulerPass<true, false>(stepped, dt, g).run(n))
                                     : (per_node ? EulerPass<false, true>(stepped, dt, g).run(n) : EulerPass<false, false>(stepped, dt, g).run(n));
        if (sane && body.field) body.field->end_explicit_step(dt, symplectic, body.x.data(), body.v.data());
        for_each_kinematic(body.kinematic, [&](size_t i) {
            for (int k = 0; k < 3; ++k) {
                const size_t j = 3 * i + k;
                w.v0[j] = w.vs[j];
                body.x[j] = body.target[j];
            }
        });
        if (!sane) roll_back(stepped, result);
        return result;
    }

    save_start_state(stepped);
    begin_kinematic_motion(body, dt);

    const double h = dt / substeps.count;
    // Friction's velocity change also moves the nodes by h times it, as if it acted through the
    // sub-step (symplectic Euler's positions take the end velocities; for RK methods it is a
    // first-order splitting); forward Euler's positions take the start velocities.
    const bool move_positions = !forward_euler;
    for (int32_t s = 0; s < result.substeps; ++s) {
        if (body.field) body.field->begin_explicit_step();
        integrate(stepped, h, g);
        if (body.field) body.field->end_explicit_step(h, move_positions, body.x.data(), body.v.data());
    }

    end_kinematic_motion(body);

    if (!body_state_is_sane(stepped)) roll_back(stepped, result);
    return result;
}

}  // namespace sh
