#include "solver/step_support.hpp"

#include "solver/node_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace sh {

void IntegratorWorkspace::resize(int32_t node_count) {
    const size_t n = 3 * static_cast<size_t>(node_count);
    for (vec<double>* array : {&x0, &v0, &xs, &vs}) array->resize(n);
    for (int i = 0; i < kMaxStages; ++i) {
        stage_v[i].resize(n);
        stage_a[i].resize(n);
    }
}

void IntegratorWorkspace::reserve(int32_t node_count) {
    const size_t n = 3 * static_cast<size_t>(node_count);
    for (vec<double>* array : {&x0, &v0, &xs, &vs}) reserve_growing(*array, n);
    for (int i = 0; i < kMaxStages; ++i) {
        reserve_growing(stage_v[i], n);
        reserve_growing(stage_a[i], n);
    }
}

void save_start_state(SteppedBody& stepped) {
    const Body& body = *stepped.body;
    std::copy(body.x.begin(), body.x.end(), stepped.workspace.x0.begin());
    std::copy(body.v.begin(), body.v.end(), stepped.workspace.v0.begin());
}

void restore_start_state(SteppedBody& stepped) {
    Body& body = *stepped.body;
    std::copy(stepped.workspace.x0.begin(), stepped.workspace.x0.end(), body.x.begin());
    std::copy(stepped.workspace.v0.begin(), stepped.workspace.v0.end(), body.v.begin());
}

void begin_kinematic_motion(Body& body, double dt) {
    for_each_kinematic(body.kinematic, [&](size_t i) {
        for (int k = 0; k < 3; ++k) body.v[3 * i + k] = (body.target[3 * i + k] - body.x[3 * i + k]) / dt;
    });
}

void end_kinematic_motion(Body& body) {
    const size_t n = body.mass.size();
    auto settle = [&](size_t i) {
        for (int k = 0; k < 3; ++k) {
            if (body.kinematic[i]) body.x[3 * i + k] = body.target[3 * i + k];
            body.v[3 * i + k] = 0.0;
        }
    };
    size_t i = 0;
#if defined(__AVX512F__)
    for (; i + 8 <= n; i += 8) {
        uint64_t kinematic8;
        std::memcpy(&kinematic8, &body.kinematic[i], sizeof kinematic8);
        const __mmask8 massless =
            _mm512_cmp_pd_mask(_mm512_loadu_pd(body.mass.data() + i), _mm512_setzero_pd(), _CMP_NGT_UQ);
        if (!kinematic8 && !massless) continue;
        for (size_t k = i; k < i + 8; ++k)
            if (body.kinematic[k] || !(body.mass[k] > 0.0)) settle(k);
    }
#endif
    for (; i < n; ++i)
        if (body.kinematic[i] || !(body.mass[i] > 0.0)) settle(i);
}

bool body_state_is_sane(const SteppedBody& stepped) {
    const Body& body = *stepped.body;
    const double runaway_speed = stepped.settings.runaway_speed;
    const double limit2 = runaway_speed * runaway_speed;
    const size_t n = body.mass.size();
    const double* x = body.x.data();
    const double* v = body.v.data();
    bool insane = false;
    size_t i = 0;
#if defined(__AVX512F__)
    const __m512d v_bound = _mm512_set1_pd(0.57 * runaway_speed);
    for (; i + 8 <= n; i += 8) {
        __mmask8 flagged = 0;
        for (int r = 0; r < 3; ++r)
            flagged |= outside_bounds(_mm512_loadu_pd(x + 3 * i + 8 * r), _mm512_loadu_pd(v + 3 * i + 8 * r), v_bound);
        if (flagged)
            for (size_t k = i; k < i + 8; ++k) insane |= node_insane(x, v, k, limit2);
    }
#endif
    for (; i < n; ++i) insane |= node_insane(x, v, i, limit2);
    return !insane;
}

}  // namespace sh
