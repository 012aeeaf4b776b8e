// The free nodes' rotations of the multigrid's warp (solver/node_rotations.hpp) under motions
// whose answer is known by hand: under an affine motion x = A X every node's least-squares
// deformation gradient is A itself (its edges' differences are A times the rest ones), so
// every node's rotation is A's polar factor, taken here from Eigen's SVD; the angle a rigid
// turn by theta reports is 2 sin(theta / 2). Under a motion that is not affine, each node's
// rotation is the polar factor of its weighted least-squares fit S Q^-1, computed here
// directly from the tets (each edge weighted by the tets that share it) with Eigen.
#include "solver/node_rotations.hpp"

#include "../internal/kuhn_block.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

// A body of tets with no physics: the rotations read only its elements and positions.
class TetsOnly final : public sh::Body {
public:
    TetsOnly(const std::vector<double>& rest, std::vector<int32_t> tets)
        : Body(sh::vec<double>(rest.begin(), rest.end()), 0.0), tets_(std::move(tets)) {}
    void add_internal_forces(const double*, const double*, double*) const override {}
    bool has_internal_damping() const override { return false; }
    double elastic_energy(const double*) const override { return 0.0; }
    ElasticEnergy add_elastic_forces_and_energy(const double*, double*) const override { return {}; }
    double stable_step(const double*) const override { return 0.0; }
    void add_tangent(const double*, double, double, sh::SparseSystem&) const override {}
    double tangent_work() const override { return 0.0; }
    const int32_t* element_nodes() const override { return tets_.data(); }
    int nodes_per_element() const override { return 4; }
    int32_t element_count() const override { return static_cast<int32_t>(tets_.size() / 4); }
    bool is_fem() const override { return true; }

private:
    std::vector<int32_t> tets_;
};

constexpr int kCells = 3;

// The block's free DOFs: every node but those of the face z = 0 (held), so that edges with a
// held end count too, numbered backwards (a free order that is not the body's).
sh::vec<int32_t> free_dofs(const TetsOnly& body) {
    sh::vec<int32_t> dofs;
    for (int32_t i = body.node_count() - 1; i >= 0; --i)
        if (body.rest[3 * static_cast<size_t>(i) + 2] > 0.0)
            for (int c = 0; c < 3; ++c) dofs.push_back(3 * i + c);
    return dofs;
}

void move_affinely(TetsOnly& body, const Eigen::Matrix3d& a, const Eigen::Vector3d& shift) {
    for (size_t i = 0; i < body.x.size() / 3; ++i) {
        const Eigen::Vector3d p = a * Eigen::Map<const Eigen::Vector3d>(&body.rest[3 * i]) + shift;
        for (int c = 0; c < 3; ++c) body.x[3 * i + static_cast<size_t>(c)] = p[c];
    }
}

Eigen::Matrix3d polar_factor(const Eigen::Matrix3d& a) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return svd.matrixU() * svd.matrixV().transpose();  // det A > 0 here
}

// Largest entry of R_k - expected over the nodes (rotations row-major).
double largest_error(const double* rotations, size_t nodes, const Eigen::Matrix3d& expected) {
    double worst = 0.0;
    for (size_t k = 0; k < nodes; ++k)
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) worst = std::fmax(worst, std::fabs(rotations[9 * k + 3 * r + c] - expected(r, c)));
    return worst;
}

void test_affine_motion_gives_its_polar_factor(void**) {
    TetsOnly body(kuhn::copies_rest(kCells, 1, 0.0), kuhn::block_tets(kCells));
    const sh::vec<int32_t> dofs = free_dofs(body);
    sh::NodeRotations rotations;
    rotations.reset(body, dofs);
    assert_int_equal(rotations.size(), dofs.size() / 3);
    Eigen::Matrix3d stretch;  // symmetric positive definite, far from isotropic
    stretch << 1.3, 0.2, -0.1, 0.2, 0.8, 0.15, -0.1, 0.15, 1.1;
    // A large turn first and a small one on top of it: each update starts from the last.
    const Eigen::Matrix3d turns[2] = {
        Eigen::AngleAxisd(2.0, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix(),
        Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.0, 1.0, 1.0).normalized()).toRotationMatrix()};
    Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
    for (const Eigen::Matrix3d& step : turns) {
        turn = step * turn;
        const Eigen::Matrix3d a = turn * stretch;
        move_affinely(body, a, Eigen::Vector3d(0.3, -1.0, 2.0));
        const double* found = rotations.update(body);
        // The rotations settle to about 1e-3 rad per update, so within about 1e-6 of the polar
        // factor (Newton's quadratic convergence): 1e-5 leaves room; a wrong F is off by 1e-2.
        assert_true(largest_error(found, rotations.size(), polar_factor(a)) < 1e-5);
    }
}

// Node i's least-squares gradient over its element edges, each weighted by the tets sharing
// it: S Q^-1 with S = sum w (x_j - x_i)(X_j - X_i)^T, Q = sum w (X_j - X_i)(X_j - X_i)^T.
Eigen::Matrix3d least_squares_gradient(const TetsOnly& body, const std::vector<int32_t>& tets, int32_t i) {
    std::map<std::pair<int32_t, int32_t>, int> shared;  // edge (a < b) -> tets holding it
    for (size_t t = 0; t < tets.size() / 4; ++t)
        for (int p = 0; p < 4; ++p)
            for (int q = p + 1; q < 4; ++q) {
                const int32_t a = tets[4 * t + static_cast<size_t>(p)], b = tets[4 * t + static_cast<size_t>(q)];
                ++shared[{std::min(a, b), std::max(a, b)}];
            }
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero(), Q = Eigen::Matrix3d::Zero();
    for (const auto& [edge, weight] : shared) {
        if (edge.first != i && edge.second != i) continue;
        const int32_t j = edge.first == i ? edge.second : edge.first;
        const Eigen::Vector3d dX = Eigen::Map<const Eigen::Vector3d>(&body.rest[3 * static_cast<size_t>(j)]) -
                                   Eigen::Map<const Eigen::Vector3d>(&body.rest[3 * static_cast<size_t>(i)]);
        const Eigen::Vector3d dx = Eigen::Map<const Eigen::Vector3d>(&body.x[3 * static_cast<size_t>(j)]) -
                                   Eigen::Map<const Eigen::Vector3d>(&body.x[3 * static_cast<size_t>(i)]);
        S += weight * dx * dX.transpose();
        Q += weight * dX * dX.transpose();
    }
    return S * Q.inverse();
}

void test_bent_block_gives_each_nodes_fit(void**) {
    const std::vector<int32_t> tets = kuhn::block_tets(kCells);
    TetsOnly body(kuhn::copies_rest(kCells, 1, 0.0), tets);
    const sh::vec<int32_t> dofs = free_dofs(body);
    sh::NodeRotations rotations;
    rotations.reset(body, dofs);
    // Bent about y by an angle growing with x, and sheared by a wave: every node's fit differs.
    for (size_t i = 0; i < body.x.size() / 3; ++i) {
        const double X = body.rest[3 * i], Y = body.rest[3 * i + 1], Z = body.rest[3 * i + 2];
        const double bend = 0.25 * X;
        body.x[3 * i] = X * std::cos(bend) + Z * std::sin(bend);
        body.x[3 * i + 1] = Y + 0.1 * std::sin(X + Z);
        body.x[3 * i + 2] = -X * std::sin(bend) + Z * std::cos(bend);
    }
    const double* found = rotations.update(body);
    double worst = 0.0;
    for (size_t k = 0; k < rotations.size(); ++k) {
        const Eigen::Matrix3d expected = polar_factor(least_squares_gradient(body, tets, dofs[3 * k] / 3));
        worst = std::fmax(worst, largest_error(found + 9 * k, 1, expected));
    }
    assert_true(worst < 1e-5);
}

void test_rigid_turn_reports_its_angle(void**) {
    TetsOnly body(kuhn::copies_rest(kCells, 1, 0.0), kuhn::block_tets(kCells));
    sh::NodeRotations rotations;
    rotations.reset(body, free_dofs(body));
    const double theta = 0.3;
    move_affinely(body, Eigen::AngleAxisd(theta, Eigen::Vector3d(1.0, 1.0, 0.0).normalized()).toRotationMatrix(),
                  Eigen::Vector3d::Zero());
    rotations.update(body);
    assert_true(std::fabs(rotations.last_turn() - 2.0 * std::sin(0.5 * theta)) < 1e-6);
    rotations.update(body);  // nothing moved
    assert_true(rotations.last_turn() < 1e-9);
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {
        cmocka_unit_test(test_affine_motion_gives_its_polar_factor),
        cmocka_unit_test(test_bent_block_gives_each_nodes_fit),
        cmocka_unit_test(test_rigid_turn_reports_its_angle),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
