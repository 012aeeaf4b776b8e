// The spring-law table's rows: what each law of sh_spring_law implements. A law is one file
// (linear_spring.cpp, ...) defining its functions and its row; spring_law_table.cpp lists the
// rows in sh_spring_law order, and SpringLaw calls its law's functions through its row.
#pragma once

#include "material/monotone_curve.hpp"

#include <softhap/softhap.h>

namespace sh {

/// A law's validated parameters and what it prepares from them. Each law fills and reads
/// only its own fields.
struct SpringLawData {
    sh_spring_params params{};  ///< a copy; params.table is not kept (NULL)
    MonotoneCurve curve;        ///< table: the curve through the rows
};

/// One row of the spring-law table. l and l0 are a spring's length and rest length (m).
struct SpringLawKind {
    sh_spring_law law;  ///< the row's index in the table
    const char* name;   ///< as the Python bindings spell it
    /// Validates the law's fields of params (SH_ERR_INVALID_ARGUMENT naming the field) and
    /// prepares its fields of data (data.params is already a copy).
    void (*init)(const sh_spring_params& params, SpringLawData& data);
    /// Tension (N, positive when stretched).
    double (*tension)(const SpringLawData& data, double l, double l0);
    /// d tension / d l (N/m).
    double (*stiffness)(const SpringLawData& data, double l, double l0);
    /// Energy stored (J): the integral of tension from l0 to l.
    double (*energy)(const SpringLawData& data, double l, double l0);
};

/// The row of law: SH_ERR_INVALID_ARGUMENT if law is not a sh_spring_law.
const SpringLawKind& spring_law_kind(int law);

/// Throws SH_ERR_INVALID_ARGUMENT naming params.<name> unless value is finite and above
/// minimum (strict) or at least minimum.
void require_finite_at_least(double value, double minimum, bool strict, const char* name);

}  // namespace sh
