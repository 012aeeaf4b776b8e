#include "model/body.hpp"

#include "model/external_field.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

Body::Body(vec<double> rest_positions, double alpha) : damping_mass(alpha), x(std::move(rest_positions)) {
    rest = x;
    const size_t n = x.size() / 3;
    v.assign(3 * n, 0.0);
    mass.assign(n, 0.0);
    inverse_mass.assign(n, 0.0);
    kinematic.assign(n, 0);
    target = x;
    external_force.assign(3 * n, 0.0);
}

void Body::update_inverse_mass() {
    for (size_t i = 0; i < mass.size(); ++i)
        inverse_mass[i] = (mass[i] > 0.0 && !kinematic[i]) ? 1.0 / mass[i] : 0.0;
}

void Body::set_positions(const double* positions) {
    std::copy(positions, positions + x.size(), x.begin());
    for (size_t i = 0; i < kinematic.size(); ++i)
        if (kinematic[i])
            for (int k = 0; k < 3; ++k) target[3 * i + k] = x[3 * i + k];
}

void Body::set_velocities(const double* velocities) {
    for (size_t i = 0; i < mass.size(); ++i)
        for (int k = 0; k < 3; ++k) v[3 * i + k] = inverse_mass[i] > 0.0 ? velocities[3 * i + k] : 0.0;
}

void Body::fix_nodes(const int32_t* nodes, int32_t count) {
    for (int32_t n = 0; n < count; ++n) {
        const size_t i = static_cast<size_t>(nodes[n]);
        kinematic[i] = 1;
        for (int k = 0; k < 3; ++k) {
            target[3 * i + k] = x[3 * i + k];
            v[3 * i + k] = 0.0;
        }
    }
    update_inverse_mass();
}

void Body::release_nodes(const int32_t* nodes, int32_t count) {
    for (int32_t n = 0; n < count; ++n) kinematic[static_cast<size_t>(nodes[n])] = 0;
    update_inverse_mass();
}

void Body::prescribe_positions(const int32_t* nodes, const double* positions, int32_t count) {
    for (int32_t n = 0; n < count; ++n) {
        const size_t i = static_cast<size_t>(nodes[n]);
        kinematic[i] = 1;
        for (int k = 0; k < 3; ++k) target[3 * i + k] = positions[3 * n + k];
    }
    update_inverse_mass();
}

void Body::set_node_damping(const double* coefficients) {
    if (coefficients)
        node_damping.assign(coefficients, coefficients + mass.size());
    else
        node_damping = vec<double>();
    ++matrix_version;
}

}  // namespace sh
