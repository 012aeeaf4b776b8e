// Force laws of springs: tension as a function of elongation, its slope and its energy.
#pragma once

#include "core/memory.hpp"

#include <softhap/softhap.h>

namespace sh {

/// A validated spring law with its tabulated curve (if any) prepared for evaluation.
class SpringLaw {
public:
    /// Validates params (SH_ERR_INVALID_ARGUMENT naming the field) and copies the table.
    explicit SpringLaw(const sh_spring_params& params);

    /// Tension (N, positive when stretched) of a spring of rest length l0 at length l.
    double tension(double l, double l0) const;

    /// d tension / d l (N/m) at length l.
    double stiffness(double l, double l0) const;

    /// Energy stored (J): the integral of tension from l0 to l.
    double energy(double l, double l0) const;

    /// Dashpot coefficient c (N s/m).
    double damping() const { return params_.damping; }

private:
    /// Monotone cubic (Fritsch-Carlson) through the table, linear beyond its ends.
    double curve(double strain) const;
    double curve_slope(double strain) const;
    double curve_integral(double strain) const;  ///< integral of curve from strain 0

    sh_spring_params params_;
    vec<double> strain_, force_, slope_;  ///< table knots and Hermite slopes
    vec<double> knot_integral_;           ///< integral of curve from strain_[0] to each knot
};

}  // namespace sh
