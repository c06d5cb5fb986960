#pragma once
/// \file
/// The scalar part of the one failure law (core/bond_failure.hpp, whose file comment states the
/// law): strengths, section stresses, utilisation, softening and the mixed-mode law, as value types
/// and functions over doubles. No Eigen here and every function PLYDEM_HOST_DEVICE
/// (core/host_device.hpp), so that the CUDA kernel (solvers/cuda_backend.cu) decides a bond with
/// the very code the host kernels and the events solver use.

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/bond_state.hpp"
#include "core/host_device.hpp"

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
  PLYDEM_HOST_DEVICE bool mixed_mode() const { return mixed_mode_exponent > 0; }
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
PLYDEM_HOST_DEVICE inline BondStresses section_stresses(double normal_force, double shear_force,
                                                        double bending, double twisting,
                                                        double radius) {
  // pi spelled out (the same double as std::numbers::pi): device code reads no host variable.
  constexpr double pi = 3.141592653589793238462643383279502884;
  const double area = pi * radius * radius;
  const double inertia = 0.25 * area * radius * radius;  // I = pi R^4 / 4; J = 2 I
  BondStresses s;
  s.axial = normal_force / area;
  s.normal = s.axial + kMomentContribution * bending * radius / inertia;
  s.shear = shear_force / area + kMomentContribution * twisting * radius / (2.0 * inertia);
  return s;
}

/// The stresses an intact bond would carry at the same deformation: `stresses` of a bond of
/// damage `damage` < 1 divided by 1 - damage.
PLYDEM_HOST_DEVICE inline BondStresses intact_stresses(const BondStresses& stresses,
                                                       double damage) {
  const double scale = 1.0 / (1.0 - damage);
  return {stresses.axial * scale, stresses.normal * scale, stresses.shear * scale};
}

/// The shear strength at the given axial stress: c - (F_n / A) tan(phi).
PLYDEM_HOST_DEVICE inline double shear_capacity(const BondStrength& strength, double axial) {
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

PLYDEM_HOST_DEVICE inline ModeComponents mode_components(const BondStresses& s,
                                                         const BondStrength& strength) {
  return {std::max(s.normal, 0.0) / strength.tensile, s.shear / strength.cohesion};
}

/// The quadratic criterion's utilisation U = sqrt(x^2 + y^2).
PLYDEM_HOST_DEVICE inline double quadratic_utilisation(const ModeComponents& c) {
  return std::sqrt(c.opening * c.opening + c.sliding * c.sliding);
}

/// The mode a mixed-mode bond breaks in: tension where x >= y, else shear.
PLYDEM_HOST_DEVICE inline BondState mixed_mode_break(const ModeComponents& c) {
  return c.opening >= c.sliding ? BondState::kBrokenTension : BondState::kBrokenShear;
}

/// The mode mix B = G_II / (G_I + G_II) = r y^2 / (x^2 + r y^2) (0 for an unloaded bond).
PLYDEM_HOST_DEVICE inline double mode_mix(const ModeComponents& c, const BondStrength& strength) {
  const double sliding = strength.peak_energy_ratio * c.sliding * c.sliding;
  const double total = c.opening * c.opening + sliding;
  return total > 0 ? sliding / total : 0.0;
}

/// The Benzeggagh-Kenane fracture energy relative to GIc: G_c(B) / GIc = 1 + (g - 1) B^eta.
PLYDEM_HOST_DEVICE inline double bk_fracture_energy_ratio(double mix,
                                                          const BondStrength& strength) {
  return 1.0 + (strength.fracture_energy_ratio - 1.0) * std::pow(mix, strength.mixed_mode_exponent);
}

/// kappa_u(B) = kappa_I (1 + (g - 1) B^eta) (1 - B + B / r), at least 1 (see the file comment).
PLYDEM_HOST_DEVICE inline double mixed_mode_ductility(double mix, const BondStrength& strength) {
  return std::max(1.0, strength.ductility * bk_fracture_energy_ratio(mix, strength) *
                           (1.0 - mix + mix / strength.peak_energy_ratio));
}

/// The ductility a bond softens with at stresses `s`: Bonds::ductility for PFC's law, kappa_u(B)
/// of the mix at `s` for the mixed-mode law.
PLYDEM_HOST_DEVICE inline double softening_ductility(const BondStresses& s,
                                                     const BondStrength& strength) {
  if (!strength.mixed_mode()) return strength.ductility;
  return mixed_mode_ductility(mode_mix(mode_components(s, strength), strength), strength);
}

/// U of stresses `s` against `strength`: PFC's law (tension first at U >= 1, as PFC tests it), or
/// for a mixed-mode bond the quadratic criterion U = sqrt(x^2 + y^2) (tension where x >= y).
PLYDEM_HOST_DEVICE inline BondUtilisation utilisation(const BondStresses& s,
                                                      const BondStrength& strength) {
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
PLYDEM_HOST_DEVICE inline double softening_damage(double kappa, double ductility) {
  if (!(kappa > 1)) return 0;
  if (kappa >= ductility) return 1;
  return 1.0 - (ductility - kappa) / (kappa * (ductility - 1.0));
}

/// The inverse: the kappa at which a bond of `damage` meets the softening line (1 for an intact
/// bond, `ductility` for a broken one).
PLYDEM_HOST_DEVICE inline double softening_ratio(double damage, double ductility) {
  return ductility / (1.0 + (1.0 - damage) * (ductility - 1.0));
}

/// The energy-equivalent saw-tooth (Rots, Belletti & Invernizzi, Eng. Fract. Mech. 75 (2008) 590;
/// ../shared/DAMAGE_NOTES.md §7). A softening member whose teeth sit on a linear-softening line
/// of ductility kappa_u' (each keeping `ratio` of the stiffness fraction s_k = ratio^k, tooth k at
/// kappa_k = softening_ratio(1 - s_k, kappa_u'), until the next would fall below `last_stiffness`:
/// that last one fails at kappa_u' and breaks) dissipates, under proportional loading,
///   sum_k kappa_k^2 (s_k - s_k+1) + kappa_u'^2 s_K
/// times its peak energy, less than the line's kappa_u' (the teeth cut the triangle's corners:
/// 0.75 of it at ratio 0.5). This is the kappa_u' whose teeth dissipate `ductility` (kappa_u: the
/// line's own area, G A / W_peak) exactly: the line stretched, so that the first tooth stays at the
/// strength (kappa = 1), no tooth rises above it, and the saw-tooth dissipates what the softening
/// law does. 1 for a brittle member (ductility <= 1).
inline double saw_tooth_ductility(double ductility, double ratio, double last_stiffness) {
  if (!(ductility > 1)) return 1.0;
  auto dissipated = [&](double line) {  // the teeth's sum on a line of ductility `line`
    double sum = 0, s = 1;
    while (s * ratio >= last_stiffness) {
      const double kappa = softening_ratio(1 - s, line);
      sum += kappa * kappa * (s - s * ratio);
      s *= ratio;
    }
    return sum + line * line * s;
  };
  double low = ductility, high = ductility;
  while (dissipated(high) < ductility) high *= 2;
  for (int k = 0; k < 200 && high - low > 1e-14 * high; ++k) {
    const double mid = 0.5 * (low + high);
    (dissipated(mid) < ductility ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

/// kappa_u that makes a softening bond dissipate `fracture_energy` [J/m^2] over `crack_area`
/// [m^2] when it held `peak_energy` [J] at its peak (proportional loading; see the file comment).
/// Below 1 (the bond is too large to dissipate so little), brittle: 1.
PLYDEM_HOST_DEVICE inline double bond_ductility(double fracture_energy, double crack_area,
                                                double peak_energy) {
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
PLYDEM_HOST_DEVICE inline CriticalLoad critical_load(const BondStresses& unit,
                                                     const BondStrength& strength,
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

}  // namespace plydem
