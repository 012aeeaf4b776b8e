#include "cut/edge_split.hpp"

namespace sh {

void split_tet(const int32_t tet[4], const EdgeSplit* splits, int count, vec<std::array<int32_t, 4>>& pieces) {
    const size_t first = pieces.size();
    pieces.push_back({tet[0], tet[1], tet[2], tet[3]});
    for (int k = 0; k < count; ++k) {
        const EdgeSplit& split = splits[k];
        const size_t end = pieces.size();
        for (size_t m = first; m < end; ++m) {
            int lo = -1, hi = -1;
            for (int a = 0; a < 4; ++a) {
                if (pieces[m][a] == split.lo) lo = a;
                if (pieces[m][a] == split.hi) hi = a;
            }
            if (lo < 0 || hi < 0) continue;
            // The new node sits on the edge, so either half keeps the piece's orientation.
            std::array<int32_t, 4> other = pieces[m];
            pieces[m][hi] = split.middle;  // the half at lo
            other[lo] = split.middle;      // the half at hi
            pieces.push_back(other);
        }
    }
}

}  // namespace sh
