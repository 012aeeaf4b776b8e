#include "model/fem_body.hpp"

#include "core/error.hpp"
#include "material/material_params.hpp"
#include "material/material_table.hpp"
#include "model/fem_kernel.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <utility>

namespace sh {

namespace {

// Spreads the low 21 bits of v to every third bit (Morton interleaving).
uint64_t spread_bits(uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

// Tets ordered along a Z-order (Morton) curve through their centroids at positions p, so that
// consecutive tets, and the kLanes tets of a block, share nodes and cache lines: the kernels'
// gathers and scatters then mostly hit L1. Node numbering is public and stays as it is; only
// the order of the tets inside the blocks changes (and with it the summation order of f).
vec<uint32_t> locality_order(const vec<int32_t>& tets, const vec<double>& p) {
    const size_t tet_count = tets.size() / 4;
    vec<double> centroid(3 * tet_count);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t t = 0; t < tet_count; ++t)
        for (int i = 0; i < 3; ++i) {
            double c = 0.0;
            for (int a = 0; a < 4; ++a) c += p[3 * static_cast<size_t>(tets[4 * t + a]) + i];
            c *= 0.25;
            centroid[3 * t + i] = c;
            lo[i] = std::min(lo[i], c);
            hi[i] = std::max(hi[i], c);
        }
    vec<std::pair<uint64_t, uint32_t>> keyed(tet_count);
    for (size_t t = 0; t < tet_count; ++t) {
        uint64_t key = 0;
        for (int i = 0; i < 3; ++i) {
            const double extent = hi[i] - lo[i];
            const double u = extent > 0.0 ? (centroid[3 * t + i] - lo[i]) / extent : 0.0;  // NaN-safe below
            const uint64_t q = u >= 0.0 ? static_cast<uint64_t>(std::min(u, 1.0) * 2097151.0) : 0;
            key |= spread_bits(q) << i;
        }
        keyed[t] = {key, static_cast<uint32_t>(t)};
    }
    std::sort(keyed.begin(), keyed.end());
    vec<uint32_t> order(tet_count);
    for (size_t k = 0; k < tet_count; ++k) order[k] = keyed[k].second;
    return order;
}

}  // namespace

FemBody::FemBody(const TetMesh& mesh, const sh_material& material, double damping_mass, double damping_stiffness)
    : Body(mesh.nodes, damping_mass), tets_(mesh.tets), damping_stiffness_(damping_stiffness) {
    surface_triangles = mesh.surface_triangles;
    const size_t tet_count = tets_.size() / 4;
    inverse_rest_.resize(9 * tet_count);
    volume_.resize(tet_count);
    for (size_t t = 0; t < tet_count; ++t) {
        const int32_t* tet = &tets_[4 * t];
        Eigen::Matrix3d dm;
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < 3; ++i) dm(i, a) = x[3 * tet[a + 1] + i] - x[3 * tet[0] + i];
        volume_[t] = dm.determinant() / 6.0;
        const Eigen::Matrix3d bm = dm.inverse();
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) inverse_rest_[9 * t + 3 * i + j] = bm(i, j);
    }
    rebuild(vec<sh_material>(tet_count, material));
}

void FemBody::set_material(const int32_t* elements, int32_t count, const sh_material& material) {
    for (int32_t k = 0; k < count; ++k)
        require(elements[k] >= 0 && elements[k] < element_count(), SH_ERR_INVALID_ARGUMENT,
                format("elements[%d] = %d is not an element index in [0, %d)", k, elements[k], element_count()));
    vec<sh_material> materials = materials_;
    for (int32_t k = 0; k < count; ++k) materials[static_cast<size_t>(elements[k])] = material;
    rebuild(std::move(materials));
}

void FemBody::rebuild(vec<sh_material> materials) {
    // Everything is built aside and swapped in at the end: a failed allocation changes nothing.
    const size_t tet_count = volume_.size();
    vec<double> new_mass(mass.size(), 0.0);
    for (size_t t = 0; t < tet_count; ++t)
        for (int a = 0; a < 4; ++a) new_mass[static_cast<size_t>(tets_[4 * t + a])] += materials[t].density * volume_[t] / 4.0;

    vec<TetBlock> new_blocks[SH_MATERIAL_COUNT];
    const vec<uint32_t> order = locality_order(tets_, x);
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) {
        vec<uint32_t> members;
        for (const uint32_t t : order)
            if (materials[t].model == model) members.push_back(t);
        vec<TetBlock>& blocks = new_blocks[model];
        blocks.assign(block_count(members.size()), TetBlock{});
        spread_over_lanes(members.data(), members.size(), [&](uint32_t t, bool used, size_t k, int l) {
            fill_lane(t, materials[t], &tets_[4 * static_cast<size_t>(t)], used, blocks[k], l);
        });
    }

    vec<double> omega2(tet_count);
    double largest = 0.0;
    for (size_t t = 0; t < tet_count; ++t) {
        omega2[t] = element_max_frequency_squared(t, materials[t]);
        largest = std::max(largest, omega2[t]);
    }
    stable_step_ = stable_step_at(largest);
    element_omega2_.swap(omega2);

    materials_.swap(materials);
    mass.swap(new_mass);
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) blocks_[model].swap(new_blocks[model]);
    ++matrix_version;
    update_inverse_mass();
}

void FemBody::fill_lane(size_t t, const sh_material& m, const int32_t nodes[4], bool used, TetBlock& b, int lane) const {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) b.Bm.m[i][j][lane] = inverse_rest_[9 * t + 3 * i + j];
    const double weight = used ? -volume_[t] : 0.0;
    b.lambda_w[lane] = weight * lame_lambda(m);
    b.mu_w[lane] = weight * lame_mu(m);
    for (int a = 0; a < 4; ++a) b.node[a][lane] = nodes[a];
}

double FemBody::element_max_frequency_squared(size_t t, const sh_material& material) const {
    // Largest eigenvalue of M_e^-1 K_e with the rest (small-strain) stiffness and the element's
    // share of the lumped mass: an upper bound of the assembled system's (Irons-Treharne).
    const double* bm = &inverse_rest_[9 * t];
    Eigen::Vector3d g[4];
    for (int a = 0; a < 3; ++a) g[a + 1] = Eigen::Vector3d(bm[3 * a], bm[3 * a + 1], bm[3 * a + 2]);
    g[0] = -(g[1] + g[2] + g[3]);
    const double lambda = lame_lambda(material), mu = lame_mu(material), v0 = volume_[t];
    Eigen::Matrix<double, 12, 12> k;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
            k.block<3, 3>(3 * a, 3 * b) = v0 * (lambda * g[a] * g[b].transpose() + mu * g[b] * g[a].transpose() +
                                                 mu * g[a].dot(g[b]) * Eigen::Matrix3d::Identity());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eigen(k, Eigen::EigenvaluesOnly);  // ascending
    return eigen.eigenvalues()(11) * 4.0 / (material.density * v0);
}

void FemBody::add_internal_forces(const double* xs, const double* vs, double* f) const {
    const double* damped_v = damping_stiffness_ > 0.0 ? vs : nullptr;
    int32_t inverted = 0;
    for_each_material([&](auto material, int model) {
        const vec<TetBlock>& blocks = blocks_[model];
        inverted += add_fem_forces<decltype(material)>(blocks.data(), blocks.size(), xs, damped_v, damping_stiffness_, f);
    });
    inverted_elements_ = std::max(inverted_elements_, inverted);
}

double FemBody::elastic_energy(const double* xs) const {
    double energy = 0.0;
    for_each_material([&](auto material, int model) {
        const vec<TetBlock>& blocks = blocks_[model];
        energy += fem_energy<decltype(material)>(blocks.data(), blocks.size(), xs);
    });
    return energy;
}

double FemBody::stable_step(const double*) const { return stable_step_; }

double FemBody::stable_step_at(double omega2) const {
    const double omega = std::sqrt(omega2);
    // Central-difference limit with stiffness damping ratio xi = beta omega / 2.
    const double xi = 0.5 * damping_stiffness_ * omega;
    return omega > 0.0 ? 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi) : INFINITY;
}

double FemBody::stable_step_of(const int32_t* tets, size_t count) const {
    double largest = 0.0;
    for (size_t k = 0; k < count; ++k) largest = std::max(largest, element_omega2_[static_cast<size_t>(tets[k])]);
    return stable_step_at(largest);
}


}  // namespace sh
