#include "solver/node_rotations.hpp"

#include "core/vec3.hpp"
#include "linalg/node_lanes.hpp"
#include "material/lanes.hpp"
#include "material/polar_decomposition.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <utility>
#include <cmath>

namespace sh {
namespace {

// A preconditioner needs the rotations to about 1e-3 rad, not the element laws' 1e-6.
constexpr double kNodeRotationSettled2 = 1e-6;

// The edges of body's elements with a free end, each once (a < b), and how many elements share
// it: in a tet mesh about five, so that the sums over element edges take a fifth of the work.
vec<NodeRotations::Edge> unique_edges(const Body& body, const vec<int32_t>& free_of) {
    const int32_t* elements = body.element_nodes();
    const int per = body.nodes_per_element();
    vec<std::pair<int32_t, int32_t>> pairs;
    pairs.reserve(static_cast<size_t>(body.element_count()) * static_cast<size_t>(per * (per - 1) / 2));
    for (int32_t e = 0; e < body.element_count(); ++e) {
        const int32_t* nodes = elements + static_cast<size_t>(e) * static_cast<size_t>(per);
        for (int i = 0; i < per; ++i)
            for (int j = i + 1; j < per; ++j) {
                const int32_t a = std::min(nodes[i], nodes[j]), b = std::max(nodes[i], nodes[j]);
                if (free_of[static_cast<size_t>(a)] >= 0 || free_of[static_cast<size_t>(b)] >= 0) pairs.emplace_back(a, b);
            }
    }
    std::sort(pairs.begin(), pairs.end());
    vec<NodeRotations::Edge> edges;
    for (size_t k = 0; k < pairs.size(); ++k) {
        if (k > 0 && pairs[k] == pairs[k - 1]) {
            edges.back().weight += 1.0;
            continue;
        }
        NodeRotations::Edge edge;
        edge.free_a = free_of[static_cast<size_t>(pairs[k].first)], edge.free_b = free_of[static_cast<size_t>(pairs[k].second)];
        edge.a = pairs[k].first, edge.b = pairs[k].second;
        edge.weight = 1.0;
        edges.push_back(edge);
    }
    return edges;
}

// Q^-1 of a free node's rest edges (Q = q, row-major, in place). A node whose edges lie in a
// plane or on a line (springs) has no inverse: it takes Q / |Q|^2 instead, so that F = S Q /
// |Q|^2 stays finite and its rotation is a rough one, which is all a preconditioner asks there.
void invert_rest_moment(double* q) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> m(q);
    const double det = m.determinant(), size = m.squaredNorm();
    if (det > 1e-9 * size * std::sqrt(size)) m = m.inverse().eval();
    else m /= std::max(size, 1e-300);
}

}  // namespace

void NodeRotations::reset(const Body& body, const vec<int32_t>& dof_to_global) {
    const size_t free_nodes = dof_to_global.size() / 3;
    vec<int32_t> free_of(body.x.size() / 3, -1), node(free_nodes);
    for (size_t k = 0; k < free_nodes; ++k) {
        node[k] = dof_to_global[3 * k] / 3;
        free_of[static_cast<size_t>(node[k])] = static_cast<int32_t>(k);
    }
    const vec<Edge> edges = unique_edges(body, free_of);
    vec<int32_t> start(free_nodes + 1, 0);
    for (const Edge& edge : edges)
        for (const int32_t k : {edge.free_a, edge.free_b})
            if (k >= 0) ++start[static_cast<size_t>(k) + 1];
    for (size_t k = 0; k < free_nodes; ++k) start[k + 1] += start[k];
    // Each end's entry holds the other end and w (X_j - X_k), from which c follows once Q is known.
    vec<int32_t> neighbour(static_cast<size_t>(start[free_nodes])), next(start.begin(), start.end() - 1);
    vec<double> difference(3 * neighbour.size()), moment(9 * free_nodes, 0.0);
    const double* X = body.rest.data();
    for (const Edge& edge : edges) {
        const int32_t ends[2][2] = {{edge.free_a, edge.b}, {edge.free_b, edge.a}};
        for (const auto& end : ends) {
            const int32_t k = end[0];
            if (k < 0) continue;
            const size_t e = static_cast<size_t>(next[static_cast<size_t>(k)]++);
            neighbour[e] = end[1];
            double d[3];
            sub3(at(X, end[1]), at(X, node[static_cast<size_t>(k)]), d);
            double* q = &moment[9 * static_cast<size_t>(k)];
            for (int i = 0; i < 3; ++i) {
                difference[3 * e + static_cast<size_t>(i)] = edge.weight * d[i];
                for (int j = 0; j < 3; ++j) q[3 * i + j] += edge.weight * d[i] * d[j];
            }
        }
    }
    vec<float> coefficient(3 * neighbour.size());
    for (size_t k = 0; k < free_nodes; ++k) {
        double* q = &moment[9 * k];
        invert_rest_moment(q);
        for (int32_t e = start[k]; e < start[k + 1]; ++e) {
            const double* w_d = &difference[3 * static_cast<size_t>(e)];
            for (int i = 0; i < 3; ++i)
                coefficient[3 * static_cast<size_t>(e) + static_cast<size_t>(i)] =
                    static_cast<float>(q[3 * i] * w_d[0] + q[3 * i + 1] * w_d[1] + q[3 * i + 2] * w_d[2]);
        }
    }
    vec<double> rotation(9 * free_nodes, 0.0);
    for (size_t k = 0; k < free_nodes; ++k) rotation[9 * k] = rotation[9 * k + 4] = rotation[9 * k + 8] = 1.0;
    node_.swap(node), entry_start_.swap(start), neighbour_.swap(neighbour), coefficient_.swap(coefficient);
    rotation_.swap(rotation);
}

void NodeRotations::gather_gradient(size_t k, const double* x, Mat3L& f, int lane) const {
    // F's columns, each a sum of the edge vectors d = x_j - x_k times one entry of c; the
    // entries go two at a time into two sets of sums, which halves the wait on the adds.
    const Node4 xk = load_node(at(x, node_[k]));
    Node4 even[3] = {}, odd[3] = {};
    const auto add = [&](int32_t e, Node4* sums) {
        const Node4 d = load_node(at(x, neighbour_[static_cast<size_t>(e)])) - xk;
        const float* c = &coefficient_[3 * static_cast<size_t>(e)];
        for (int col = 0; col < 3; ++col) sums[col] += d * static_cast<double>(c[col]);
    };
    int32_t e = entry_start_[k];
    const int32_t end = entry_start_[k + 1];
    for (; e + 1 < end; e += 2) add(e, even), add(e + 1, odd);
    if (e < end) add(e, even);
    for (int r = 0; r < 3; ++r)
        for (int col = 0; col < 3; ++col) f.m[r][col][lane] = even[col][r] + odd[col][r];
}

const double* NodeRotations::update(const Body& body) {
    // kLanes nodes at a time; the last group's spare lanes repeat its first node.
    const size_t n = size();
    double turn = 0.0;
    for (size_t first = 0; first < n; first += kLanes) {
        Mat3L f, near;
        for (int l = 0; l < kLanes; ++l) {
            const size_t k = first + static_cast<size_t>(l) < n ? first + static_cast<size_t>(l) : first;
            gather_gradient(k, body.x.data(), f, l);
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) near.m[r][c][l] = rotation_[9 * k + 3 * static_cast<size_t>(r) + static_cast<size_t>(c)];
        }
        const Mat3L found = polar_rotation_near(f, near, kNodeRotationSettled2);
        for (int l = 0; l < kLanes && first + static_cast<size_t>(l) < n; ++l) {
            double change2 = 0.0;
            double* r = &rotation_[9 * (first + static_cast<size_t>(l))];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const double value = found.m[i][j][l], d = value - r[3 * i + j];
                    change2 += d * d;
                    r[3 * i + j] = value;
                }
            turn = std::max(turn, std::sqrt(0.5 * change2));  // |R' - R|_F = sqrt(2) angle
        }
    }
    last_turn_ = turn;
    return rotation_.data();
}

}  // namespace sh
