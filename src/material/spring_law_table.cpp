// The spring-law table: one row per sh_spring_law, in the enum's order. Each law's file
// defines its row; adding a law is its file plus its row here.
#include "material/spring_law_kind.hpp"

#include "core/error.hpp"

namespace sh {

extern const SpringLawKind kLinearSpring, kCubicSpring, kHyperbolicSpring, kTableSpring;

namespace {

const SpringLawKind* const kSpringLaws[] = {
    &kLinearSpring,      // SH_SPRING_LINEAR
    &kCubicSpring,       // SH_SPRING_CUBIC
    &kHyperbolicSpring,  // SH_SPRING_HYPERBOLIC
    &kTableSpring,       // SH_SPRING_TABLE
};
static_assert(sizeof(kSpringLaws) / sizeof(kSpringLaws[0]) == SH_SPRING_LAW_COUNT, "one row per sh_spring_law");

}  // namespace

const SpringLawKind& spring_law_kind(int law) {
    SH_REQUIRE(law >= 0 && law < SH_SPRING_LAW_COUNT, SH_ERR_INVALID_ARGUMENT, "params.law = %d is not a sh_spring_law",
               law);
    const SpringLawKind& row = *kSpringLaws[law];
    // The rows live in their laws' files, out of the compiler's sight here: a row in the wrong
    // place shows at its law's first spring body.
    SH_REQUIRE(row.law == law, SH_ERR_INTERNAL, "spring-law table: row %d holds the %s law (%d)", law, row.name,
               static_cast<int>(row.law));
    return row;
}

}  // namespace sh
