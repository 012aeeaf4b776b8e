// The element kernel's fused pass (model/fem_kernel.hpp: add_fem_forces_and_energy), which the
// implicit step's evaluations use, against the separate force and energy passes
// (add_fem_forces, fem_energy) for every law of the material table, on randomly shaped and
// deformed tets; its force norms against each tet's forces alone; and its forces against
// central differences of its own energy (f = -dE/dx).
#include "material/material_table.hpp"
#include "model/fem_kernel.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <random>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

constexpr int kNodes = 40, kTets = 21;  // 3 blocks, the last with 3 unused lanes
constexpr double kLambda = 2.0e4, kMu = 5.0e3;

struct Scene {
    std::vector<double> rest, x;
    std::vector<sh::TetBlock> blocks;
};

/// Random rest nodes in a 10 cm box, tets of random nodes with positive volume, and the nodes
/// moved by a random rotation plus a stretch and noise of a few percent.
Scene make_scene(unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 0.1), noise(-0.004, 0.004);
    Scene s;
    for (int i = 0; i < 3 * kNodes; ++i) s.rest.push_back(unit(rng));
    std::vector<int32_t> tets;
    std::uniform_int_distribution<int32_t> node(0, kNodes - 1);
    while (tets.size() < 4 * static_cast<size_t>(kTets)) {
        int32_t t[4] = {node(rng), node(rng), node(rng), node(rng)};
        Eigen::Matrix3d dm;
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < 3; ++i) dm(i, a) = s.rest[3 * t[a + 1] + i] - s.rest[3 * t[0] + i];
        if (dm.determinant() < 0.0) std::swap(t[1], t[2]);
        if (std::abs(dm.determinant()) < 2e-5) continue;  // no slivers or repeated nodes
        tets.insert(tets.end(), t, t + 4);
    }
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (int i = 0; i < kNodes; ++i) {
        const Eigen::Vector3d p(s.rest[3 * i], s.rest[3 * i + 1] * 1.05, s.rest[3 * i + 2] * 0.97);
        const Eigen::Vector3d q = turn * p;
        for (int c = 0; c < 3; ++c) s.x.push_back(q(c) + noise(rng));
    }
    std::vector<int32_t> members(kTets);
    for (int t = 0; t < kTets; ++t) members[static_cast<size_t>(t)] = t;
    s.blocks.resize(sh::block_count(kTets));
    sh::spread_over_lanes(members.data(), members.size(), [&](int32_t t, bool used, size_t k, int l) {
        sh::TetBlock& b = s.blocks[k];
        const int32_t* n = &tets[4 * static_cast<size_t>(t)];
        Eigen::Matrix3d dm;
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < 3; ++i) dm(i, a) = s.rest[3 * n[a + 1] + i] - s.rest[3 * n[0] + i];
        const Eigen::Matrix3d bm = dm.inverse();
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) b.Bm.m[i][j][l] = bm(i, j);
        const double v0 = used ? dm.determinant() / 6.0 : 0.0;
        b.lambda_w[l] = -v0 * kLambda;
        b.mu_w[l] = -v0 * kMu;
        for (int a = 0; a < 4; ++a) b.node[a][l] = n[a];
    });
    return s;
}

/// Law's forces, energy and force norms at x by the fused pass.
template <class Law>
sh::EnergySum fused_sum(const Scene& s, const double* x, std::vector<double>& f) {
    f.assign(3 * kNodes, 0.0);
    sh::EnergySum energy;
    sh::add_fem_forces_and_energy<Law>(s.blocks.data(), s.blocks.size(), x, f.data(), sh::KeptRotations{}, &energy);
    return energy;
}

/// Law's forces and energy at x by the fused pass.
template <class Law>
double fused(const Scene& s, const double* x, std::vector<double>& f) {
    return fused_sum<Law>(s, x, f).value;
}

/// The sum over the tets of the Frobenius norm of their forces on nodes 1-3, each tet's forces
/// from the force pass over a copy of the blocks where only that tet has moduli.
template <class Law>
double separate_force_norms(const Scene& s) {
    double sum = 0.0;
    for (size_t k = 0; k < s.blocks.size(); ++k)
        for (int l = 0; l < sh::kLanes; ++l) {
            if (s.blocks[k].mu_w[l] == 0.0) continue;  // an unused lane
            std::vector<sh::TetBlock> alone = s.blocks;
            for (size_t j = 0; j < alone.size(); ++j)
                for (int m = 0; m < sh::kLanes; ++m)
                    if (j != k || m != l) alone[j].lambda_w[m] = alone[j].mu_w[m] = 0.0;
            std::vector<double> f(3 * kNodes, 0.0);
            sh::add_fem_forces<Law>(alone.data(), alone.size(), s.x.data(), nullptr, 0.0, f.data());
            double squares = 0.0;
            for (int a = 1; a < 4; ++a)
                for (int c = 0; c < 3; ++c) squares += f[3 * static_cast<size_t>(s.blocks[k].node[a][l]) + c] * f[3 * static_cast<size_t>(s.blocks[k].node[a][l]) + c];
            sum += std::sqrt(squares);
        }
    return sum;
}

template <class Law>
void check_law(const Scene& s) {
    std::vector<double> f_fused, f_separate(3 * kNodes, 0.0);
    const sh::EnergySum sum = fused_sum<Law>(s, s.x.data(), f_fused);
    const double e_fused = sum.value;
    // Its force norms are the tets' own, one at a time (the nodes of a tet are distinct).
    const double norms = separate_force_norms<Law>(s);
    assert_true(norms > 0.0 && std::abs(sum.force_norm - norms) <= 1e-12 * norms);
    sh::add_fem_forces<Law>(s.blocks.data(), s.blocks.size(), s.x.data(), nullptr, 0.0, f_separate.data());
    const double e_separate = sh::fem_energy<Law>(s.blocks.data(), s.blocks.size(), s.x.data());
    // The same forces and energy as the separate passes.
    double f_max = 0.0;
    for (double v : f_separate) f_max = std::max(f_max, std::abs(v));
    assert_true(f_max > 0.0 && e_separate > 0.0);
    for (int j = 0; j < 3 * kNodes; ++j) assert_true(std::abs(f_fused[j] - f_separate[j]) <= 1e-12 * f_max);
    assert_true(std::abs(e_fused - e_separate) <= 1e-12 * e_separate);
    // Its forces are minus its energy's gradient (central differences).
    const double h = 1e-7;
    std::vector<double> xp = s.x, scratch;
    for (int j = 0; j < 3 * kNodes; ++j) {
        xp[j] = s.x[j] + h;
        const double up = fused<Law>(s, xp.data(), scratch);
        xp[j] = s.x[j] - h;
        const double down = fused<Law>(s, xp.data(), scratch);
        xp[j] = s.x[j];
        assert_true(std::abs(-(up - down) / (2.0 * h) - f_fused[j]) <= 1e-5 * f_max);
    }
}

void fused_pass_matches_the_separate_passes(void**) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
        const Scene s = make_scene(seed);
        sh::for_each_material([&](auto law, int) { check_law<decltype(law)>(s); });
    }
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {cmocka_unit_test(fused_pass_matches_the_separate_passes)};
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
