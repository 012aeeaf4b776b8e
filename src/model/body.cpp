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

GrownNodes Body::grow_nodes(const NodeOrigin* origins, size_t count) const {
    GrownNodes g;
    const size_t n = mass.size(), total = n + count;
    g.x = x, g.v = v, g.rest = rest, g.target = target, g.external_force = external_force;
    g.kinematic = kinematic;
    g.x.resize(3 * total), g.v.resize(3 * total), g.rest.resize(3 * total), g.target.resize(3 * total);
    g.external_force.resize(3 * total, 0.0);
    g.kinematic.resize(total, 0);
    g.mass.assign(total, 0.0);
    g.inverse_mass.assign(total, 0.0);
    g.parent.assign(total, -1);
    std::copy(node_parent.begin(), node_parent.end(), g.parent.begin());
    if (!node_damping.empty()) g.node_damping = node_damping, g.node_damping.resize(total);
    for (size_t k = 0; k < count; ++k) {
        const NodeOrigin& o = origins[k];
        const size_t a = static_cast<size_t>(o.a), b = static_cast<size_t>(o.b), i = n + k;
        const double t = o.t, s = 1.0 - t;
        for (int c = 0; c < 3; ++c) {
            g.x[3 * i + c] = s * g.x[3 * a + c] + t * g.x[3 * b + c];
            g.v[3 * i + c] = s * g.v[3 * a + c] + t * g.v[3 * b + c];
            g.rest[3 * i + c] = s * g.rest[3 * a + c] + t * g.rest[3 * b + c];
            g.target[3 * i + c] = s * g.target[3 * a + c] + t * g.target[3 * b + c];
        }
        g.kinematic[i] = g.kinematic[a] && g.kinematic[b];
        if (!g.kinematic[i])  // a free node's target is where it is
            for (int c = 0; c < 3; ++c) g.target[3 * i + c] = g.x[3 * i + c];
        if (!g.node_damping.empty()) g.node_damping[i] = s * g.node_damping[a] + t * g.node_damping[b];
        g.parent[i] = t <= 0.5 ? o.a : o.b;
    }
    return g;
}

void Body::adopt_nodes(GrownNodes& g) noexcept {
    x.swap(g.x), v.swap(g.v), rest.swap(g.rest), target.swap(g.target);
    external_force.swap(g.external_force), node_damping.swap(g.node_damping);
    mass.swap(g.mass), inverse_mass.swap(g.inverse_mass), kinematic.swap(g.kinematic);
    node_parent.swap(g.parent);
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
