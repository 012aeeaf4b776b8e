#include "cut/breaking.hpp"

#include "contact/collider.hpp"
#include "core/vec3.hpp"
#include "cut/material_frame.hpp"
#include "model/fem_body.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Samples along the blade's edge for its engaged length.
constexpr int kSamples = 33;
// How far outside its tet (in barycentric weight, about a fraction of the tet's size) a blade
// sample may lie and still count as in the material: the walls of its own slit, which meet
// on the crack plane the edge runs in.
constexpr double kSlitSlack = 0.05;

/// The blade's edge ends a, b at the tool's start pose and the unit direction of the step's
/// motion across the edge (false if there is none).
bool blade_frame(const Collider& tool, double a[3], double b[3], double across[3], double& distance) {
    double e[3];
    tool.start.to_world(tool.cutting.edge[0], a);
    tool.start.to_world(tool.cutting.edge[1], b);
    sub3(b, a, e);
    sub3(tool.target.p, tool.start.p, across);
    const double along = dot3(across, e) / dot3(e, e);
    for (int k = 0; k < 3; ++k) across[k] -= along * e[k];
    distance = norm3(across);
    if (!(distance > 1e-9 * norm3(e))) return false;
    for (int k = 0; k < 3; ++k) across[k] /= distance;
    return true;
}

}  // namespace

Engagement engage(const Body& body, const Collider& tool) {
    Engagement found;
    if (!body.is_fem()) return found;
    double a[3], b[3];
    tool.start.to_world(tool.cutting.edge[0], a);
    tool.start.to_world(tool.cutting.edge[1], b);
    const vec<SegmentSpan> spans = segment_in_tets(body, a, b, kSlitSlack);
    // The samples along the edge that some stretch holds: the first and the last make the
    // engaged length, and the one nearest their middle names the material.
    const auto sample_at = [](int s) { return static_cast<double>(s) / (kSamples - 1); };
    const auto holding = [&](int s) {
        for (const SegmentSpan& span : spans)
            if (span.from <= sample_at(s) && sample_at(s) <= span.to) return span.tet;
        return int32_t{-1};
    };
    int first = -1, last = -1;
    for (int s = 0; s < kSamples; ++s) {
        if (holding(s) < 0) continue;
        if (first < 0) first = s;
        last = s;
    }
    if (first < 0) return found;
    double d[3];
    sub3(b, a, d);
    found.length = norm3(d) * static_cast<double>(last - first) / (kSamples - 1);
    int32_t middle = holding((first + last) / 2);
    for (int s = (first + last) / 2; middle < 0 && s <= last; ++s) middle = holding(s);  // a gap: the next held one
    found.toughness = static_cast<const FemBody&>(body).material(static_cast<size_t>(middle)).toughness;
    return found;
}

bool crack_ahead(const Collider& tool, double advance, double triangles[18]) {
    double a[3], b[3], across[3], distance = 0.0;
    if (!blade_frame(tool, a, b, across, distance)) return false;
    double a1[3], b1[3];
    for (int k = 0; k < 3; ++k) a1[k] = a[k] + advance * across[k], b1[k] = b[k] + advance * across[k];
    const double* corners[6] = {a, b, b1, a, b1, a1};
    for (int c = 0; c < 6; ++c)
        for (int k = 0; k < 3; ++k) triangles[3 * c + k] = corners[c][k];
    return true;
}

void measure_held(const Body& body, BreakState& state, double force[3]) {
    force[0] = force[1] = force[2] = 0.0;
    state.forces.clear();
    if (state.held.empty()) return;
    vec<double> f(body.x.size(), 0.0);
    body.add_internal_forces(body.x.data(), nullptr, f.data());
    for (const int32_t i : state.held) {
        state.forces.insert(state.forces.end(), at(f.data(), i), at(f.data(), i) + 3);
        for (int k = 0; k < 3; ++k) force[k] += at(f.data(), i)[k];
    }
}

double pending_work(const Body& body, const BreakState& state) {
    if (state.forces.size() != state.previous.size()) return 0.0;  // held since the last step: nothing done yet
    double work = 0.0;
    for (size_t h = 0; h < state.held.size(); ++h) {
        double moved[3];
        sub3(at(body.x.data(), state.held[h]), &state.previous[3 * h], moved);
        // The blade held the node against the material's force f: it did work -f.dx on it.
        work += std::max(0.0, -dot3(&state.forces[3 * h], moved));
    }
    return work;
}

void count_work(const Body& body, BreakState& state) {
    state.work += pending_work(body, state);
    if (state.forces.size() != state.previous.size()) return;
    for (size_t h = 0; h < state.held.size(); ++h)
        for (int k = 0; k < 3; ++k) state.previous[3 * h + static_cast<size_t>(k)] = at(body.x.data(), state.held[h])[k];
}

void hold_ahead(Body& body, const Collider& tool, double reach, const vec<int32_t>& cut_nodes, BreakState& state) {
    double a[3], b[3], across[3], distance = 0.0;
    if (!blade_frame(tool, a, b, across, distance)) return;
    if (state.held.empty()) {
        double e[3], n[3];
        sub3(b, a, e);
        cross3(e, across, n);
        const double nn = norm3(n), ee = dot3(e, e);
        // Where each node lies against the edge: along it (u in [0, 1] alongside), ahead of it
        // along the motion, and off the crack plane.
        const auto place = [&](int32_t i, double& u, double& ahead, double& off) {
            double d[3];
            sub3(at(body.x.data(), i), a, d);
            u = dot3(d, e) / ee, ahead = dot3(d, across), off = std::fabs(dot3(d, n)) / nn;
            return u >= 0.0 && u <= 1.0 && off <= 0.5 * reach;
        };
        // The crack's front alongside the edge: the farthest cut node ahead of it (behind it if
        // the edge has run past the front; the edge itself where nothing is cut yet).
        double front = -INFINITY, u, ahead, off;
        for (const int32_t i : cut_nodes)
            if (i < body.node_count() && place(i, u, ahead, off)) front = std::max(front, ahead);
        if (front == -INFINITY) front = 0.0;
        // The material the edge meets: uncut nodes from the front to just ahead of the edge.
        for (int32_t i = 0; i < body.node_count(); ++i) {
            if (body.kinematic[static_cast<size_t>(i)] || std::binary_search(cut_nodes.begin(), cut_nodes.end(), i)) continue;
            if (!place(i, u, ahead, off) || ahead < front || ahead > 0.5 * reach) continue;
            state.held.push_back(i);
            state.previous.insert(state.previous.end(), at(body.x.data(), i), at(body.x.data(), i) + 3);
        }
        if (!state.held.empty()) ++state.hold;
    }
    for (const int32_t i : state.held) {
        double target[3];
        for (int k = 0; k < 3; ++k) target[k] = at(body.x.data(), i)[k] + distance * across[k];
        body.prescribe_positions(&i, target, 1);
    }
}

bool break_at_rest(const Body& body, const Collider& tool, const BreakState& state, const vec<int32_t>& cut_nodes, double advance,
                   double rest[18]) {
    double a[3], b[3], across[3], distance = 0.0;
    if (!blade_frame(tool, a, b, across, distance)) return false;
    double ra[3], rb[3], forward[3], direction[3];
    for (int k = 0; k < 3; ++k) forward[k] = a[k] + advance * across[k];
    const double world[9] = {a[0], a[1], a[2], b[0], b[1], b[2], forward[0], forward[1], forward[2]};
    double rest_of[9];
    to_rest_all(body, world, 3, rest_of);
    for (int k = 0; k < 3; ++k) ra[k] = rest_of[k], rb[k] = rest_of[3 + k], direction[k] = rest_of[6 + k];
    sub3(direction, ra, direction);
    const double length = norm3(direction);
    if (!(length > 0.0)) return false;
    for (double& c : direction) c /= length;
    // Where each node lies at rest against the edge: ahead of it, if alongside it and near the
    // crack plane (within half an advance).
    double e[3], n[3];
    sub3(rb, ra, e);
    cross3(e, direction, n);
    const double nn = norm3(n), ee = dot3(e, e);
    const auto ahead_of = [&](int32_t i, double& ahead) {
        double d[3];
        sub3(at(body.rest.data(), i), ra, d);
        const double u = dot3(d, e) / ee;
        ahead = dot3(d, direction);
        return u >= 0.0 && u <= 1.0 && std::fabs(dot3(d, n)) / nn <= 0.5 * advance;
    };
    double front = -INFINITY, held = -INFINITY, ahead = 0.0;
    for (const int32_t i : cut_nodes)
        if (i < body.node_count() && ahead_of(i, ahead)) front = std::max(front, ahead);
    if (front == -INFINITY) front = 0.0;  // nothing cut yet: the crack starts at the edge
    for (const int32_t i : state.held) held = std::max(held, dot3(at(body.rest.data(), i), direction) - dot3(ra, direction));
    // From the front (or the edge, if it is behind it) to `advance` beyond the front, and past
    // every held node.
    const double from = std::min(front, 0.0), to = std::max(front + advance, held + 0.25 * advance);
    double ra0[3], rb0[3], ra1[3], rb1[3];
    for (int k = 0; k < 3; ++k) {
        ra0[k] = ra[k] + from * direction[k], rb0[k] = rb[k] + from * direction[k];
        ra1[k] = ra[k] + to * direction[k], rb1[k] = rb[k] + to * direction[k];
    }
    const double* corners[6] = {ra0, rb0, rb1, ra0, rb1, ra1};
    for (int c = 0; c < 6; ++c)
        for (int k = 0; k < 3; ++k) rest[3 * c + k] = corners[c][k];
    return true;
}

void release(Body& body, BreakState& state) {
    if (!state.held.empty()) body.release_nodes(state.held.data(), static_cast<int32_t>(state.held.size()));
    state.held.clear();
    state.previous.clear();
    state.forces.clear();
    state.work = 0.0;
}

}  // namespace sh
