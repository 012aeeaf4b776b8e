// The sim side of the Volumetric Buffer Model: after each full-model step, the tets around the
// tool's nearest surface point are copied into the back buffer with the full model's state.
#include "collision/closest_point.hpp"
#include "contact/body_contacts.hpp"
#include "contact/shape_contact.hpp"
#include "core/vec3.hpp"
#include "haptic/haptic_context.hpp"
#include "material/material_table.hpp"
#include "model/fem_body.hpp"
#include "model/fem_kernel.hpp"
#include "world/world.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// The tool's nearest FEM surface: which body, which triangle, the point and the distance.
struct NearestSurface {
    Id body = kNullId;
    const FemBody* fem = nullptr;
    int32_t triangle = -1;
    double point[3] = {};
    double distance = INFINITY;
};

NearestSurface nearest_surface(const World& world, const double p[3]) {
    NearestSurface best;
    world.for_each_body([&](Id id, const Body& body) {
        if (!body.is_fem()) return;
        const vec<int32_t>& tris = body.surface_triangles;
        const double* x = body.x.data();
        for (size_t t = 0; t < tris.size(); t += 3) {
            double w[3];
            const double* a = at(x, tris[t]);
            const double* b = at(x, tris[t + 1]);
            const double* c = at(x, tris[t + 2]);
            const double d = closest_on_triangle(p, a, b, c, w);
            if (!(d < best.distance)) continue;
            best.body = id;
            best.fem = static_cast<const FemBody*>(&body);
            best.triangle = static_cast<int32_t>(t / 3);
            best.distance = d;
            for (int k = 0; k < 3; ++k) best.point[k] = w[0] * a[k] + w[1] * b[k] + w[2] * c[k];
        }
    });
    return best;
}

// Distance (m) from tet t's centroid to the segment from a to b.
double centroid_distance(const FemBody& body, int32_t t, const double a[3], const double b[3]) {
    const int32_t* tet = body.element_nodes() + 4 * static_cast<size_t>(t);
    double c[3] = {0.0, 0.0, 0.0};
    for (int v = 0; v < 4; ++v)
        for (int k = 0; k < 3; ++k) c[k] += 0.25 * at(body.x.data(), tet[v])[k];
    return distance_to_segment(c, a, b);
}

// The line the buffer is centred on: through the contact point, along the tool's balls (its
// core: a capsule's axis, a box's or hull's inscribed capsule's; a sphere's is a point), as
// long as they, so that a long tool lying on the surface has its whole length in the buffer.
void contact_line(const Collider& tool, const double point[3], double a[3], double b[3]) {
    const int count = tool.shape.ball_count();
    double first[3], last[3];
    for (int k = 0; k < 3; ++k) a[k] = b[k] = point[k];
    if (count < 2) return;
    tool.shape.ball_centre(tool.target, 0, first);
    tool.shape.ball_centre(tool.target, count - 1, last);
    double axis[3], offset[3];
    sub3(last, first, axis);
    sub3(point, first, offset);
    const double s = std::min(std::max(dot3(offset, axis) / dot3(axis, axis), 0.0), 1.0);
    for (int k = 0; k < 3; ++k) {
        a[k] = point[k] - s * axis[k];
        b[k] = point[k] + (1.0 - s) * axis[k];
    }
}

// The surface node deepest inside the tool (ties: the one nearest the tool's centre), as the
// contact point of near, if any node of near's body is inside.
void deepest_contact(const Collider& tool, NearestSurface& near) {
    const double* x = near.fem->x.data();
    const vec<int32_t>& tris = near.fem->surface_triangles;
    double lo[3], hi[3];
    tool.shape.bounds(tool.target, 0.0, lo, hi);
    double best_depth = 0.0, best_distance = INFINITY;
    for (size_t j = 0; j < tris.size(); ++j) {
        const double* p = at(x, tris[j]);
        if (p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] || p[1] > hi[1] || p[2] < lo[2] || p[2] > hi[2]) continue;
        Penetration pen;
        if (!tool.shape.penetrate_point(tool.target, p, pen)) continue;
        double d[3];
        sub3(p, tool.target.p, d);
        const double distance = norm3(d);
        const bool deeper = pen.depth > best_depth * (1.0 + 1e-9);
        if (!deeper && !(pen.depth >= best_depth * (1.0 - 1e-9) && distance < best_distance)) continue;
        best_depth = pen.depth;
        best_distance = distance;
        near.triangle = static_cast<int32_t>(j / 3);
        for (int k = 0; k < 3; ++k) near.point[k] = p[k];
    }
}

// The proxy's point and outward normal: near's point on its triangle's plane.
void fill_proxy(const NearestSurface& near, Buffer& out) {
    const int32_t* tri = near.fem->surface_triangles.data() + 3 * static_cast<size_t>(near.triangle);
    const double* x = near.fem->x.data();
    double ab[3], ac[3], n[3];
    sub3(at(x, tri[1]), at(x, tri[0]), ab);
    sub3(at(x, tri[2]), at(x, tri[0]), ac);
    cross3(ab, ac, n);
    const double length = norm3(n);
    if (!(length > 0.0)) return;
    out.has_proxy = true;
    for (int k = 0; k < 3; ++k) {
        out.proxy_point[k] = near.point[k];
        out.proxy_normal[k] = n[k] / length;
    }
}

}  // namespace

void HapticContext::ensure_adjacency(const FemBody& body, Id id) {
    if (adjacency_body_ == id && adjacency_version_ == body.topology_version) return;
    const size_t n = static_cast<size_t>(body.node_count()), tets = static_cast<size_t>(body.element_count());
    const int32_t* nodes = body.element_nodes();
    node_tet_begin_.assign(n + 1, 0);
    for (size_t j = 0; j < 4 * tets; ++j) ++node_tet_begin_[static_cast<size_t>(nodes[j]) + 1];
    for (size_t i = 0; i < n; ++i) node_tet_begin_[i + 1] += node_tet_begin_[i];
    node_tet_.assign(4 * tets, 0);
    vec<int32_t> fill(node_tet_begin_.begin(), node_tet_begin_.end() - 1);
    for (size_t j = 0; j < 4 * tets; ++j) node_tet_[static_cast<size_t>(fill[static_cast<size_t>(nodes[j])]++)] = static_cast<int32_t>(j / 4);
    local_of_.assign(n, -1);
    in_buffer_.assign(tets, 0);
    adjacency_body_ = id;
    adjacency_version_ = body.topology_version;
}

void HapticContext::select_tets(const FemBody& body, const BufferCentre& centre, Buffer& out) {
    const int32_t tet_count = body.element_count();
    const double* line_a = centre.a;
    const double* line_b = centre.b;
    ranked_.clear();
    // The tets at the contact: those with a seed node.
    for (size_t k = 0; k < centre.seed_count; ++k) {
        const size_t node = static_cast<size_t>(centre.seeds[k]);
        for (int32_t j = node_tet_begin_[node]; j < node_tet_begin_[node + 1]; ++j) {
            const int32_t t = node_tet_[static_cast<size_t>(j)];
            if (in_buffer_[static_cast<size_t>(t)]) continue;
            in_buffer_[static_cast<size_t>(t)] = 1;
            ranked_.push_back({centroid_distance(body, t, line_a, line_b), t});
        }
    }
    if (def_.rings > 0) {
        size_t frontier = 0;
        for (int32_t ring = 0; ring < def_.rings; ++ring) {
            const size_t end = ranked_.size();
            for (size_t r = frontier; r < end; ++r) {
                const int32_t* tet = body.element_nodes() + 4 * static_cast<size_t>(ranked_[r].second);
                for (int a = 0; a < 4; ++a)
                    for (int32_t j = node_tet_begin_[static_cast<size_t>(tet[a])]; j < node_tet_begin_[static_cast<size_t>(tet[a]) + 1]; ++j) {
                        const int32_t t = node_tet_[static_cast<size_t>(j)];
                        if (in_buffer_[static_cast<size_t>(t)]) continue;
                        in_buffer_[static_cast<size_t>(t)] = 1;
                        ranked_.push_back({centroid_distance(body, t, line_a, line_b), t});
                    }
            }
            frontier = end;
        }
    } else {
        for (int32_t t = 0; t < tet_count; ++t) {
            if (in_buffer_[static_cast<size_t>(t)]) continue;
            const double d = centroid_distance(body, t, line_a, line_b);
            if (d <= def_.radius) ranked_.push_back({d, t});
        }
    }
    for (const auto& r : ranked_) in_buffer_[static_cast<size_t>(r.second)] = 0;
    std::sort(ranked_.begin(), ranked_.end());
    // The nearest first, as many as the capacities hold.
    chosen_.clear();
    int32_t nodes = 0;
    for (const auto& r : ranked_) {
        const int32_t* tet = body.element_nodes() + 4 * static_cast<size_t>(r.second);
        int32_t fresh = 0;
        for (int a = 0; a < 4; ++a) fresh += local_of_[static_cast<size_t>(tet[a])] < 0;
        if (static_cast<int32_t>(chosen_.size()) == def_.capacity_tets || nodes + fresh > def_.capacity_nodes) {
            out.warnings |= 1u << SH_WARN_CAPACITY;
            continue;  // a later, farther tet may still fit within the node capacity
        }
        for (int a = 0; a < 4; ++a)
            if (local_of_[static_cast<size_t>(tet[a])] < 0) local_of_[static_cast<size_t>(tet[a])] = nodes++;
        chosen_.push_back(r.second);
        in_buffer_[static_cast<size_t>(r.second)] = 1;
    }
}

// Local node numbers of the chosen tets (local_of_, ring_), in ascending body order, so that
// the haptic side can match buffers by a merge.
void HapticContext::number_nodes(const FemBody& body, Buffer& out) {
    const int32_t* elements = body.element_nodes();
    int32_t n = 0;
    ring_.clear();
    for (const int32_t t : chosen_)
        for (int a = 0; a < 4; ++a) {
            const int32_t node = elements[4 * static_cast<size_t>(t) + a];
            if (local_of_[static_cast<size_t>(node)] >= 0) {
                ring_.push_back(node);
                local_of_[static_cast<size_t>(node)] = -1;
            }
        }
    std::sort(ring_.begin(), ring_.end());
    for (const int32_t node : ring_) local_of_[static_cast<size_t>(node)] = n++;
    out.node_count = n;
    out.tet_count = static_cast<int32_t>(chosen_.size());
}

// The nodes' ids, start and end positions, masses, and which are interior.
void HapticContext::fill_nodes(const FemBody& body, Buffer& out) {
    const int32_t n = out.node_count;
    const bool have_start = out.period > 0.0 && x_before_body_ == out.body && x_before_.size() == body.x.size();
    const double* start = have_start ? x_before_.data() : body.x.data();
    for (int32_t i = 0; i < n; ++i) {
        const int32_t node = ring_[static_cast<size_t>(i)];
        out.node_id[i] = node;
        for (int k = 0; k < 3; ++k) {
            out.x_start[3 * i + k] = at(start, node)[k];
            out.x_end[3 * i + k] = at(body.x.data(), node)[k];
        }
        out.mass[i] = body.mass[static_cast<size_t>(node)];
        // A node is interior when every tet around it is in the buffer and the full model
        // integrates it; the others follow the full model.
        int32_t around = 0;
        for (int32_t j = node_tet_begin_[static_cast<size_t>(node)]; j < node_tet_begin_[static_cast<size_t>(node) + 1]; ++j)
            around += in_buffer_[static_cast<size_t>(node_tet_[static_cast<size_t>(j)])];
        const bool interior = around == node_tet_begin_[static_cast<size_t>(node) + 1] - node_tet_begin_[static_cast<size_t>(node)] &&
                              body.is_free(node) && !other_contact_[static_cast<size_t>(node)];
        out.inverse_mass[i] = interior ? 1.0 / out.mass[i] : 0.0;
    }
}

// The tets' kernel blocks per material model, lanes over local numbers, spread like the full
// model's. A tet all of whose nodes follow the full model (and none is held) moves nothing
// the haptic side integrates or renders: its forces would fall on prescribed nodes only, so
// it gets no lane (a tenth of a 500-tet buffer, its outer shell).
void HapticContext::fill_blocks(const FemBody& body, Buffer& out) {
    const int32_t* elements = body.element_nodes();
    moved_.assign(static_cast<size_t>(out.node_count), 0);
    for (int32_t i = 0; i < out.node_count; ++i) moved_[static_cast<size_t>(i)] = out.inverse_mass[i] > 0.0;
    for (int32_t h = 0; h < out.held_count; ++h) moved_[static_cast<size_t>(out.held[h])] = 1;
    const auto moves_a_node = [&](int32_t t) {
        bool moves = false;
        for (int a = 0; a < 4; ++a)
            moves = moves || moved_[static_cast<size_t>(local_of_[static_cast<size_t>(elements[4 * static_cast<size_t>(t) + a])])];
        return moves;
    };
    int32_t block = 0;
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) {
        out.block_begin[model] = block;
        members_.clear();
        for (const int32_t t : chosen_)
            if (body.material(static_cast<size_t>(t)).model == model && moves_a_node(t)) members_.push_back(t);
        spread_over_lanes(members_.data(), members_.size(), [&](int32_t t, bool used, size_t k, int l) {
            int32_t local[4];
            for (int a = 0; a < 4; ++a) local[a] = local_of_[static_cast<size_t>(elements[4 * static_cast<size_t>(t) + a])];
            body.fill_lane(static_cast<size_t>(t), body.material(static_cast<size_t>(t)), local, used, out.blocks[block + static_cast<int32_t>(k)], l);
        });
        block += static_cast<int32_t>(block_count(members_.size()));
    }
    out.block_begin[SH_MATERIAL_COUNT] = block;
}

// The rotations of the buffer's elements at the full model's start of step, for the laws
// that keep them: the haptic side's first force pass starts from them instead of finding
// them from F alone (which takes three or four times as long).
void HapticContext::fill_rotations(Buffer& out) const {
    for_each_material([&](auto material, int model) {
        const int32_t begin = out.block_begin[model], end = out.block_begin[model + 1];
        fem_rotations<decltype(material)>(out.blocks + begin, static_cast<size_t>(end - begin), out.x_start,
                                          out.rotations + begin);
    });
}

// The body's surface triangles that lie on a buffer tet, in local numbers.
void HapticContext::fill_triangles(const FemBody& body, Buffer& out) {
    const int32_t* elements = body.element_nodes();
    const vec<int32_t>& tris = body.surface_triangles;
    int32_t count = 0;
    for (size_t t = 0; t < tris.size(); t += 3) {
        const int32_t a = tris[t], b = tris[t + 1], c = tris[t + 2];
        if (local_of_[static_cast<size_t>(a)] < 0 || local_of_[static_cast<size_t>(b)] < 0 || local_of_[static_cast<size_t>(c)] < 0)
            continue;
        bool owned = false;
        for (int32_t j = node_tet_begin_[static_cast<size_t>(a)]; j < node_tet_begin_[static_cast<size_t>(a) + 1] && !owned; ++j) {
            const int32_t tet = node_tet_[static_cast<size_t>(j)];
            if (!in_buffer_[static_cast<size_t>(tet)]) continue;
            const int32_t* e = elements + 4 * static_cast<size_t>(tet);
            bool has_b = false, has_c = false;
            for (int k = 0; k < 4; ++k) {
                has_b |= e[k] == b;
                has_c |= e[k] == c;
            }
            owned = has_b && has_c;
        }
        if (!owned) continue;
        out.triangles[3 * count] = local_of_[static_cast<size_t>(a)];
        out.triangles[3 * count + 1] = local_of_[static_cast<size_t>(b)];
        out.triangles[3 * count + 2] = local_of_[static_cast<size_t>(c)];
        ++count;
    }
    out.triangle_count = count;
}

// The buffer surface's edges, each once (the contact potential's edge terms), the rest sizes
// of its triangles and edges, and its nodes.
void HapticContext::fill_surface_features(const FemBody& body, Buffer& out) {
    const int32_t count = out.triangle_count, n = out.node_count;
    neighbor_.resize(3 * static_cast<size_t>(count));
    pair_triangles_across_edges(out.triangles, static_cast<size_t>(count), neighbor_.data());
    int32_t edges = 0;
    for (int32_t t = 0; t < count; ++t)
        for (int k = 0; k < 3; ++k) {
            const int32_t across = neighbor_[3 * static_cast<size_t>(t) + static_cast<size_t>(k)];
            if (across >= 0 && across <= t) continue;
            const int32_t* own = out.triangles + 3 * t;
            int32_t* edge = out.edges + 2 * edges++;
            edge[0] = own[k];
            edge[1] = own[(k + 1) % 3];
        }
    out.edge_count = edges;
    auto length = [&](int32_t a, int32_t b) {
        double e[3];
        sub3(at(body.rest.data(), out.node_id[a]), at(body.rest.data(), out.node_id[b]), e);
        return norm3(e);
    };
    for (int32_t t = 0; t < count; ++t) {
        const int32_t* f = out.triangles + 3 * t;
        out.triangle_size[t] = std::max({length(f[0], f[1]), length(f[1], f[2]), length(f[2], f[0])});
    }
    for (int32_t e = 0; e < edges; ++e) out.edge_size[e] = length(out.edges[2 * e], out.edges[2 * e + 1]);
    int32_t surface = 0;
    for (int32_t i = 0; i < n; ++i) out.surface_nodes[i] = 0;
    for (int32_t j = 0; j < 3 * count; ++j) out.surface_nodes[out.triangles[j]] = 1;
    for (int32_t i = 0; i < n; ++i)
        if (out.surface_nodes[i]) out.surface_nodes[surface++] = i;  // compacts in place: surface <= i
    out.surface_node_count = surface;
}

void HapticContext::fill_buffer(const World& world, const Collider& tool, const FemBody& body, Buffer& out) {
    number_nodes(body, out);
    fill_nodes(body, out);
    fill_held(world, tool, out);
    fill_blocks(body, out);
    fill_rotations(out);
    fill_triangles(body, out);
    fill_surface_features(body, out);
    for (int k = 0; k < 3; ++k) out.gravity[k] = world.gravity[k];
    out.damping_mass = body.damping_mass;
    out.damping_stiffness = body.damping_stiffness();
    out.dt_stable = body.stable_step_of(chosen_.data(), chosen_.size());
    out.runaway_speed = world.step_settings(out.body).runaway_speed;

    for (const int32_t node : ring_) local_of_[static_cast<size_t>(node)] = -1;
    for (const int32_t t : chosen_) in_buffer_[static_cast<size_t>(t)] = 0;
    std::fill(other_contact_.begin(), other_contact_.end(), 0);
}

void HapticContext::fill_held(const World& world, const Collider& tool, Buffer& out) {
    BladeHold hold;
    if (!world.blade_hold(def_.tool.value, out.body, hold)) return;
    const Body& body = world.body(out.body);
    out.held_work = hold.work;
    out.held_needed = hold.needed;
    out.held_serial = hold.serial;
    for (size_t h = 0; h < hold.count; ++h) {
        const int32_t node = hold.nodes[h];
        const int32_t* found = std::lower_bound(out.node_id, out.node_id + out.node_count, node);
        if (found != out.node_id + out.node_count && *found == node) {
            const int32_t i = static_cast<int32_t>(found - out.node_id);
            tool.target.to_local(at(out.x_end, i), &out.held_offset[3 * out.held_count]);
            out.held[out.held_count++] = i;
            continue;
        }
        double arm[3], torque[3];
        const double* f = &hold.forces[3 * h];
        sub3(at(body.x.data(), node), tool.target.p, arm);
        cross3(arm, f, torque);
        for (int k = 0; k < 3; ++k) out.held_outside_force[k] += f[k], out.held_outside_torque[k] += torque[k];
    }
}

void HapticContext::extract(World& world, double period, Buffer& out) {
    out.body = 0;
    out.node_count = out.tet_count = out.triangle_count = out.surface_node_count = out.edge_count = 0;
    out.held_count = 0;
    out.held_work = out.held_needed = 0.0;
    out.held_serial = 0;
    for (int k = 0; k < 3; ++k) out.held_outside_force[k] = out.held_outside_torque[k] = 0.0;
    for (int32_t& b : out.block_begin) b = 0;
    out.warnings = 0;
    out.has_proxy = false;
    out.period = period;
    out.tool_alive = world.is_valid_collider(def_.tool.value, true);
    extracted_body_ = 0;
    if (!out.tool_alive) return;
    const Collider& tool = world.collider(def_.tool.value, true);
    // The surface point nearest the tool's centre; once the tool is in the surface, where it
    // is deepest (a long tool's tip, the middle of a flat press).
    NearestSurface near = nearest_surface(world, tool.target.p);
    if (!near.fem) return;
    deepest_contact(tool, near);
    fill_proxy(near, out);
    // A buffer only where the tool may touch before the next extraction.
    double lo[3], hi[3], extent[3];
    tool.shape.bounds(tool.target, 0.0, lo, hi);
    sub3(hi, lo, extent);
    const double max_gap = def_.radius + 0.5 * norm3(extent);
    double offset[3];
    sub3(near.point, tool.target.p, offset);
    const bool touching = norm3(offset) <= max_gap;
    // Where a blade holds material, the buffer is there, wherever the tool's own shape is (a
    // scalpel's handle above the tissue, its edge in it): the hold's pull is what the device
    // feels.
    Id held_body = kNullId;
    BufferCentre centre;
    const bool holding = find_held_centre(world, held_body, centre);
    if (!touching && !holding) return;
    const Id body_id = holding ? held_body : near.body;
    const FemBody& body = static_cast<const FemBody&>(world.body(body_id));
    if (!holding || (touching && near.body == held_body)) {
        const int32_t* tri = body.surface_triangles.data() + 3 * static_cast<size_t>(near.triangle);
        if (!holding) contact_line(tool, near.point, centre.a, centre.b);
        else std::copy(near.point, near.point + 3, centre.b);  // from the hold to the contact
        seeds_.insert(seeds_.end(), tri, tri + 3);
        centre.seeds = seeds_.data();
        centre.seed_count = seeds_.size();
    }
    out.body = body_id;
    extracted_body_ = body_id;
    ensure_adjacency(body, body_id);
    // Nodes held by anything else (a table, another tool or body) follow the full model: the
    // buffer models the tool's contact only.
    other_contact_.assign(static_cast<size_t>(body.node_count()), 0);
    if (const BodyContacts* contacts = world.contacts_of(body_id))
        contacts->mark_nodes_of_other_contacts(&tool, other_contact_.data());
    select_tets(body, centre, out);
    fill_buffer(world, tool, body, out);
}

// The FEM body whose nodes the tool's blade holds, the held nodes as seeds (in seeds_) and their
// centroid as the centre's segment (a point, b = a); false, seeds_ empty, if it holds none.
bool HapticContext::find_held_centre(const World& world, Id& body, BufferCentre& centre) {
    seeds_.clear();
    world.for_each_body([&](Id id, const Body& candidate) {
        BladeHold hold;
        if (!seeds_.empty() || !candidate.is_fem() || !world.blade_hold(def_.tool.value, id, hold) || hold.count == 0) return;
        seeds_.assign(hold.nodes, hold.nodes + hold.count);
        body = id;
        double sum[3] = {0.0, 0.0, 0.0};
        for (const int32_t node : seeds_)
            for (int k = 0; k < 3; ++k) sum[k] += at(candidate.x.data(), node)[k];
        for (int k = 0; k < 3; ++k) centre.a[k] = centre.b[k] = sum[k] / static_cast<double>(hold.count);
    });
    centre.seeds = seeds_.data();
    centre.seed_count = seeds_.size();
    return !seeds_.empty();
}

}  // namespace sh
