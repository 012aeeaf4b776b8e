#include "cut/tearing.hpp"

#include "core/clock.hpp"
#include "model/spring_body.hpp"
#include "world/world.hpp"

#include <algorithm>
#include <numeric>

namespace sh {
namespace {

/// Names the world's tearing hook.
const char kTearingKey = 0;

int32_t root(vec<int32_t>& parent, int32_t i) {
    while (parent[static_cast<size_t>(i)] != i) i = parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    return i;
}

/// A spring body's topology after its overstretched springs break.
struct Torn {
    vec<int32_t> springs;      ///< 2 per spring left (copies' indices where re-pointed)
    vec<double> rest_lengths;  ///< per spring left
    vec<NodeOrigin> copies;    ///< nodes split off
    vec<double> masses;        ///< every node's, the copies' appended
};

/// Per node, its springs (indices into springs), as compressed rows.
struct NodeSprings {
    vec<size_t> first;   ///< node i's springs are at[first[i], first[i + 1])
    vec<int32_t> at;

    NodeSprings(const vec<int32_t>& springs, size_t node_count) : first(node_count + 1, 0), at(springs.size()) {
        for (const int32_t n : springs) ++first[static_cast<size_t>(n) + 1];
        std::partial_sum(first.begin(), first.end(), first.begin());
        vec<size_t> next(first.begin(), first.end() - 1);
        for (size_t s = 0; s < springs.size() / 2; ++s)
            for (int e = 0; e < 2; ++e) at[next[static_cast<size_t>(springs[2 * s + static_cast<size_t>(e)])]++] = static_cast<int32_t>(s);
    }
};

/// The node at the other end of spring s from node n.
int32_t other_end(const vec<int32_t>& springs, int32_t s, int32_t n) {
    return springs[2 * static_cast<size_t>(s)] == n ? springs[2 * static_cast<size_t>(s) + 1] : springs[2 * static_cast<size_t>(s)];
}

/// Splits node n of body (springs left in kept, their rows in rows; torn.springs is kept with
/// the splits so far re-pointed) if the neighbours its springs
/// reach were one group joined by springs among themselves when the body was made and now fall
/// into several: each extra group's springs move to a copy of n, whose mass is n's share by
/// the rest length of its springs. Nodes whose neighbours were never joined (a chain, a
/// lattice without diagonals) stay as they are.
void split_if_pinched(const SpringBody& body, const vec<int32_t>& kept, const NodeSprings& rows, int32_t n, Torn& torn) {
    const size_t begin = rows.first[static_cast<size_t>(n)], end = rows.first[static_cast<size_t>(n) + 1];
    const size_t count = end - begin;
    if (count < 2) return;
    vec<int32_t> ends(count);
    for (size_t k = 0; k < count; ++k) ends[k] = other_end(kept, rows.at[begin + k], n);
    vec<int32_t> before(count), now(count);
    std::iota(before.begin(), before.end(), 0);
    std::iota(now.begin(), now.end(), 0);
    for (size_t i = 0; i < count; ++i)
        for (size_t j = i + 1; j < count; ++j) {
            if (body.were_joined(ends[i], ends[j])) before[static_cast<size_t>(root(before, static_cast<int32_t>(i)))] = root(before, static_cast<int32_t>(j));
            const size_t b = rows.first[static_cast<size_t>(ends[i])], e = rows.first[static_cast<size_t>(ends[i]) + 1];
            for (size_t k = b; k < e; ++k)
                if (other_end(kept, rows.at[k], ends[i]) == ends[j]) {
                    now[static_cast<size_t>(root(now, static_cast<int32_t>(i)))] = root(now, static_cast<int32_t>(j));
                    break;
                }
        }
    const auto groups = [&](vec<int32_t>& parent) {
        int32_t g = 0;
        for (size_t i = 0; i < count; ++i) g += root(parent, static_cast<int32_t>(i)) == static_cast<int32_t>(i) ? 1 : 0;
        return g;
    };
    if (groups(before) != 1 || groups(now) == 1) return;
    // Each group's share of n's springs by rest length; the largest keeps n.
    vec<double> length(count, 0.0);
    double total = 0.0;
    for (size_t k = 0; k < count; ++k) {
        const double l = torn.rest_lengths[static_cast<size_t>(rows.at[begin + k])];
        length[static_cast<size_t>(root(now, static_cast<int32_t>(k)))] += l;
        total += l;
    }
    const size_t keeper = static_cast<size_t>(std::max_element(length.begin(), length.end()) - length.begin());
    const double mass = torn.masses[static_cast<size_t>(n)];
    for (size_t g = 0; g < count; ++g) {
        if (root(now, static_cast<int32_t>(g)) != static_cast<int32_t>(g) || g == keeper) continue;
        const int32_t copy = static_cast<int32_t>(torn.masses.size());
        torn.copies.push_back(NodeOrigin{n, n, 0.0});
        torn.masses.push_back(mass * length[g] / total);
        torn.masses[static_cast<size_t>(n)] -= mass * length[g] / total;
        for (size_t k = 0; k < count; ++k) {
            if (static_cast<size_t>(root(now, static_cast<int32_t>(k))) != g) continue;
            const size_t s = static_cast<size_t>(rows.at[begin + k]);
            int32_t* spring = &torn.springs[2 * s];
            (spring[0] == n ? spring[0] : spring[1]) = copy;
        }
    }
}

/// body's topology once its overstretched springs (broken, one per spring) break.
Torn tear(const SpringBody& body, const vec<uint8_t>& broken) {
    Torn torn;
    vec<int32_t> touched;
    for (size_t s = 0; s < broken.size(); ++s) {
        const int32_t* ends = &body.springs()[2 * s];
        if (broken[s]) {
            touched.insert(touched.end(), ends, ends + 2);
            continue;
        }
        torn.springs.insert(torn.springs.end(), ends, ends + 2);
        torn.rest_lengths.push_back(body.rest_lengths()[s]);
    }
    torn.masses = body.mass;
    const vec<int32_t> kept = torn.springs;
    const NodeSprings rows(kept, static_cast<size_t>(body.node_count()));
    // A broken spring changes the neighbourhood of the nodes next to both its ends (it joined
    // two of their neighbours): those may be left pinched, as may its ends.
    const size_t ends = touched.size();
    for (size_t i = 0; i < ends; ++i)
        for (size_t k = rows.first[static_cast<size_t>(touched[i])]; k < rows.first[static_cast<size_t>(touched[i]) + 1]; ++k)
            touched.push_back(other_end(kept, rows.at[k], touched[i]));
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (const int32_t n : touched) split_if_pinched(body, kept, rows, n, torn);
    return torn;
}

/// Tears every mass-spring body with a breaking strain before the step's motion.
class Tearing final : public BeforeMotionHook {
public:
    void before_motion(World& world, sh_step_report& report) override {
        const double start = now_seconds();
        bool any = false;
        world.for_each_body([&](Id id, const Body& found) {
            if (found.is_fem()) return;
            const SpringBody& body = static_cast<const SpringBody&>(found);
            if (!(body.break_strain() > 0.0)) return;
            const vec<uint8_t> broken = body.overstretched(body.x.data());
            const int32_t count = static_cast<int32_t>(std::count(broken.begin(), broken.end(), uint8_t{1}));
            if (count == 0) return;
            Torn torn = tear(body, broken);
            TopologyScratch prepared;
            world.prepare_topology_change(id, body.node_count() + static_cast<int32_t>(torn.copies.size()), prepared);
            static_cast<SpringBody&>(world.body(id)).retopologize(torn.copies, std::move(torn.springs), std::move(torn.rest_lengths), torn.masses);
            world.topology_changed(id, prepared);
            report.springs_broken += count;
            any = true;
        });
        if (any) report.topology_seconds += now_seconds() - start;
    }
};

}  // namespace

void enable_tearing(World& world) { world.own_hook_once<Tearing>(&kTearingKey); }

}  // namespace sh
