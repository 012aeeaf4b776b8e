#include "model/fem_body.hpp"

#include "core/error.hpp"
#include "core/morton.hpp"
#include "core/vec3.hpp"
#include "material/material_params.hpp"
#include "material/material_table.hpp"
#include "model/fem_kernel.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <utility>

namespace sh {

namespace {

// Tets ordered along a Z-order (Morton) curve through their centroids at positions p, so that
// consecutive tets, and the kLanes tets of a block, share nodes and cache lines: the kernels'
// gathers and scatters then mostly hit L1. Node numbering is public and stays as it is; only
// the order of the tets inside the blocks changes (and with it the summation order of f).
vec<uint32_t> locality_order(const vec<int32_t>& tets, const vec<double>& p) {
    const size_t tet_count = tets.size() / 4;
    vec<double> centroid(3 * tet_count);
    for (size_t t = 0; t < tet_count; ++t)
        for (int i = 0; i < 3; ++i) {
            double c = 0.0;
            for (int a = 0; a < 4; ++a) c += p[3 * static_cast<size_t>(tets[4 * t + a]) + i];
            centroid[3 * t + i] = 0.25 * c;
        }
    return morton_order(tet_count, [&](size_t t) { return &centroid[3 * t]; });
}

}  // namespace

FemBody::FemBody(const TetMesh& mesh, const sh_material& material, double damping_mass, double damping_stiffness)
    : Body(mesh.nodes, damping_mass), damping_stiffness_(damping_stiffness) {
    surface_triangles = mesh.surface_triangles;
    const size_t tet_count = mesh.tets.size() / 4;
    ElementSet set;
    set.tets = mesh.tets;
    set.materials.assign(tet_count, material);
    set.inverse_rest.resize(9 * tet_count);
    set.volume.resize(tet_count);
    set.omega2.assign(tet_count, -1.0);
    for (size_t t = 0; t < tet_count; ++t) shape_from_rest(rest, &set.tets[4 * t], &set.inverse_rest[9 * t], set.volume[t]);
    adopt(set, nullptr);
    surface_index_.build(surface_triangles, mass.size());
}

void FemBody::shape_from_rest(const vec<double>& rest_positions, const int32_t* tet, double* bm_out, double& volume) {
    const double* corners[4];
    for (int a = 0; a < 4; ++a) corners[a] = &rest_positions[3 * static_cast<size_t>(tet[a])];
    shape_from_corners(corners, bm_out, volume);
}

void FemBody::shape_from_corners(const double* const corners[4], double* bm_out, double& volume) {
    Eigen::Matrix3d dm;
    for (int a = 0; a < 3; ++a)
        for (int i = 0; i < 3; ++i) dm(i, a) = corners[a + 1][i] - corners[0][i];
    volume = dm.determinant() / 6.0;
    const Eigen::Matrix3d bm = dm.inverse();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) bm_out[3 * i + j] = bm(i, j);
}

void FemBody::set_material(const int32_t* elements, int32_t count, const sh_material& material) {
    for (int32_t k = 0; k < count; ++k)
        require(elements[k] >= 0 && elements[k] < element_count(), SH_ERR_INVALID_ARGUMENT,
                format("elements[%d] = %d is not an element index in [0, %d)", k, elements[k], element_count()));
    ElementSet set;
    set.tets = tets_, set.inverse_rest = inverse_rest_, set.volume = volume_, set.materials = materials_;
    set.omega2 = element_omega2_;
    for (int32_t k = 0; k < count; ++k) {
        set.materials[static_cast<size_t>(elements[k])] = material;
        set.omega2[static_cast<size_t>(elements[k])] = -1.0;
    }
    adopt(set, nullptr);
}

void FemBody::retopologize(const NodeOrigin* origins, size_t origin_count, vec<int32_t> tets, const vec<int32_t>& source) {
    GrownNodes grown = grow_nodes(origins, origin_count);
    const vec<int32_t> changed = changed_tets(tets, source);
    const size_t old_changed = static_cast<size_t>(std::lower_bound(changed.begin(), changed.end(), element_count()) - changed.begin());
    if (changes_locally(changed.size(), old_changed)) return change_locally(grown, tets, source, changed);
    const size_t tet_count = tets.size() / 4;
    ElementSet set;
    set.tets = std::move(tets);
    set.inverse_rest.resize(9 * tet_count);
    set.volume.resize(tet_count);
    set.materials.resize(tet_count);
    set.omega2.resize(tet_count);
    for (size_t t = 0; t < tet_count; ++t) element_from_source(grown, &set.tets[4 * t], source[t], set, t);
    adopt(set, &grown);
}

void FemBody::element_from_source(const GrownNodes& grown, const int32_t* tet, int32_t source, ElementSet& set, size_t slot) const {
    const bool piece = source < 0;
    const size_t from = static_cast<size_t>(piece ? -1 - source : source);
    set.materials[slot] = materials_[from];
    if (piece) {
        const double* corners[4];
        for (int a = 0; a < 4; ++a) corners[a] = grown.rest_of(*this, tet[a]);
        shape_from_corners(corners, &set.inverse_rest[9 * slot], set.volume[slot]);
        set.omega2[slot] = -1.0;  // computed by whoever adopts it
    } else {
        std::copy(&inverse_rest_[9 * from], &inverse_rest_[9 * from] + 9, &set.inverse_rest[9 * slot]);
        set.volume[slot] = volume_[from];
        set.omega2[slot] = element_omega2_[from];
    }
}

void FemBody::reserve_rotations(const vec<TetBlock> (&blocks)[SH_MATERIAL_COUNT], const vec<TetBlock>* added,
                                RotatingBlocks& out) {
    for_each_material([&](auto material, int model) {
        const size_t count = blocks[model].size() + (added ? added[model].size() : 0);
        out[model] = decltype(material)::kRotates ? count : 0;
    });
    rotations_.reserve(out);
}

vec<double> FemBody::lumped_mass(const ElementSet& set, size_t node_count) {
    vec<double> m(node_count, 0.0);
    for (size_t t = 0; t < set.volume.size(); ++t)
        for (int a = 0; a < 4; ++a) m[static_cast<size_t>(set.tets[4 * t + a])] += set.materials[t].density * set.volume[t] / 4.0;
    return m;
}

void FemBody::adopt(ElementSet& set, GrownNodes* grown) {
    // Everything is built aside and swapped in at the end: a failed allocation changes nothing.
    const size_t tet_count = set.volume.size();
    vec<double> new_mass = lumped_mass(set, grown ? grown->node_count() : mass.size());
    vec<TetBlock> new_blocks[SH_MATERIAL_COUNT];
    vec<int32_t> new_lane_of(tet_count, -1);
    const vec<uint32_t> order = locality_order(set.tets, grown ? GrownNodes::joined(x, grown->x) : x);
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) {
        vec<uint32_t> members;
        for (const uint32_t t : order)
            if (set.materials[t].model == model) members.push_back(t);
        vec<TetBlock>& blocks = new_blocks[model];
        blocks.assign(block_count(members.size()), TetBlock{});
        spread_over_lanes(members.data(), members.size(), [&](uint32_t t, bool used, size_t k, int l) {
            fill_lane(set, t, used, blocks[k], l);
            if (used) new_lane_of[t] = static_cast<int32_t>(k * kLanes + static_cast<size_t>(l));
        });
    }
    vec<int32_t> surface = grown ? boundary_triangles(set.tets.data(), tet_count) : vec<int32_t>();
    SurfaceIndex index;
    if (grown) index.build(surface, grown->node_count());

    double largest = 0.0;
    for (size_t t = 0; t < tet_count; ++t) {
        if (set.omega2[t] < 0.0) set.omega2[t] = element_max_frequency_squared(&set.inverse_rest[9 * t], set.volume[t], set.materials[t]);
        largest = std::max(largest, set.omega2[t]);
    }
    RotatingBlocks rotating;
    reserve_rotations(new_blocks, nullptr, rotating);
    // Commit: nothing below allocates.
    if (grown) {
        adopt_nodes(*grown);
        surface_triangles.swap(surface);
        surface_index_.swap(index);
        ++topology_version;
    }
    stable_step_ = stable_step_at(largest);
    stable_step_known_ = true;
    if (!grown) reference_omega2_ = largest;
    tets_.swap(set.tets);
    inverse_rest_.swap(set.inverse_rest);
    volume_.swap(set.volume);
    element_omega2_.swap(set.omega2);
    materials_.swap(set.materials);
    mass.swap(new_mass);
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) blocks_[model].swap(new_blocks[model]);
    lane_of_.swap(new_lane_of);
    rotations_.fit(rotating, false);
    vacant_lanes_ = 0;
    ++matrix_version;
    update_inverse_mass();
}

void FemBody::fill_lane(size_t t, const sh_material& m, const int32_t nodes[4], bool used, TetBlock& b, int lane) const {
    fill_lane_from(&inverse_rest_[9 * t], volume_[t], m, nodes, used, b, lane);
}

void FemBody::fill_lane(const ElementSet& set, size_t t, bool used, TetBlock& b, int lane) {
    fill_lane_from(&set.inverse_rest[9 * t], set.volume[t], set.materials[t], &set.tets[4 * t], used, b, lane);
}

void FemBody::fill_lane_from(const double* bm, double v0, const sh_material& m, const int32_t nodes[4], bool used,
                             TetBlock& b, int lane) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) b.Bm.m[i][j][lane] = bm[3 * i + j];
    const double weight = used ? -v0 : 0.0;
    b.lambda_w[lane] = weight * lame_lambda(m);
    b.mu_w[lane] = weight * lame_mu(m);
    for (int a = 0; a < 4; ++a) b.node[a][lane] = nodes[a];
}

double FemBody::element_max_frequency_squared(const double* bm, double v0, const sh_material& material) {
    // Largest eigenvalue of M_e^-1 K_e with the rest (small-strain) stiffness and the element's
    // share of the lumped mass: an upper bound of the assembled system's (Irons-Treharne).
    // K_e = V0 B^T D B (B: the 6 x 12 strain-displacement matrix, D: Voigt elasticity) has the
    // nonzero eigenvalues of V0 D^1/2 B B^T D^1/2, a 6 x 6 problem instead of a 12 x 12 one.
    Eigen::Vector3d g[4];
    for (int a = 0; a < 3; ++a) g[a + 1] = Eigen::Vector3d(bm[3 * a], bm[3 * a + 1], bm[3 * a + 2]);
    g[0] = -(g[1] + g[2] + g[3]);
    Eigen::Matrix<double, 6, 12> strain = Eigen::Matrix<double, 6, 12>::Zero();  // engineering shears
    for (int a = 0; a < 4; ++a) {
        const double x = g[a](0), y = g[a](1), z = g[a](2);
        strain(0, 3 * a) = x, strain(1, 3 * a + 1) = y, strain(2, 3 * a + 2) = z;
        strain(3, 3 * a) = y, strain(3, 3 * a + 1) = x;
        strain(4, 3 * a + 1) = z, strain(4, 3 * a + 2) = y;
        strain(5, 3 * a) = z, strain(5, 3 * a + 2) = x;
    }
    // D's normal block 2 mu I + lambda 1 1^T has eigenvalues 2 mu + 3 lambda (along 1 1 1) and
    // 2 mu; its shear block is mu I.
    const double lambda = lame_lambda(material), mu = lame_mu(material);
    const double shear_root = std::sqrt(2.0 * mu), bulk_root = std::sqrt(std::max(0.0, 2.0 * mu + 3.0 * lambda));
    Eigen::Matrix<double, 6, 6> d_root = Eigen::Matrix<double, 6, 6>::Zero();
    d_root.topLeftCorner<3, 3>() = shear_root * Eigen::Matrix3d::Identity() + (bulk_root - shear_root) / 3.0 * Eigen::Matrix3d::Ones();
    d_root.bottomRightCorner<3, 3>() = std::sqrt(mu) * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 6, 12> a = d_root * strain;
    const Eigen::Matrix<double, 6, 6> reduced = v0 * a * a.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(reduced, Eigen::EigenvaluesOnly);  // ascending
    return eigen.eigenvalues()(5) * 4.0 / (material.density * v0);
}

double FemBody::element_frequency_bound(const double* bm, const sh_material& material) {
    // trace K_e = V0 (lambda + 4 mu) sum_a |g_a|^2 (each diagonal block of K_e is
    // V0 (lambda g_a g_a^T + mu g_a g_a^T + mu |g_a|^2 I)), and K_e is positive semi-definite.
    double sum = 0.0;
    for (int i = 0; i < 3; ++i) {
        double g0 = 0.0;  // g_0 = -(g_1 + g_2 + g_3)
        for (int a = 0; a < 3; ++a) {
            sum += bm[3 * a + i] * bm[3 * a + i];
            g0 -= bm[3 * a + i];
        }
        sum += g0 * g0;
    }
    return 4.0 * (lame_lambda(material) + 4.0 * lame_mu(material)) * sum / material.density;
}

void FemBody::add_internal_forces(const double* xs, const double* vs, double* f) const {
    const double* damped_v = damping_stiffness_ > 0.0 ? vs : nullptr;
    int32_t inverted = 0;
    for_each_material([&](auto material, int model) {
        using Material = decltype(material);
        const vec<TetBlock>& blocks = blocks_[model];
        const KeptRotations kept = rotations_.pass(model);
        inverted += add_fem_forces<Material>(blocks.data(), blocks.size(), xs, damped_v, damping_stiffness_, f, kept);
    });
    inverted_elements_ = std::max(inverted_elements_, inverted);
}

Body::ElasticEnergy FemBody::add_elastic_forces_and_energy(const double* xs, double* f) const {
    EnergySum sum;
    int32_t inverted = 0;
    for_each_material([&](auto material, int model) {
        using Material = decltype(material);
        const vec<TetBlock>& blocks = blocks_[model];
        inverted += add_fem_forces_and_energy<Material>(blocks.data(), blocks.size(), xs, f, rotations_.pass(model), &sum);
    });
    inverted_elements_ = std::max(inverted_elements_, inverted);
    // Node 0's force is minus the others' sum: its rounding counts about as much again.
    return {sum.value, std::fabs(sum.value) + 2.0 * largest_magnitude(xs, x.size()) * sum.force_norm};
}

double FemBody::elastic_energy(const double* xs) const {
    double energy = 0.0;
    for_each_material([&](auto material, int model) {
        using Material = decltype(material);
        const vec<TetBlock>& blocks = blocks_[model];
        const KeptRotations kept = rotations_.pass(model);
        energy += fem_energy<Material>(blocks.data(), blocks.size(), xs, kept);
    });
    return energy;
}

double FemBody::frequency_squared_of(size_t t) const {
    double& omega2 = element_omega2_[t];
    if (omega2 < 0.0) omega2 = element_max_frequency_squared(&inverse_rest_[9 * t], volume_[t], materials_[t]);
    return omega2;
}

double FemBody::tangent_work() const {
    double work = 0.0;
    for_each_material([&](auto material, int model) {
        work += decltype(material)::kTangentWork * static_cast<double>(blocks_[model].size() * kLanes);
    });
    return work;
}

double FemBody::stable_step(const double*) const {
    if (!stable_step_known_) {
        double largest = 0.0;
        for (size_t t = 0; t < volume_.size(); ++t) largest = std::max(largest, frequency_squared_of(t));
        stable_step_ = stable_step_at(largest);
        stable_step_known_ = true;
    }
    return stable_step_;
}

double FemBody::stable_step_at(double omega2) const {
    const double omega = std::sqrt(omega2);
    // Central-difference limit with stiffness damping ratio xi = beta omega / 2.
    const double xi = 0.5 * damping_stiffness_ * omega;
    return omega > 0.0 ? 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi) : INFINITY;
}

double FemBody::stable_step_of(const int32_t* tets, size_t count) const {
    double largest = 0.0;
    for (size_t k = 0; k < count; ++k) largest = std::max(largest, frequency_squared_of(static_cast<size_t>(tets[k])));
    return stable_step_at(largest);
}


}  // namespace sh
