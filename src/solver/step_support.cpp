#include "solver/step_support.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

void save_start_state(Body& body) {
    std::copy(body.x.begin(), body.x.end(), body.workspace.x0.begin());
    std::copy(body.v.begin(), body.v.end(), body.workspace.v0.begin());
}

void restore_start_state(Body& body) {
    std::copy(body.workspace.x0.begin(), body.workspace.x0.end(), body.x.begin());
    std::copy(body.workspace.v0.begin(), body.workspace.v0.end(), body.v.begin());
}

void begin_kinematic_motion(Body& body, double dt) {
    for (size_t i = 0; i < body.kinematic.size(); ++i)
        if (body.kinematic[i])
            for (int k = 0; k < 3; ++k) body.v[3 * i + k] = (body.target[3 * i + k] - body.x[3 * i + k]) / dt;
}

void end_kinematic_motion(Body& body) {
    for (size_t i = 0; i < body.kinematic.size(); ++i) {
        if (!body.kinematic[i] && body.mass[i] > 0.0) continue;
        for (int k = 0; k < 3; ++k) {
            if (body.kinematic[i]) body.x[3 * i + k] = body.target[3 * i + k];
            body.v[3 * i + k] = 0.0;
        }
    }
}

bool body_state_is_sane(const Body& body) {
    const double limit2 = body.settings.runaway_speed * body.settings.runaway_speed;
    bool sane = true;
    for (size_t i = 0; i < body.mass.size(); ++i) {
        const double* xi = &body.x[3 * i];
        const double* vi = &body.v[3 * i];
        // NaN fails every comparison, so a non-finite speed fails the first test too.
        sane &= vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2] <= limit2 && std::isfinite(xi[0] + xi[1] + xi[2]);
    }
    return sane;
}

}  // namespace sh
