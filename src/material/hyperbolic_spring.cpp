// The hyperbolic spring law: T = dx / (a |dx| + b), dx = l - l0, which saturates at 1/a. A
// row of the spring-law table.
#include "material/spring_law_kind.hpp"

#include <cmath>

namespace sh {
namespace {

void hyperbolic_init(const sh_spring_params& p, SpringLawData&) {
    require_finite_at_least(p.a, 0.0, false, "a");
    require_finite_at_least(p.b, 0.0, true, "b");
}

double hyperbolic_tension(const SpringLawData& data, double l, double l0) {
    const double dx = l - l0;
    return dx / (data.params.a * std::fabs(dx) + data.params.b);
}

double hyperbolic_stiffness(const SpringLawData& data, double l, double l0) {
    const double denominator = data.params.a * std::fabs(l - l0) + data.params.b;
    return data.params.b / (denominator * denominator);
}

double hyperbolic_energy(const SpringLawData& data, double l, double l0) {
    const double dx = l - l0, a = data.params.a, b = data.params.b, u = a * std::fabs(dx) / b;
    // The closed form loses its digits to cancellation for small a |dx| / b: its series there.
    if (u < 1e-4) return dx * dx / (2.0 * b) - a * std::fabs(dx) * dx * dx / (3.0 * b * b);
    return std::fabs(dx) / a - b / (a * a) * std::log1p(u);
}

}  // namespace

extern const SpringLawKind kHyperbolicSpring = {SH_SPRING_HYPERBOLIC, "hyperbolic",         hyperbolic_init,
                                                hyperbolic_tension,   hyperbolic_stiffness, hyperbolic_energy};

}  // namespace sh
