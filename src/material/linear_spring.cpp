// The linear spring law: T = k (l - l0). A row of the spring-law table.
#include "material/spring_law_kind.hpp"

namespace sh {
namespace {

void linear_init(const sh_spring_params& p, SpringLawData&) { require_finite_at_least(p.stiffness, 0.0, true, "stiffness"); }

double linear_tension(const SpringLawData& data, double l, double l0) { return data.params.stiffness * (l - l0); }

double linear_stiffness(const SpringLawData& data, double, double) { return data.params.stiffness; }

double linear_energy(const SpringLawData& data, double l, double l0) {
    const double dx = l - l0;
    return 0.5 * data.params.stiffness * dx * dx;
}

}  // namespace

extern const SpringLawKind kLinearSpring = {SH_SPRING_LINEAR, "linear",         linear_init,
                                            linear_tension,   linear_stiffness, linear_energy};

}  // namespace sh
