#pragma once
/// \file
/// The one failure law of plydem, next to the one bond law (core/parallel_bond.hpp): PFC's linear
/// parallel-bond criterion (Potyondy & Cundall, Int. J. Rock Mech. Min. Sci. 41 (2004) 1329). The
/// static events solver, both explicit kernels and the strength calibration decide through the
/// functions here, so that every path breaks the same bonds at the same load.
///
/// A bond's cross-section is a disc of radius R: A = pi R^2, I = pi R^4 / 4, J = pi R^4 / 2. With
/// the bond's normal force F_n (tension positive), shear force F_s, bending moment M_b and twisting
/// moment M_t (core/parallel_bond.hpp: F = k_n du_n n + k_s du_s, M = k_t dtheta_n n + k_b
/// dtheta_s), the largest normal and shear stresses on the section are
///   sigma = F_n / A + beta |M_b| R / I,      tau = |F_s| / A + beta |M_t| R / J,
/// beta the moment-contribution factor (0..1). The bond fails in tension when sigma >= sigma_c,
/// else in shear when tau >= c - (F_n / A) tan(phi): compression raises the shear strength
/// (cohesion c, friction angle phi). Tension is tested first, as PFC does.
///
/// The scalar law (strengths, stresses, utilisation, softening, the mixed-mode law) lives in
/// core/bond_failure_law.hpp, compiled for host and device alike; this header adds what reads the
/// model's arrays.
///
/// Both stresses depend on |du_s|, |dtheta_s|, du_n and dtheta_n only, which are the same seen
/// from either end of the bond (swapping the ends flips n, du and dtheta together), so the decision
/// does not depend on which particle is `first` or on the particles' order.
///
/// Utilisation. U = max(sigma / sigma_c, tau / (c - (F_n / A) tan(phi))) is the bond's load
/// relative to its strength; it fails at U >= 1. For phi = 0, U scales linearly with the bond's
/// deformation.
///
/// Softening. A linear-softening bond is a bilinear traction-separation law in terms of kappa, the
/// largest utilisation the bond has seen, computed with its intact stiffness: elastic up to
/// kappa = 1, then its stiffness falls so that its load follows a straight line from the peak to
/// zero at kappa = kappa_u (the bond's `ductility`):
///   1 - damage = (kappa_u - kappa) / (kappa (kappa_u - 1)),   1 <= kappa <= kappa_u.
/// Under proportional loading such a bond dissipates kappa_u times the elastic energy it held at
/// its peak (the triangle's area), so kappa_u = G A_crack / E_peak makes it dissipate the fracture
/// energy G over its share A_crack of crack area (bond_ductility). kappa_u = 1 is brittle.
/// Events solvers follow the same line as a saw-tooth (DAMAGE_NOTES §3): a bond of damage d next
/// fails when its kappa reaches softening_ratio(d, kappa_u), the line's kappa at stiffness 1 - d.
///
/// Mixed-mode law (interface bonds: Bonds::mixed_mode_exponent eta > 0; every other bond keeps
/// PFC's law above). With the section stresses above (for an interface bond, k_b = k_t = 0, so
/// sigma = F_n / A and tau = |F_s| / A, A = pi R^2, and the section strengths are the interface's
/// N and S times area / A: sigma / sigma_c = t_n / N and tau / c = t_s / S with t = F / area the
/// nominal tractions), the utilisation components
///   x = <sigma> / sigma_c   (Macaulay: compression does not count),      y = tau / c
/// give
///  - onset, the quadratic nominal-traction criterion: U = sqrt(x^2 + y^2) = 1. U scales linearly
///    with the bond's deformation, so the events solver's critical load factor stays kappa / U of
///    the unit solution. No friction term: a mixed-mode bond has tan(phi) = 0.
///  - the mode mix from the bond's current deformation, B = G_II / (G_I + G_II) with
///    G_I ~ <F_n>^2 / (2 k_n) and G_II ~ |F_s|^2 / (2 k_s): B = r y^2 / (x^2 + r y^2), where
///    r = E_II / E_I = (c^2 / k_s) / (sigma_c^2 / k_n) is the ratio of the energies the intact bond
///    holds at onset in pure mode II and pure mode I (Bonds::peak_energy_ratio); B = 0 when the
///    bond is unloaded.
///  - propagation, Benzeggagh & Kenane (Compos. Sci. Technol. 56 (1996) 439):
///    G_c(B) = GIc + (GIIc - GIc) B^eta. The intact bond holds E_peak(B) = E_I / (1 - B + B / r)
///    at onset under the mix B, so the ductility that makes it dissipate G_c(B) area is
///      kappa_u(B) = G_c(B) area / E_peak(B) = kappa_I (1 + (g - 1) B^eta) (1 - B + B / r),
///    kappa_I = GIc area / E_I the bond's pure mode I ductility (Bonds::ductility) and
///    g = GIIc / GIc (Bonds::fracture_energy_ratio); at least 1 (brittle). B = 0 gives kappa_I and
///    the onset x = sigma / sigma_c: PFC's tension law exactly; B = 1 gives GIIc area / E_II.
///  - history: the mix is taken where the law is evaluated, from the bond's intact-equivalent
///    stresses at that state (explicit kernels: every cycle at which U passes the largest U so
///    far, kappa; events solver: the unit solution of each equilibrium, whose mix every load
///    factor shares), and the damage never falls: d = max(d, softening_damage(kappa,
///    kappa_u(B))). Under a fixed mix (proportional loading) this is the linear-softening law of
///    ductility kappa_u(B), which dissipates exactly G_c(B) area.
///  - break mode: tension where x >= y at the break, else shear.
/// Brittle mixed-mode bonds (no fracture energy) have kappa_I = g = r = 1: kappa_u(B) = 1.

#include <cmath>

#include "core/bond_failure_law.hpp"
#include "core/model.hpp"
#include "core/parallel_bond.hpp"

namespace plydem {

/// The stresses of bond `b` (its current, possibly damaged, stiffnesses) at the given state of its
/// two particles, in the bond's own orientation (first -> second).
inline BondStresses bond_stresses(const BondParameters& b, double radius,
                                  const Eigen::Vector3d& u_i, const Eigen::Vector3d& theta_i,
                                  const Eigen::Vector3d& u_j, const Eigen::Vector3d& theta_j) {
  const Eigen::Vector3d& n = b.normal;
  const Eigen::Vector3d du = contact_relative_displacement(b, u_i, theta_i, u_j, theta_j);
  const double du_n = n.dot(du);
  const Eigen::Vector3d dtheta = theta_j - theta_i;
  const double dtheta_n = n.dot(dtheta);
  return section_stresses(b.normal_stiffness * du_n, shear_force(b, du - du_n * n).norm(),
                          b.bending_stiffness * (dtheta - dtheta_n * n).norm(),
                          b.twisting_stiffness * std::abs(dtheta_n), radius);
}

/// Bond b's strength, from the Bonds arrays.
inline BondStrength bond_strength(const Bonds& bonds, int b) {
  BondStrength s;
  s.radius = bonds.strength_radius(b);
  s.tensile = bonds.tensile_strength(b);
  s.cohesion = bonds.cohesion(b);
  s.friction = bonds.friction_coefficient(b);
  s.ductility = bonds.ductility(b);
  s.mixed_mode_exponent = bonds.mixed_mode_exponent(b);
  s.fracture_energy_ratio = bonds.fracture_energy_ratio(b);
  s.peak_energy_ratio = bonds.peak_energy_ratio(b);
  return s;
}

/// Whether a bond of `strength` may soften (ductility > 1 under some mix): PFC's law at
/// ductility > 1; every mixed-mode bond but a brittle one (kappa_I = g = r = 1).
inline bool may_soften(const BondStrength& strength) {
  return strength.ductility > 1 || (strength.mixed_mode() && (strength.fracture_energy_ratio != 1 ||
                                                              strength.peak_energy_ratio != 1));
}

/// The softening history (largest utilisation so far, kappa) that a bond of `damage` starts from
/// when a kernel is built on it: 1 for an intact bond; PFC's law: softening_ratio(damage,
/// ductility); mixed-mode law: 1, since its kappa_u depends on the mix the damage was taken at
/// (the damage never falls, so a lower kappa only makes the law look again).
inline double softening_history(double damage, const BondStrength& strength) {
  if (!(damage > 0) || strength.mixed_mode()) return 1.0;
  return softening_ratio(damage, strength.ductility);
}

/// One broken (or, for softening, fully softened) bond, as solvers log it.
struct BondBreak {
  int bond = 0;                                ///< row in Bonds
  BondState mode = BondState::kBrokenTension;  ///< tension or shear
  double at = 0;    ///< event number (events solver) or time [s] (explicit)
  double load = 0;  ///< the grip displacement or strain at the break, as the solver states it
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< the bond's contact point [m]
};

/// "tension" or "shear" ("intact" for kIntact).
inline const char* mode_name(BondState mode) {
  switch (mode) {
    case BondState::kBrokenTension:
      return "tension";
    case BondState::kBrokenShear:
      return "shear";
    case BondState::kIntact:
      break;
  }
  return "intact";
}

}  // namespace plydem
