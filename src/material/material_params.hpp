// Validation of isotropic material parameters and their Lame constants.
#pragma once

#include <softhap/softhap.h>

namespace sh {

/// Throws SH_ERR_INVALID_ARGUMENT naming the parameter unless: the model is known, young > 0,
/// -1 < poisson < 0.5 and density > 0, all finite. context prefixes the message.
void validate_material(const sh_material& material, const char* context);

/// Poisson's ratio above which linear (4-node) tets lock: SH_WARN_LOCKING.
constexpr double kLockingPoisson = 0.45;

/// True if material makes linear tets lock (too stiff when nearly incompressible).
inline bool locks_linear_tets(const sh_material& material) { return material.poisson > kLockingPoisson; }

/// Lame lambda (Pa) of an isotropic material.
double lame_lambda(const sh_material& material);

/// Lame mu, the shear modulus (Pa), of an isotropic material.
double lame_mu(const sh_material& material);

}  // namespace sh
