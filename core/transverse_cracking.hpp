#pragma once
/// \file
/// Closed forms for the stiffness of a cross-ply [0_m/90_n]s with transverse cracks in its 90°
/// layer (../shared/DAMAGE_NOTES.md §5): the shear-lag model (Garrett & Bailey, J. Mater. Sci. 12
/// (1977) 157; Highsmith & Reifsnider, ASTM STP 775 (1982) 103), its ply-discount limit, and
/// Hashin's variational bound (§6).
/// With b the thickness of each 0° sublaminate, d half the 90° layer's thickness and 2 s the crack
/// spacing (s = 1 / (2 density)),
///   E / E0 = 1 / (1 + (d E2) / (b E1) tanh(lambda s) / (lambda s)),
///   lambda^2 = G23 (b E1 + d E2) / (b d^2 E1 E2),
/// E0 = (b E1 + d E2) / (b + d) the uncracked modulus the model assumes (rule of mixtures), and for
/// a dense crack pattern (s -> 0) the ply-discount limit E = b E1 / (b + d).
/// §6's fracture mechanics of the same layer follow: the in-situ strength, the energy of a new
/// crack between two, and the crack density it sets against the applied stress.

#include "core/material.hpp"

namespace plydem {

/// E / E0 of the shear-lag model at `density` cracks per unit length [1/m] (0: 1). Throws
/// plydem::Error for non-positive thicknesses or a negative or non-finite density.
double shear_lag_stiffness_ratio(const Material& material, double b, double d, double density);

/// The ply-discount limit of E / E0: b E1 / (b E1 + d E2).
double ply_discount_stiffness_ratio(const Material& material, double b, double d);

/// The shear-lag parameter lambda of the file comment [1/m].
double shear_lag_parameter(const Material& material, double b, double d);

/// Hashin's variational analysis of the cracked cross-ply (Hashin, Mech. Mater. 4 (1985) 121;
/// Nairn, J. Compos. Mater. 23 (1989) 1106): the 90° layer's axial stress perturbation between two
/// cracks 2a apart is sigma90 psi(xi), xi = x / d, psi(±rho) = 1, psi'(±rho) = 0 (rho = a / d),
/// the minimiser of the complementary energy
///   F = C22 integral over (-rho, rho) of (q psi^2 - p psi'^2 + psi''^2) dxi,
/// with, for lambda = b / d (E_A = E1, E_T = E2, nu_A = nu12, nu_T = nu23, G_A = G12, G_T = G23),
///   C00 = 1/E_T + 1/(lambda E_A),  C02 = (nu_T/E_T)(lambda + 2/3) - lambda nu_A / (3 E_A),
///   C11 = (1/G_T + lambda/G_A) / 3, C22 = (lambda + 1)(3 lambda^2 + 12 lambda + 8) / (60 E_T),
///   p = (C02 - C11) / C22, q = C00 / C22.
/// Its Euler-Lagrange equation psi'''' + p psi'' + q psi = 0 has, where 4q > p^2, the roots
/// ±alpha ± i beta, alpha^2 = (sqrt(q) - p/2) / 2, beta^2 = (sqrt(q) + p/2) / 2, and
///   chi(rho) = -psi'''(rho) = 2 alpha beta (alpha^2 + beta^2) (cosh 2 alpha rho - cos 2 beta rho)
///              / (alpha sin 2 beta rho + beta sinh 2 alpha rho),
/// the minimum of F being 2 C22 chi(rho). The cracked laminate's compliance is then bounded by
///   1/E <= 1/E0 + k1^2 eta(lambda) chi(rho) / (E_T rho),  k1 = E_T / E0,
///   eta = (3 lambda^2 + 12 lambda + 8) / 60,
/// E0 the rule-of-mixtures modulus of the file comment: a rigorous lower bound of the stiffness,
/// tending to the ply-discount limit as rho -> 0.
struct HashinCrossPly {
  double p = 0, q = 0;         ///< the Euler-Lagrange equation's coefficients
  double alpha = 0, beta = 0;  ///< its roots' real and imaginary parts
  double eta = 0;              ///< eta(lambda)
  /// chi(rho) of the comment, for rho > 0.
  double chi(double rho) const;
};

/// Hashin's analysis of the cross-ply of 0° sublaminates `b` thick and a 90° layer 2 `d` thick.
/// Throws plydem::Error for non-positive thicknesses, or where 4q <= p^2 (non-oscillating
/// perturbations, which this closed form does not cover; the message names p and q).
HashinCrossPly hashin_cross_ply(const Material& material, double b, double d);

/// E / E0 of Hashin's variational bound at `density` cracks per unit length [1/m] (0: 1), evenly
/// spaced (2a = 1 / density). Throws plydem::Error as hashin_cross_ply, or for a negative or
/// non-finite density.
double hashin_stiffness_ratio(const Material& material, double b, double d, double density);

// Fracture mechanics of the 90° layer (../shared/DAMAGE_NOTES.md §6). G_Ic is the material's
// G_matrix (the energy of a crack along the fibres); each function throws plydem::Error naming
// G_matrix when the material has none.

/// Where a 90° layer lies in the laminate: between two other plies, or on the surface.
enum class PlyPlacement { kEmbedded, kOuter };

/// The in-situ transverse tensile strength of a 90° layer of thickness `t` (Camanho, Davila,
/// Pinho, Iannucci & Robinson, Compos. A 37 (2006) 165, eqs. 43-46, after Dvorak & Laws 1987):
///   thick:   Y_is = 1.12 sqrt(2) YT (any embedded ply thicker than the transition thickness),
///   thin embedded: Y_is = sqrt(8 G_Ic / (pi t Lambda22)),
///   thin outer:    Y_is = 1.79 sqrt(G_Ic / (pi t Lambda22)),
/// Lambda22 = 2 (1/E2 - nu21^2 / E1). A layer is thin below the transition thickness, where the two
/// are equal; an outer layer has no thick limit of its own here (Camanho's thick outer ply is YT).
struct InSituStrength {
  double thick = 0;                 ///< 1.12 sqrt(2) YT (embedded), YT (outer) [Pa]
  double thin = 0;                  ///< the thin-ply formula at t [Pa]
  double transition_thickness = 0;  ///< where thin = thick [m]
  double value = 0;                 ///< thin below the transition thickness, thick above [Pa]
};
InSituStrength in_situ_transverse_strength(const Material& material, double t,
                                           PlyPlacement placement = PlyPlacement::kEmbedded);

/// The energy a new transverse crack releases per unit crack area when it forms midway in an
/// uncracked interval of length `interval` of the 90° layer, in the shear-lag stress field of the
/// file comment, at the 90° layer's stress sigma90 far from cracks [Pa] (finite fracture
/// mechanics, the complementary energy the new crack adds at fixed load):
///   G = sigma90^2 (lambda d^2 / G23) [2 tanh(lambda L / 4) - tanh(lambda L / 2)]  [J/m^2],
/// increasing in L to sigma90^2 lambda d^2 / G23, an isolated crack's (`interval` = +inf).
double new_crack_energy_release_rate(const Material& material, double b, double d, double sigma90,
                                     double interval);

/// The 90° layer's stress at which an isolated crack releases G_Ic: the energy criterion of the
/// first crack, sqrt(G_Ic G23 / (lambda d^2)) [Pa].
double isolated_crack_stress(const Material& material, double b, double d);

/// The crack-multiplication model: at 90° stress sigma90, the interval L* in which a new crack
/// midway releases exactly G_Ic (+inf below isolated_crack_stress: no crack forms). Cracks that
/// split every interval longer than L* leave intervals between L*/2 and L*, so the crack density
/// lies between 1 / L* and 2 / L* [1/m] (the band crossply's report draws).
double crack_multiplication_interval(const Material& material, double b, double d, double sigma90);

}  // namespace plydem
