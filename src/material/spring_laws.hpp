// Force laws of springs: tension as a function of elongation, its slope and its energy, each
// answered by the law's row of the spring-law table (spring_law_kind.hpp).
#pragma once

#include "material/spring_law_kind.hpp"

#include <softhap/softhap.h>

namespace sh {

/// A validated spring law with its tabulated curve (if any) prepared for evaluation.
class SpringLaw {
public:
    /// Validates params (SH_ERR_INVALID_ARGUMENT naming the field) and copies the table.
    explicit SpringLaw(const sh_spring_params& params);

    /// Tension (N, positive when stretched) of a spring of rest length l0 at length l.
    double tension(double l, double l0) const { return row_->tension(data_, l, l0); }

    /// d tension / d l (N/m) at length l.
    double stiffness(double l, double l0) const { return row_->stiffness(data_, l, l0); }

    /// Energy stored (J): the integral of tension from l0 to l.
    double energy(double l, double l0) const { return row_->energy(data_, l, l0); }

    /// Dashpot coefficient c (N s/m).
    double damping() const { return data_.params.damping; }

private:
    const SpringLawKind* row_;  ///< the law's row of the spring-law table
    SpringLawData data_;
};

}  // namespace sh
