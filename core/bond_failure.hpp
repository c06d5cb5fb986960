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

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/model.hpp"
#include "core/parallel_bond.hpp"

namespace plydem {

/// One bond's strength (the strength fields of Bonds, core/model.hpp).
struct BondStrength {
  double radius = 0;                                          ///< R of the section [m]
  double tensile = std::numeric_limits<double>::infinity();   ///< sigma_c [Pa]
  double cohesion = std::numeric_limits<double>::infinity();  ///< c [Pa]
  double friction = 0;                                        ///< tan(phi)
  double ductility = 1;  ///< kappa_u (1 = brittle); mixed-mode: kappa_I, in pure mode I
  /// The mixed-mode law's Benzeggagh-Kenane exponent eta (see the file comment); 0 = PFC's law.
  double mixed_mode_exponent = 0;
  double fracture_energy_ratio = 1;  ///< g = GIIc / GIc (mixed-mode law)
  double peak_energy_ratio = 1;      ///< r = E_II / E_I at onset (mixed-mode law)
  bool mixed_mode() const { return mixed_mode_exponent > 0; }
};

/// PFC's moment-contribution factor beta for every bond of plydem (PFC's default).
inline constexpr double kMomentContribution = 1.0;

/// The stresses on a bond's section.
struct BondStresses {
  double axial = 0;   ///< F_n / A, tension positive [Pa]
  double normal = 0;  ///< sigma = F_n / A + beta |M_b| R / I [Pa]
  double shear = 0;   ///< tau = |F_s| / A + beta |M_t| R / J [Pa]
};

/// The stresses from the bond's forces and moments: F_n (signed), |F_s|, |M_b|, |M_t|.
inline BondStresses section_stresses(double normal_force, double shear_force, double bending,
                                     double twisting, double radius) {
  const double area = std::numbers::pi * radius * radius;
  const double inertia = 0.25 * area * radius * radius;  // I = pi R^4 / 4; J = 2 I
  BondStresses s;
  s.axial = normal_force / area;
  s.normal = s.axial + kMomentContribution * bending * radius / inertia;
  s.shear = shear_force / area + kMomentContribution * twisting * radius / (2.0 * inertia);
  return s;
}

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

/// The stresses an intact bond would carry at the same deformation: `stresses` of a bond of
/// damage `damage` < 1 divided by 1 - damage.
inline BondStresses intact_stresses(const BondStresses& stresses, double damage) {
  const double scale = 1.0 / (1.0 - damage);
  return {stresses.axial * scale, stresses.normal * scale, stresses.shear * scale};
}

/// The shear strength at the given axial stress: c - (F_n / A) tan(phi).
inline double shear_capacity(const BondStrength& strength, double axial) {
  return strength.cohesion - axial * strength.friction;
}

/// Utilisation and the mode it points to.
struct BondUtilisation {
  double ratio = 0;  ///< U (see the file comment); +inf if the shear capacity is gone
  BondState mode = BondState::kIntact;  ///< the mode that fails first at U >= 1; intact below
};

/// The mixed-mode law's utilisation components (see the file comment): x = <sigma> / sigma_c
/// (opening) and y = tau / c (sliding), each 0 where the strength is +inf.
struct ModeComponents {
  double opening = 0;  ///< x
  double sliding = 0;  ///< y
};

inline ModeComponents mode_components(const BondStresses& s, const BondStrength& strength) {
  return {std::max(s.normal, 0.0) / strength.tensile, s.shear / strength.cohesion};
}

/// The quadratic criterion's utilisation U = sqrt(x^2 + y^2).
inline double quadratic_utilisation(const ModeComponents& c) {
  return std::sqrt(c.opening * c.opening + c.sliding * c.sliding);
}

/// The mode a mixed-mode bond breaks in: tension where x >= y, else shear.
inline BondState mixed_mode_break(const ModeComponents& c) {
  return c.opening >= c.sliding ? BondState::kBrokenTension : BondState::kBrokenShear;
}

/// The mode mix B = G_II / (G_I + G_II) = r y^2 / (x^2 + r y^2) (0 for an unloaded bond).
inline double mode_mix(const ModeComponents& c, const BondStrength& strength) {
  const double sliding = strength.peak_energy_ratio * c.sliding * c.sliding;
  const double total = c.opening * c.opening + sliding;
  return total > 0 ? sliding / total : 0.0;
}

/// The Benzeggagh-Kenane fracture energy relative to GIc: G_c(B) / GIc = 1 + (g - 1) B^eta.
inline double bk_fracture_energy_ratio(double mix, const BondStrength& strength) {
  return 1.0 + (strength.fracture_energy_ratio - 1.0) * std::pow(mix, strength.mixed_mode_exponent);
}

/// kappa_u(B) = kappa_I (1 + (g - 1) B^eta) (1 - B + B / r), at least 1 (see the file comment).
inline double mixed_mode_ductility(double mix, const BondStrength& strength) {
  return std::max(1.0, strength.ductility * bk_fracture_energy_ratio(mix, strength) *
                           (1.0 - mix + mix / strength.peak_energy_ratio));
}

/// The ductility a bond softens with at stresses `s`: Bonds::ductility for PFC's law, kappa_u(B)
/// of the mix at `s` for the mixed-mode law.
inline double softening_ductility(const BondStresses& s, const BondStrength& strength) {
  if (!strength.mixed_mode()) return strength.ductility;
  return mixed_mode_ductility(mode_mix(mode_components(s, strength), strength), strength);
}

/// U of stresses `s` against `strength`: PFC's law (tension first at U >= 1, as PFC tests it), or
/// for a mixed-mode bond the quadratic criterion U = sqrt(x^2 + y^2) (tension where x >= y).
inline BondUtilisation utilisation(const BondStresses& s, const BondStrength& strength) {
  if (strength.mixed_mode()) {
    const ModeComponents c = mode_components(s, strength);
    BondUtilisation u;
    u.ratio = quadratic_utilisation(c);
    if (u.ratio >= 1) u.mode = mixed_mode_break(c);
    return u;
  }
  const double tension = s.normal / strength.tensile;
  const double capacity = shear_capacity(strength, s.axial);
  const double shear = capacity > 0 ? s.shear / capacity
                                    : (s.shear > 0 ? std::numeric_limits<double>::infinity() : 0);
  BondUtilisation u;
  u.ratio = std::max(tension, shear);
  if (tension >= 1) {
    u.mode = BondState::kBrokenTension;
  } else if (shear >= 1) {
    u.mode = BondState::kBrokenShear;
  }
  return u;
}

/// The damage of a linear-softening bond whose largest utilisation so far (intact stiffness) is
/// `kappa` (see the file comment): 0 up to 1, 1 from `ductility` on.
inline double softening_damage(double kappa, double ductility) {
  if (!(kappa > 1)) return 0;
  if (kappa >= ductility) return 1;
  return 1.0 - (ductility - kappa) / (kappa * (ductility - 1.0));
}

/// The inverse: the kappa at which a bond of `damage` meets the softening line (1 for an intact
/// bond, `ductility` for a broken one).
inline double softening_ratio(double damage, double ductility) {
  return ductility / (1.0 + (1.0 - damage) * (ductility - 1.0));
}

/// kappa_u that makes a softening bond dissipate `fracture_energy` [J/m^2] over `crack_area`
/// [m^2] when it held `peak_energy` [J] at its peak (proportional loading; see the file comment).
/// Below 1 (the bond is too large to dissipate so little), brittle: 1.
inline double bond_ductility(double fracture_energy, double crack_area, double peak_energy) {
  return std::max(1.0, fracture_energy * crack_area / peak_energy);
}

/// Where a bond reaches utilisation `kappa` when its stresses grow in proportion to a load
/// factor: `unit` are the stresses at load factor 1.
struct CriticalLoad {
  double factor = std::numeric_limits<double>::infinity();  ///< +inf: never, under this load
  BondState mode = BondState::kIntact;
};

/// The smallest load factor lambda > 0 at which stresses lambda `unit` reach
/// U = kappa against `strength` (tension: lambda sigma = kappa sigma_c; shear:
/// lambda tau = kappa (c - lambda sigma_axial tan(phi)); mixed-mode law: lambda U = kappa).
inline CriticalLoad critical_load(const BondStresses& unit, const BondStrength& strength,
                                  double kappa = 1.0) {
  CriticalLoad c;
  if (strength.mixed_mode()) {
    const ModeComponents m = mode_components(unit, strength);
    const double u = quadratic_utilisation(m);  // linear in the load factor
    if (u > 0) {
      c.factor = kappa / u;
      c.mode = mixed_mode_break(m);
    }
    return c;
  }
  if (unit.normal > 0) {
    c.factor = kappa * strength.tensile / unit.normal;
    c.mode = BondState::kBrokenTension;
  }
  const double denominator = unit.shear + kappa * unit.axial * strength.friction;
  if (denominator > 0) {
    const double shear = kappa * strength.cohesion / denominator;
    if (shear < c.factor) {
      c.factor = shear;
      c.mode = BondState::kBrokenShear;
    }
  }
  return c;
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
