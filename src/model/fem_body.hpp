// FemBody: a tetrahedral FEM body with per-element materials, lumped mass and Rayleigh damping.
#pragma once

#include "mesh/surface_index.hpp"
#include "mesh/tet_mesh.hpp"
#include "model/block_rotations.hpp"
#include "model/body.hpp"
#include "model/tet_block.hpp"

namespace sh {

/// Explicit tetrahedral FEM body. Elements are grouped by material model into TetBlocks.
class FemBody final : public Body {
public:
    /// Builds the body from mesh's rest shape with one material everywhere, Rayleigh damping
    /// alpha = damping_mass (1/s) and beta = damping_stiffness (s).
    FemBody(const TetMesh& mesh, const sh_material& material, double damping_mass, double damping_stiffness);

    /// Sets the material of the listed elements; recomputes masses, blocks and the stable step.
    void set_material(const int32_t* elements, int32_t count, const sh_material& material);

    /// Replaces the elements after a cut: appends the nodes of origins[0..origin_count) (see
    /// Body::grow_nodes), then takes tets (4 per tet, over the grown numbering, positively
    /// oriented) where source[t] names the tet each comes from: source[t] = s >= 0 keeps tet s's
    /// rest shape and material (its nodes may be copies of s's), source[t] = -1 - s is a piece
    /// of tet s (s's material, its rest shape from its nodes' rest positions). Recomputes
    /// masses, blocks, the surface and the stable step, and bumps topology_version; a failed
    /// allocation changes nothing. A change of a few tets costs time in their count plus linear
    /// copies: their old lanes are emptied and they go into new blocks (every block is rebuilt
    /// in locality order once the emptied lanes reach a quarter of them, or the change is large).
    void retopologize(const NodeOrigin* origins, size_t origin_count, vec<int32_t> tets, const vec<int32_t>& source);

    /// Rest volume of tet t (m^3).
    double rest_volume(size_t t) const { return volume_[t]; }

    /// The largest squared frequency of a tet alone at rest (1/s^2; stable_step is 2/omega
    /// over the largest) when the body's materials were last set (at creation or by
    /// set_material): cuts keep every piece's frequency within a bound of it, so
    /// that the critical step never falls far below the uncut body's however often it is cut.
    double reference_frequency_squared() const { return reference_omega2_; }

    /// Squared largest frequency (1/s^2) that a tet of rest inverse shape bm (9, row-major),
    /// rest volume v0 and material would have.
    static double element_max_frequency_squared(const double* bm, double v0, const sh_material& material);

    /// An upper bound of element_max_frequency_squared (1/s^2), from the trace of the
    /// element's stiffness (which is at least its largest eigenvalue): at most 6 times it,
    /// at a tenth of its cost.
    static double element_frequency_bound(const double* bm, const sh_material& material);

    /// Inverse rest shape Bm (9, row-major) and rest volume of tet (4 node indices) at
    /// rest_positions.
    static void shape_from_rest(const vec<double>& rest_positions, const int32_t* tet, double* bm, double& volume);

    /// Inverse rest shape Bm (9, row-major) and rest volume of the tet with corners[4] (3
    /// values each) at rest.
    static void shape_from_corners(const double* const corners[4], double* bm, double& volume);

    void add_internal_forces(const double* x, const double* v, double* f) const override;
    double elastic_energy(const double* x) const override;
    ElasticEnergy add_elastic_forces_and_energy(const double* x, double* f) const override;
    double stable_step(const double* x) const override;
    /// Per block lane, its law's kTangentWork (the material table).
    double tangent_work() const override;
    void add_tangent(const double* x, double stiffness_scale, double damping_scale,
                     SparseSystem& system) const override;
    const int32_t* element_nodes() const override { return tets_.data(); }
    /// The tets in their blocks' lane order (the kernel blocks' locality order).
    const int32_t* tangent_order() const override;
    int nodes_per_element() const override { return 4; }
    int32_t element_count() const override { return static_cast<int32_t>(volume_.size()); }
    bool is_fem() const override { return true; }
    int32_t inverted_elements() const override { return inverted_elements_; }
    void clear_inverted_elements() override { inverted_elements_ = 0; }

    /// True if node is a corner of a surface triangle.
    bool on_surface(int32_t node) const { return surface_index_.has_node(node); }

    /// The material of tet t.
    const sh_material& material(size_t t) const { return materials_[t]; }

    /// Rayleigh beta (s).
    double damping_stiffness() const { return damping_stiffness_; }
    bool has_internal_damping() const override { return damping_stiffness_ > 0.0; }

    /// Largest stable step (as stable_step) of the tets listed in tets[count] alone.
    double stable_step_of(const int32_t* tets, size_t count) const;

    /// Writes tet t with material m into lane `lane` of block b, over node numbers nodes[4]
    /// (the body's, or a copy's own); an unused lane (used false) gets zero weights.
    void fill_lane(size_t t, const sh_material& m, const int32_t nodes[4], bool used, TetBlock& b, int lane) const;

private:
    /// A body's elements as built aside before they are adopted.
    struct ElementSet {
        vec<int32_t> tets;          ///< 4 per tet
        vec<double> inverse_rest;   ///< 9 per tet
        vec<double> volume;         ///< per tet
        vec<sh_material> materials; ///< per tet
        vec<double> omega2;         ///< per tet; negative: to be computed
    };
    /// Adopts set (and grown's nodes, for a topology change, then also the new surface):
    /// masses, blocks and the stable step, all or nothing.
    void adopt(ElementSet& set, GrownNodes* grown);
    /// Writes into slot of set (all but its nodes) the element data of tet (4 nodes, the
    /// body's or grown's) coming from body tet `source` as retopologize's source[] says:
    /// copied, or a piece with its own rest shape (its frequency left negative: to be computed).
    void element_from_source(const GrownNodes& grown, const int32_t* tet, int32_t source, ElementSet& set, size_t slot) const;
    /// The element data of the tets `changed` of tets (as retopologize takes them), in
    /// changed's order, frequencies computed.
    ElementSet fresh_elements(const GrownNodes& grown, const vec<int32_t>& tets, const vec<int32_t>& source,
                              const vec<int32_t>& changed) const;
    /// Blocks per model for fresh's tets, to go after the body's own, and each tet's lane in
    /// them (block * kLanes + lane, counting the body's blocks).
    void fill_new_blocks(const ElementSet& fresh, vec<TetBlock> (&added)[SH_MATERIAL_COUNT], vec<int32_t>& lanes) const;
    /// Moves the lumped masses of the tets `changed` from their old nodes to fresh's (the body's
    /// elements still the old ones) and recomputes inverse_mass.
    void move_masses(const vec<int32_t>& changed, const ElementSet& fresh) noexcept;
    /// The tets of tets (after a change described by source, as retopologize takes them) that
    /// differ from the body's, ascending.
    vec<int32_t> changed_tets(const vec<int32_t>& tets, const vec<int32_t>& source) const;
    /// True if a change of `changed` tets (of which old were the body's) is done in place.
    bool changes_locally(size_t changed, size_t old) const;
    /// retopologize for the few tets `changed`, in place: see retopologize.
    void change_locally(GrownNodes& grown, const vec<int32_t>& tets, const vec<int32_t>& source, const vec<int32_t>& changed);
    /// Empties the lane of body tet t (zero weights, a live tet's shape).
    void vacate_lane(size_t t);
    /// Room in rotations_ for the blocks of blocks (plus added's, when given) whose law keeps
    /// a rotation, their counts in out; throws std::bad_alloc, changing nothing else.
    void reserve_rotations(const vec<TetBlock> (&blocks)[SH_MATERIAL_COUNT], const vec<TetBlock>* added,
                           RotatingBlocks& out);
    /// Lumped masses of set over node_count nodes.
    static vec<double> lumped_mass(const ElementSet& set, size_t node_count);
    /// fill_lane for tet t of set.
    static void fill_lane(const ElementSet& set, size_t t, bool used, TetBlock& b, int lane);
    /// Writes one lane from a tet's Bm, rest volume, material and nodes.
    static void fill_lane_from(const double* bm, double v0, const sh_material& m, const int32_t nodes[4], bool used,
                               TetBlock& b, int lane);
    /// lane_tets_, rebuilt first (with tangent_order_) if the elements changed since
    /// (allocates only then).
    const vec<int32_t>& tets_by_lane() const;
    /// The tangent of count (1 or 2) consecutive blocks b of model's law at positions xs
    /// (near: their kept rotations, or null), each used lane's (tets: the blocks' lanes' tets,
    /// -1 for none) into system; position counts the tets added, their place in
    /// tangent_order().
    void add_block_tangent(int model, const TetBlock* b, int count, const Mat3L* near, const int32_t* tets,
                           const double* xs, double scale, size_t& position, SparseSystem& system) const;
    /// element_omega2_[t], computed first if unknown.
    double frequency_squared_of(size_t t) const;
    /// 2/omega with the stiffness damping, for omega^2 = omega2 (1/s^2).
    double stable_step_at(double omega2) const;

    vec<int32_t> tets_;          ///< 4 per tet
    vec<double> inverse_rest_;   ///< Bm = Dm^-1, 9 per tet, row-major
    vec<double> volume_;         ///< V0 per tet
    vec<sh_material> materials_; ///< per tet
    vec<TetBlock> blocks_[SH_MATERIAL_COUNT];  ///< per sh_material_model
    mutable BlockRotations rotations_;         ///< the corotational blocks' last rotations
    double damping_stiffness_;
    mutable double stable_step_ = 0.0;       ///< 2/omega_max at rest, with stiffness damping
    mutable bool stable_step_known_ = false; ///< false after a local change, until asked for
    double reference_omega2_ = 0.0;  ///< see reference_frequency_squared
    /// per tet: its largest squared frequency (Irons-Treharne); negative until asked for, for
    /// a piece a local change made (an implicit body never asks)
    mutable vec<double> element_omega2_;
    mutable int32_t inverted_elements_ = 0;  ///< most elements with det F <= 0 at one evaluation
    vec<int32_t> lane_of_;       ///< per tet: block * kLanes + lane in its model's blocks
    /// per lane slot of every model's blocks in turn: the tet in it, -1 for none (lane_of_'s
    /// inverse, for the tangent's scatter), as of matrix_version lane_tets_version_ (0: never;
    /// building the elements bumps matrix_version past it)
    mutable vec<int32_t> lane_tets_;
    mutable vec<int32_t> tangent_order_;  ///< lane_tets_ without its empty lanes
    mutable uint64_t lane_tets_version_ = 0;
    size_t vacant_lanes_ = 0;    ///< lanes emptied by local changes since blocks were last built
    SurfaceIndex surface_index_; ///< surface_triangles by their nodes
};

}  // namespace sh
