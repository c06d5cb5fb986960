#pragma once
/// \file
/// Closed forms for the stiffness of a cross-ply [0_m/90_n]s with transverse cracks in its 90°
/// layer (../shared/DAMAGE_NOTES.md §5): the shear-lag model (Garrett & Bailey, J. Mater. Sci. 12
/// (1977) 157; Highsmith & Reifsnider, ASTM STP 775 (1982) 103) and its ply-discount limit.
/// With b the thickness of each 0° sublaminate, d half the 90° layer's thickness and 2 s the crack
/// spacing (s = 1 / (2 density)),
///   E / E0 = 1 / (1 + (d E2) / (b E1) tanh(lambda s) / (lambda s)),
///   lambda^2 = G23 (b E1 + d E2) / (b d^2 E1 E2),
/// E0 = (b E1 + d E2) / (b + d) the uncracked modulus the model assumes (rule of mixtures), and for
/// a dense crack pattern (s -> 0) the ply-discount limit E = b E1 / (b + d).

#include "core/material.hpp"

namespace plydem {

/// E / E0 of the shear-lag model at `density` cracks per unit length [1/m] (0: 1). Throws
/// plydem::Error for non-positive thicknesses or a negative or non-finite density.
double shear_lag_stiffness_ratio(const Material& material, double b, double d, double density);

/// The ply-discount limit of E / E0: b E1 / (b E1 + d E2).
double ply_discount_stiffness_ratio(const Material& material, double b, double d);

}  // namespace plydem
