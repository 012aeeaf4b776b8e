// The cubic spring law: T = lambda1 d^3 + lambda2 d on the strain d = (l - l0) / l0. A row of
// the spring-law table.
#include "material/spring_law_kind.hpp"

namespace sh {
namespace {

void cubic_init(const sh_spring_params& p, SpringLawData&) {
    require_finite_at_least(p.lambda1, 0.0, false, "lambda1");
    require_finite_at_least(p.lambda2, 0.0, true, "lambda2");
}

double cubic_tension(const SpringLawData& data, double l, double l0) {
    const double d = (l - l0) / l0;
    return data.params.lambda1 * d * d * d + data.params.lambda2 * d;
}

double cubic_stiffness(const SpringLawData& data, double l, double l0) {
    const double d = (l - l0) / l0;
    return (3.0 * data.params.lambda1 * d * d + data.params.lambda2) / l0;
}

double cubic_energy(const SpringLawData& data, double l, double l0) {
    const double d = (l - l0) / l0;
    return l0 * (0.25 * data.params.lambda1 * d * d * d * d + 0.5 * data.params.lambda2 * d * d);
}

}  // namespace

extern const SpringLawKind kCubicSpring = {SH_SPRING_CUBIC, "cubic",         cubic_init,
                                           cubic_tension,   cubic_stiffness, cubic_energy};

}  // namespace sh
