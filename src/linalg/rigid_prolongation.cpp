#include "linalg/rigid_prolongation.hpp"

#include "core/error.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <utility>

namespace sh {
namespace {

// A rotation mode whose aggregate's second moment about it is below this fraction of its
// largest moves the nodes by nothing that a round-off could not swamp: it is left inert.
constexpr double kFlat = 1e-10;

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

Vector3 rest_of(const double* rest, size_t node) { return Vector3(rest[3 * node], rest[3 * node + 1], rest[3 * node + 2]); }

// The rotations' scaling G of an aggregate whose second moment (the sum of |d|^2 I - d d^T
// over its nodes) is moment: rotations about its eigenvectors u_k, scaled by 1 / sqrt(lambda_k),
// are orthonormal over the aggregate (and orthogonal to its translations: d sums to 0). A
// mode of no motion gets a zero column and is marked in inert (3 entries).
Matrix3 rotation_gauge(const Matrix3& moment, uint8_t* inert) {
    const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(moment);
    const double top = eigen.eigenvalues().maxCoeff();
    Matrix3 gauge;
    for (int k = 0; k < 3; ++k) {
        const double lambda = eigen.eigenvalues()[k];
        const bool moves = top > 0.0 && lambda > kFlat * top;
        gauge.col(k) = moves ? Vector3(eigen.eigenvectors().col(k) / std::sqrt(lambda)) : Vector3::Zero();
        inert[k] = moves ? 0 : 1;
    }
    return gauge;
}

}  // namespace

void RigidProlongation::build(vec<int32_t> aggregate, int32_t aggregates, const double* rest) {
    SH_REQUIRE(aggregates >= 0, SH_ERR_INTERNAL, "rigid prolongation: %d aggregates", aggregates);
    const size_t m = static_cast<size_t>(aggregates), n = aggregate.size();
    vec<Vector3> centroid(m, Vector3::Zero());
    vec<int32_t> size(m, 0);
    for (size_t i = 0; i < n; ++i) {
        SH_REQUIRE(aggregate[i] >= 0 && aggregate[i] < aggregates, SH_ERR_INTERNAL,
                   "rigid prolongation: node %zu in aggregate %d of %d", i, aggregate[i], aggregates);
        centroid[static_cast<size_t>(aggregate[i])] += rest_of(rest, i);
        ++size[static_cast<size_t>(aggregate[i])];
    }
    for (size_t a = 0; a < m; ++a) {
        SH_REQUIRE(size[a] > 0, SH_ERR_INTERNAL, "rigid prolongation: aggregate %zu has no node", a);
        centroid[a] /= size[a];
    }
    vec<Node4> offset(n);
    vec<Matrix3> moment(m, Matrix3::Zero());
    for (size_t i = 0; i < n; ++i) {
        const Vector3 d = rest_of(rest, i) - centroid[static_cast<size_t>(aggregate[i])];
        offset[i] = Node4{d.x(), d.y(), d.z(), 0.0};
        moment[static_cast<size_t>(aggregate[i])] += d.squaredNorm() * Matrix3::Identity() - d * d.transpose();
    }
    vec<double> scale(m);
    vec<Node4> gauge(3 * m);
    vec<uint8_t> inert(6 * m, 0);
    for (size_t a = 0; a < m; ++a) {
        scale[a] = 1.0 / std::sqrt(static_cast<double>(size[a]));
        const Matrix3 g = rotation_gauge(moment[a], &inert[6 * a + 3]);
        for (int k = 0; k < 3; ++k) gauge[3 * a + static_cast<size_t>(k)] = Node4{g(0, k), g(1, k), g(2, k), 0.0};
    }
    vec<int32_t> member_start(m + 1, 0), members(n);
    for (size_t a = 0; a < m; ++a) member_start[a + 1] = member_start[a] + size[a];
    vec<int32_t> next(member_start.begin(), member_start.end() - 1);
    for (size_t i = 0; i < n; ++i) members[static_cast<size_t>(next[static_cast<size_t>(aggregate[i])]++)] = static_cast<int32_t>(i);
    aggregate_.swap(aggregate), member_start_.swap(member_start), members_.swap(members), offset_.swap(offset),
        scale_.swap(scale), gauge_.swap(gauge), inert_.swap(inert);
    aggregates_ = aggregates;
}

Eigen::Matrix<double, 3, 6> RigidProlongation::block(size_t node) const {
    const size_t a = static_cast<size_t>(aggregate_[node]);
    Eigen::Matrix<double, 3, 6> p;
    p.leftCols<3>() = scale_[a] * Matrix3::Identity();
    for (int k = 0; k < 3; ++k) {
        const Node4 column = node_cross(gauge_[3 * a + static_cast<size_t>(k)], offset_[node]);  // g_k x d_i
        p.col(3 + k) = Vector3(column[0], column[1], column[2]);
    }
    return p;
}

void RigidProlongation::galerkin_row(const BlockRows& rows, int32_t a, vec<int32_t>& slot, vec<int32_t>& columns,
                                     vec<Eigen::Matrix<double, 6, 6>>& blocks) const {
    const size_t begin = columns.size();
    for (int32_t k = member_start_[static_cast<size_t>(a)]; k < member_start_[static_cast<size_t>(a) + 1]; ++k) {
        const size_t i = static_cast<size_t>(members_[static_cast<size_t>(k)]);
        const Eigen::Matrix<double, 6, 3> left = block(i).transpose();
        for (int32_t e = rows.first[i]; e < rows.first[i + 1]; ++e) {
            const size_t j = static_cast<size_t>(rows.column[static_cast<size_t>(e)]);
            const int32_t b = aggregate_[j];
            if (b < a) continue;
            int32_t& at = slot[static_cast<size_t>(b)];
            if (at < 0) {
                at = static_cast<int32_t>(columns.size());
                columns.push_back(b);
                blocks.push_back(Eigen::Matrix<double, 6, 6>::Zero());
            }
            blocks[static_cast<size_t>(at)] += left * rows.block[static_cast<size_t>(e)] * block(j);
        }
    }
    for (size_t c = begin; c < columns.size(); ++c) slot[static_cast<size_t>(columns[c])] = -1;
}

void RigidProlongation::galerkin(const BlockRows& rows, SparseSystem& out) const {
    const int32_t m = aggregates_;
    vec<int32_t> slot(static_cast<size_t>(m), -1), row_start(static_cast<size_t>(m) + 1, 0), columns;
    vec<Eigen::Matrix<double, 6, 6>> blocks;
    for (int32_t a = 0; a < m; ++a) {
        galerkin_row(rows, a, slot, columns, blocks);
        row_start[static_cast<size_t>(a) + 1] = static_cast<int32_t>(columns.size());
    }
    // Pseudo-node 2a holds aggregate a's translations, 2a + 1 its rotations; each pair of
    // them that a block couples is an element of two nodes.
    vec<int32_t> pairs, identity(2 * static_cast<size_t>(m));
    for (int32_t p = 0; p < 2 * m; ++p) identity[static_cast<size_t>(p)] = p;
    for (int32_t a = 0; a < m; ++a)
        for (int32_t k = row_start[static_cast<size_t>(a)]; k < row_start[static_cast<size_t>(a) + 1]; ++k) {
            const int32_t b = columns[static_cast<size_t>(k)];
            for (int s = 0; s < 2; ++s)
                for (int u = 0; u < 2; ++u)
                    if (b != a || s < u) pairs.push_back(2 * a + s), pairs.push_back(2 * b + u);
        }
    SparseSystem coarse;
    coarse.build_pattern(pairs.data(), pairs.size() / 2, 2, identity.data(), 2 * m, 2 * m);
    for (int32_t a = 0; a < m; ++a)
        for (int32_t k = row_start[static_cast<size_t>(a)]; k < row_start[static_cast<size_t>(a) + 1]; ++k) {
            const int32_t b = columns[static_cast<size_t>(k)];
            for (int s = 0; s < 2; ++s)
                for (int u = 0; u < 2; ++u) {
                    if (b == a && s > u) continue;  // the lower block of the diagonal: its transpose is stored
                    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> part =
                        blocks[static_cast<size_t>(k)].block<3, 3>(3 * s, 3 * u);
                    coarse.add_block(2 * a + s, 2 * b + u, part.data(), 1.0);
                }
        }
    vec<double> inert(inert_.size());
    for (size_t d = 0; d < inert.size(); ++d) inert[d] = inert_[d];
    coarse.add_diagonal(inert.data(), 1.0);
    out = std::move(coarse);
}

}  // namespace sh
