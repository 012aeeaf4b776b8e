#include "material/material_params.hpp"

#include "core/enum_value.hpp"
#include "core/error.hpp"

#include <cmath>

namespace sh {

void validate_material(const sh_material& m, const char* context) {
    const int model = enum_value(m.model);
    SH_REQUIRE(model >= 0 && model < SH_MATERIAL_COUNT, SH_ERR_INVALID_ARGUMENT, "%s: material.model %d is not a sh_material_model", context, model);
    SH_REQUIRE(std::isfinite(m.young) && m.young > 0.0, SH_ERR_INVALID_ARGUMENT, "%s: material.young = %g Pa, must be finite and > 0", context, m.young);
    SH_REQUIRE(std::isfinite(m.poisson) && m.poisson > -1.0 && m.poisson < 0.5, SH_ERR_INVALID_ARGUMENT, "%s: material.poisson = %g, must lie in (-1, 0.5)", context, m.poisson);
    SH_REQUIRE(std::isfinite(m.density) && m.density > 0.0, SH_ERR_INVALID_ARGUMENT, "%s: material.density = %g kg/m^3, must be finite and > 0", context, m.density);
    SH_REQUIRE(std::isfinite(m.toughness) && m.toughness >= 0.0, SH_ERR_INVALID_ARGUMENT, "%s: material.toughness = %g J/m^2, must be finite and >= 0", context, m.toughness);
}

double lame_lambda(const sh_material& m) {
    return m.young * m.poisson / ((1.0 + m.poisson) * (1.0 - 2.0 * m.poisson));
}

double lame_mu(const sh_material& m) { return m.young / (2.0 * (1.0 + m.poisson)); }

}  // namespace sh
