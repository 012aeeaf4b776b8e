#include "solver/node_rotations.hpp"

#include "core/vec3.hpp"
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
    // In the free nodes' order (a Z-order through the rest shape: solver/free_node_order.hpp),
    // so that each edge's sums land near the last one's; the file's numbers may jump anywhere.
    // As unsigned numbers a fixed end (-1) comes last, so the lower key is the first free end.
    const auto key = [](const NodeRotations::Edge& edge) {
        const uint32_t a = static_cast<uint32_t>(edge.free_a), b = static_cast<uint32_t>(edge.free_b);
        return std::make_pair(std::min(a, b), std::max(a, b));
    };
    std::sort(edges.begin(), edges.end(),
              [&](const NodeRotations::Edge& p, const NodeRotations::Edge& q) { return key(p) < key(q); });
    return edges;
}

// Adds weight (x_b - x_a)(r_b - r_a)^T over the edges into out at each free end (9 per free
// node): the sum over the element edges from each free node, x and r node positions. An
// edge's product is the same from either end.
void add_edge_products(const vec<NodeRotations::Edge>& edges, const double* x, const double* r, vec<double>& out) {
    for (const NodeRotations::Edge& edge : edges) {
        double dx[3], dr[3], product[9];
        sub3(at(x, edge.b), at(x, edge.a), dx);
        sub3(at(r, edge.b), at(r, edge.a), dr);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) product[3 * i + j] = edge.weight * dx[i] * dr[j];
        for (const int32_t k : {edge.free_a, edge.free_b}) {
            if (k < 0) continue;
            double* s = &out[9 * static_cast<size_t>(k)];
            for (int q = 0; q < 9; ++q) s[q] += product[q];
        }
    }
}

}  // namespace

void NodeRotations::reset(const Body& body, const vec<int32_t>& dof_to_global) {
    const size_t free_nodes = dof_to_global.size() / 3;
    vec<int32_t> free_of(body.x.size() / 3, -1);
    for (size_t k = 0; k < free_nodes; ++k) free_of[static_cast<size_t>(dof_to_global[3 * k]) / 3] = static_cast<int32_t>(k);
    vec<Edge> edges = unique_edges(body, free_of);
    vec<double> shape(9 * free_nodes, 0.0), inverse_rest(9 * free_nodes, 0.0), rotation(9 * free_nodes, 0.0);
    add_edge_products(edges, body.rest.data(), body.rest.data(), inverse_rest);
    for (size_t k = 0; k < free_nodes; ++k) {
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> q(&inverse_rest[9 * k]);
        const double det = q.determinant(), size = q.squaredNorm();
        // A node whose edges lie in a plane or on a line (springs): S alone, scaled.
        if (det > 1e-9 * size * std::sqrt(size)) q = q.inverse().eval();
        else q /= std::max(size, 1e-300);
        rotation[9 * k] = rotation[9 * k + 4] = rotation[9 * k + 8] = 1.0;
    }
    edges_.swap(edges), shape_.swap(shape), inverse_rest_.swap(inverse_rest), rotation_.swap(rotation);
}

const double* NodeRotations::update(const Body& body) {
    std::fill(shape_.begin(), shape_.end(), 0.0);
    add_edge_products(edges_, body.x.data(), body.rest.data(), shape_);
    for (size_t k = 0; k < size(); ++k) {
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> s(&shape_[9 * k]);
        s = (s * Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&inverse_rest_[9 * k])).eval();
    }
    // kLanes nodes at a time; the last group's spare lanes repeat its first node.
    const size_t n = size();
    double turn = 0.0;
    for (size_t first = 0; first < n; first += kLanes) {
        Mat3L f, near;
        for (int l = 0; l < kLanes; ++l) {
            const size_t k = first + static_cast<size_t>(l) < n ? first + static_cast<size_t>(l) : first;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) {
                    f.m[r][c][l] = shape_[9 * k + 3 * static_cast<size_t>(r) + static_cast<size_t>(c)];
                    near.m[r][c][l] = rotation_[9 * k + 3 * static_cast<size_t>(r) + static_cast<size_t>(c)];
                }
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
