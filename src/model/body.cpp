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
    for (size_t i = 0; i < mass.size(); ++i) update_inverse_mass_of(i);
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

const double* GrownNodes::rest_of(const Body& body, int32_t node) const {
    const size_t i = static_cast<size_t>(node);
    return i < first ? &body.rest[3 * i] : &rest[3 * (i - first)];
}

vec<double> GrownNodes::joined(const vec<double>& values, const vec<double>& appended) {
    vec<double> all;
    all.reserve(values.size() + appended.size());
    all.insert(all.end(), values.begin(), values.end());
    all.insert(all.end(), appended.begin(), appended.end());
    return all;
}

GrownNodes Body::grow_nodes(const NodeOrigin* origins, size_t count) {
    GrownNodes g;
    const size_t n = mass.size(), total = n + count;
    g.first = n;
    g.x.resize(3 * count), g.v.resize(3 * count), g.rest.resize(3 * count), g.target.resize(3 * count);
    g.kinematic.resize(count), g.parent.resize(count);
    if (!node_damping.empty()) g.node_damping.resize(count);
    // An origin may name a node appended before it (a copy of a node made on a crossed edge).
    const auto of = [&](const vec<double>& own, const vec<double>& appended, size_t node, int stride) {
        return node < n ? &own[static_cast<size_t>(stride) * node] : &appended[static_cast<size_t>(stride) * (node - n)];
    };
    for (size_t k = 0; k < count; ++k) {
        const NodeOrigin& o = origins[k];
        const size_t a = static_cast<size_t>(o.a), b = static_cast<size_t>(o.b);
        const double t = o.t, s = 1.0 - t;
        const auto held = [&](size_t node) { return node < n ? kinematic[node] != 0 : g.kinematic[node - n] != 0; };
        g.kinematic[k] = held(a) && held(b);
        for (int c = 0; c < 3; ++c) {
            g.x[3 * k + c] = s * of(x, g.x, a, 3)[c] + t * of(x, g.x, b, 3)[c];
            g.v[3 * k + c] = s * of(v, g.v, a, 3)[c] + t * of(v, g.v, b, 3)[c];
            g.rest[3 * k + c] = s * of(rest, g.rest, a, 3)[c] + t * of(rest, g.rest, b, 3)[c];
            // a free node's target is where it is
            g.target[3 * k + c] = g.kinematic[k] ? s * of(target, g.target, a, 3)[c] + t * of(target, g.target, b, 3)[c] : g.x[3 * k + c];
        }
        if (!node_damping.empty()) g.node_damping[k] = s * *of(node_damping, g.node_damping, a, 1) + t * *of(node_damping, g.node_damping, b, 1);
        g.parent[k] = t <= 0.5 ? o.a : o.b;
    }
    for (vec<double>* values : {&x, &v, &rest, &target, &external_force}) reserve_growing(*values, 3 * total);
    for (vec<double>* values : {&mass, &inverse_mass}) reserve_growing(*values, total);
    if (!node_damping.empty()) reserve_growing(node_damping, total);
    reserve_growing(kinematic, total);
    reserve_growing(node_parent, total);
    return g;
}

void Body::adopt_nodes(const GrownNodes& g) noexcept {
    const size_t count = g.kinematic.size(), total = g.first + count;
    x.insert(x.end(), g.x.begin(), g.x.end());
    v.insert(v.end(), g.v.begin(), g.v.end());
    rest.insert(rest.end(), g.rest.begin(), g.rest.end());
    target.insert(target.end(), g.target.begin(), g.target.end());
    external_force.resize(3 * total, 0.0);
    if (!node_damping.empty()) node_damping.insert(node_damping.end(), g.node_damping.begin(), g.node_damping.end());
    mass.resize(total, 0.0);
    inverse_mass.resize(total, 0.0);
    kinematic.insert(kinematic.end(), g.kinematic.begin(), g.kinematic.end());
    node_parent.resize(g.first, -1);  // the body's own nodes have none until a cut appends some
    node_parent.insert(node_parent.end(), g.parent.begin(), g.parent.end());
}

void Body::set_node_damping(const double* coefficients) {
    if (coefficients)
        node_damping.assign(coefficients, coefficients + mass.size());
    else
        node_damping = vec<double>();
    ++matrix_version;
}

double Body::elastic_energy_recalled(const double* x) const {
    double value = 0.0;
    return energy_memo_.recall(x, this->x.size(), topology_version, matrix_version, value) ? value : elastic_energy(x);
}

void Body::remember_elastic_energy(const double* x, double value) {
    energy_memo_.remember(x, this->x.size(), topology_version, matrix_version, value);
}

}  // namespace sh
