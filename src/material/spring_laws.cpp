#include "material/spring_laws.hpp"

#include "core/enum_value.hpp"
#include "core/error.hpp"

#include <cmath>

namespace sh {

void require_finite_at_least(double value, double minimum, bool strict, const char* name) {
    const bool ok = std::isfinite(value) && (strict ? value > minimum : value >= minimum);
    SH_REQUIRE(ok, SH_ERR_INVALID_ARGUMENT, "params.%s = %g, must be finite and %s %g", name, value, strict ? ">" : ">=", minimum);
}

SpringLaw::SpringLaw(const sh_spring_params& p) {
    data_.params = p;
    data_.params.table = nullptr;
    require_finite_at_least(p.damping, 0.0, false, "damping");  // every law's dashpot
    row_ = &spring_law_kind(enum_value(p.law));
    row_->init(p, data_);
}

}  // namespace sh
