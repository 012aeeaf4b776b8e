// A body's elastic energy at one set of positions, kept for the next caller that asks at the
// same positions. An implicit step ends on the iterate it evaluated last, and the next step
// measures the energy at its start, which is that iterate, as does a step report asked for in
// between: recalled, each costs a comparison of the positions instead of a pass over the
// elements (3 % of a 20 k-tet step each).
#pragma once

#include "core/memory.hpp"

#include <cstddef>
#include <cstdint>

namespace sh {

/// An energy and the positions and body version (its topology and matrix versions: the
/// elements and materials) it was taken at.
class ElasticEnergyMemo {
public:
    /// Keeps value as the energy at x[0..count) of version (allocates only when count grew;
    /// throws std::bad_alloc then, keeping nothing, as any allocation of the step would).
    void remember(const double* x, size_t count, uint64_t topology_version, uint64_t matrix_version, double value);
    /// True, with the kept value in value, if x[0..count) is bit for bit where it was taken and
    /// the versions are the same.
    bool recall(const double* x, size_t count, uint64_t topology_version, uint64_t matrix_version, double& value) const;

private:
    vec<double> x_;
    double value_ = 0.0;
    uint64_t topology_version_ = 0, matrix_version_ = 0;
    bool valid_ = false;
};

}  // namespace sh
