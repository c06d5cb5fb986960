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
  double ductility = 1;                                       ///< kappa_u (1 = brittle)
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

/// U of stresses `s` against `strength` (tension first at U >= 1, as PFC tests it).
inline BondUtilisation utilisation(const BondStresses& s, const BondStrength& strength) {
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
/// lambda tau = kappa (c - lambda sigma_axial tan(phi))).
inline CriticalLoad critical_load(const BondStresses& unit, const BondStrength& strength,
                                  double kappa = 1.0) {
  CriticalLoad c;
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
  return s;
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
