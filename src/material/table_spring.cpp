// The tabulated spring law: T = curve(d) on the strain d = (l - l0) / l0, a monotone cubic
// through measured (strain, force) rows. A row of the spring-law table.
#include "material/spring_law_kind.hpp"

#include "core/error.hpp"

#include <cmath>
#include <cstddef>

namespace sh {
namespace {

void table_init(const sh_spring_params& p, SpringLawData& data) {
    require(p.table != nullptr, SH_ERR_INVALID_ARGUMENT, "params.table is NULL");
    SH_REQUIRE(p.table_rows >= 2, SH_ERR_INVALID_ARGUMENT, "params.table_rows = %d, a curve needs at least 2 rows", p.table_rows);
    for (size_t k = 0; k < static_cast<size_t>(p.table_rows); ++k) {
        const double strain = p.table[2 * k], force = p.table[2 * k + 1];
        SH_REQUIRE(std::isfinite(strain) && std::isfinite(force), SH_ERR_INVALID_ARGUMENT, "params.table row %zu is not finite", k);
        SH_REQUIRE(k == 0 || strain > p.table[2 * (k - 1)], SH_ERR_INVALID_ARGUMENT, "params.table row %zu: strain %g does not increase", k, strain);
    }
    data.curve.build(p.table, p.table_rows);
}

double table_tension(const SpringLawData& data, double l, double l0) { return data.curve.value((l - l0) / l0); }

double table_stiffness(const SpringLawData& data, double l, double l0) { return data.curve.slope((l - l0) / l0) / l0; }

double table_energy(const SpringLawData& data, double l, double l0) { return l0 * data.curve.integral((l - l0) / l0); }

}  // namespace

extern const SpringLawKind kTableSpring = {SH_SPRING_TABLE, "table",         table_init,
                                           table_tension,   table_stiffness, table_energy};

}  // namespace sh
