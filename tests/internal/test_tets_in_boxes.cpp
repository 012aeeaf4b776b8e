// mesh/tets_in_box.hpp's box query against a brute-force one: a tet's box meets a query box
// exactly when, on every axis, the tet's lowest corner is at most the box's top and its
// highest at least the box's bottom. The query packs eight boxes into one word per node and
// tells a tet's hits apart by zero bytes, so the test crosses group boundaries (1 to 20
// boxes), flat and point boxes, boxes outside the mesh and boxes touching a corner exactly.
#include "mesh/tets_in_box.hpp"

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

struct Mesh {
    std::vector<double> x;
    std::vector<int32_t> tets;
    int32_t nodes() const { return static_cast<int32_t>(x.size() / 3); }
    int32_t count() const { return static_cast<int32_t>(tets.size() / 4); }
};

// Random points in the unit cube, and random tets over them (their shape does not matter).
Mesh random_mesh(std::mt19937& rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_int_distribution<int32_t> node(0, 199);
    Mesh m;
    for (int i = 0; i < 3 * 200; ++i) m.x.push_back(unit(rng));
    for (int t = 0; t < 4 * 500; ++t) m.tets.push_back(node(rng));
    return m;
}

bool meets(const Mesh& m, int32_t t, const double* box) {
    for (int k = 0; k < 3; ++k) {
        double lo = 1e300, hi = -1e300;
        for (int a = 0; a < 4; ++a) {
            const double v = m.x[3 * static_cast<size_t>(m.tets[4 * static_cast<size_t>(t) + a]) + k];
            lo = std::min(lo, v), hi = std::max(hi, v);
        }
        if (lo > box[3 + k] || hi < box[k]) return false;
    }
    return true;
}

// Small boxes, flat and point boxes, boxes outside the cube, and boxes whose bottom or top
// corner is a node.
std::vector<double> random_boxes(std::mt19937& rng, const Mesh& m, int count) {
    std::uniform_real_distribution<double> where(-0.2, 1.2), size(0.0, 0.3);
    std::uniform_int_distribution<int> kind(0, 4);
    std::vector<double> boxes;
    for (int b = 0; b < count; ++b) {
        double lo[3], hi[3];
        const int k = kind(rng);
        for (int i = 0; i < 3; ++i) {
            lo[i] = k >= 3 ? m.x[static_cast<size_t>(3 * b + i)] : where(rng);
            hi[i] = lo[i] + (k == 1 || (k == 2 && i == 0) ? 0.0 : size(rng));
            if (k == 4) std::swap(lo[i], hi[i]), lo[i] = 2.0 * hi[i] - lo[i];  // the node is the top corner
        }
        boxes.insert(boxes.end(), lo, lo + 3);
        boxes.insert(boxes.end(), hi, hi + 3);
    }
    return boxes;
}

void test_hits_match_brute_force(void**) {
    std::mt19937 rng(7);
    int expected = 0, visits = 0;
    for (int round = 0; round < 40; ++round) {
        const Mesh m = random_mesh(rng);
        const int count = 1 + round % 20;
        const std::vector<double> boxes = random_boxes(rng, m, count);
        std::vector<uint8_t> seen(static_cast<size_t>(m.count()) * static_cast<size_t>(count), 0);
        sh::for_each_tet_in_boxes(m.x.data(), m.nodes(), m.tets.data(), m.count(), boxes.data(), count,
                                  [&](int32_t t, int first, uint32_t hits) {
                                      assert_true(hits != 0);
                                      assert_true(first % 8 == 0);
                                      for (int i = 0; i < 8; ++i)
                                          if (hits >> i & 1u) {
                                              assert_true(first + i < count);
                                              seen[static_cast<size_t>(t) * static_cast<size_t>(count) + static_cast<size_t>(first + i)] = 1;
                                          }
                                      ++visits;
                                  });
        for (int32_t t = 0; t < m.count(); ++t)
            for (int b = 0; b < count; ++b) {
                const bool hit = meets(m, t, &boxes[6 * static_cast<size_t>(b)]);
                expected += hit ? 1 : 0;
                assert_int_equal(seen[static_cast<size_t>(t) * static_cast<size_t>(count) + static_cast<size_t>(b)], hit ? 1 : 0);
            }
    }
    assert_true(expected > 1000);  // the boxes do meet tets: the comparison is not vacuous
    assert_true(visits > 0);
}

// The one-box form visits the same tets as the many-box form's first box.
void test_one_box_form_agrees(void**) {
    std::mt19937 rng(11);
    const Mesh m = random_mesh(rng);
    const std::vector<double> boxes = random_boxes(rng, m, 1);
    std::vector<int32_t> one, many;
    sh::for_each_tet_in_box(m.x.data(), m.nodes(), m.tets.data(), m.count(), &boxes[0], &boxes[3],
                            [&](int32_t t) { one.push_back(t); });
    for (int32_t t = 0; t < m.count(); ++t)
        if (meets(m, t, boxes.data())) many.push_back(t);
    assert_true(one == many);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hits_match_brute_force),
        cmocka_unit_test(test_one_box_form_agrees),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
