#include "model/elastic_energy_memo.hpp"

#include <cstring>

namespace sh {

void ElasticEnergyMemo::remember(const double* x, size_t count, uint64_t topology_version, uint64_t matrix_version,
                                 double value) {
    valid_ = false;  // until the copy is whole
    x_.assign(x, x + count);
    value_ = value;
    topology_version_ = topology_version;
    matrix_version_ = matrix_version;
    valid_ = true;
}

bool ElasticEnergyMemo::recall(const double* x, size_t count, uint64_t topology_version, uint64_t matrix_version,
                               double& value) const {
    // Bit for bit: any change of a position, even of the sign of a zero, computes afresh.
    if (!valid_ || topology_version != topology_version_ || matrix_version != matrix_version_ || count != x_.size() ||
        std::memcmp(x_.data(), x, count * sizeof(double)) != 0)
        return false;
    value = value_;
    return true;
}

}  // namespace sh
