#pragma once
/// \file
/// Strength calibration as simulated. Under a uniform in-plane stress the relaxed lattice's bond
/// forces and moments are linear in the stress, and known exactly from the unit cell the strategy
/// calibrated its stiffnesses on (core/homogenizer.hpp, relaxed: spins and sublattice shifts at
/// minimum energy). For each bond family the calibration solves for its tensile strength sigma_c
/// and cohesion c (core/bond_failure.hpp) so that the model without scatter first breaks exactly at
/// XT (sigma1), YT (sigma2) and S12 (tau12, either sign): the least strengths that let no family
/// fail earlier than a target, and the refusal (Error) when one of the three is then not met by
/// any family, since every other choice only makes the model stronger there.
/// XC and YC are reported (the model's first failure under sigma1 = -1, sigma2 = -1) beside the
/// targets, never solved for: a bond criterion of tension and shear represents compression only
/// through its shear mode.
///
/// Fracture energy (softening): a bond's share of crack area is A_crack = 1 / sum_g (rho_g L_g
/// |n_g . n_b|) for a crack normal to it (rho_g bonds of family g per unit volume, L_g their
/// length), so that a straight crack normal to a bond direction cuts bonds whose shares add up to
/// its area; families within 15 deg of the fibre get G_fibre, the others G_matrix; ductility from
/// bond_ductility with the family's energy at its calibrated first failure.
///
/// Rules the calibration follows (measured figures: tests/test_strength_calibration.cpp):
///  - A family's strength in a mode is its largest demand over its cell bonds at +XT, +YT, +S12 and
///    -S12 (the demand of shear: tau + (F_n / A) tan(phi)). A target is met when the model's first
///    failure under it lies within 1e-9 of it; S12 must be met under both signs.
///  - A mode that none of the four loads reaches keeps +inf. No uniaxial tension test of the ply at
///    any angle can load it: its stress is a positively homogeneous convex function of the ply
///    stress (a linear part plus norms), <= 0 at the four loads and so on their cone, which holds
///    every such state (sigma1 = cos^2, sigma2 = sin^2, tau12 = -sin cos, times sigma_x >= 0).
///    Non-uniform fields (near grips, notches) may load it; it does not break there.
///  - The refusal names each target missed, the model's first failure there and the family that
///    breaks first, the nearest consistent strengths (the model's own first failures, and for
///    each target missed: that target kept with the others lowered as little as needed), and the
///    registered strategies that meet all three for this material and angle.
///  - Friction: PFC's shear capacity c - sigma tan(phi) falls in tension, so a bond pulled to a
///    large sigma by XT needs a cohesion of sigma tan(phi): a friction angle of a few degrees
///    already takes S12 out of reach of a bond family that XT stretches.
///  - A coupon, as built and solved by the engine, first breaks at the targets when it carries the
///    relaxed bulk's uniform state: with grips that hold it (displacement and spin) and free long
///    edges along lattice lines (square at 0 and 90 deg, hex2d at 0 deg), or an affine frame. Grips
///    that move rigidly along x (the tension test's) restrain the ply's Poisson contraction and
///    break it first next to them; hex2d's zig-zag edges at 90 deg, where boundary completion is
///    not exact, first break about 14% below YT.

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/failure_criteria.hpp"
#include "core/material.hpp"
#include "strategies/specimen.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// Strengths and fracture energies of a laminate's interface bonds (0 = not given: the interface
/// does not break). Interface bonds fail by the mixed-mode law of core/bond_failure.hpp: onset
/// where (<t_n> / normal)^2 + (t_s / shear)^2 = 1, then linear softening that dissipates the
/// Benzeggagh-Kenane energy G_c(B) = GIc + (GIIc - GIc) B^bk_exponent at the mode mix B.
struct InterfaceStrength {
  double normal = 0;  ///< tensile strength across the interface [Pa]
  double shear = 0;   ///< shear strength (cohesion) [Pa]
  double GIc = 0;     ///< mode I fracture energy [J/m^2]; 0 = brittle (no softening)
  /// Mode II fracture energy [J/m^2]; 0 with GIc given = GIc (a mode-independent G_c). Given
  /// without GIc is refused: the law scales from GIc.
  double GIIc = 0;
  /// The Benzeggagh-Kenane exponent eta (> 0). Default 2.284: the value Camanho, Davila & de Moura
  /// (J. Compos. Mater. 37 (2003) 1415) fitted to Reeder's mixed-mode bending tests of AS4/PEEK,
  /// the one most cohesive-zone studies use when the interface's own is not measured; it is not a
  /// measurement of E-glass/MY750 (measure it by mixed-mode bending, ASTM D6671).
  double bk_exponent = 2.284;
  bool given() const { return normal > 0 || shear > 0; }
  /// GIIc, or GIc where GIIc is not given (0).
  double mode_II_energy() const { return GIIc > 0 ? GIIc : GIc; }
  /// Throws plydem::Error naming a negative or non-finite entry, only one of the two strengths,
  /// GIIc without GIc, or a bk_exponent that is not finite and > 0.
  void validate() const;
};

struct StrengthOptions {
  double friction_coefficient = 0;  ///< tan(phi) of every in-ply bond
  bool softening = false;           ///< linear softening from G_fibre, G_matrix (else brittle)
  /// The particle diameter the family strengths are stated for [m]; 0 = CouponSpec's default.
  /// At a fixed calibration a bond's section stresses under a given strain scale as 1/R (forces
  /// as R, the section as R^2), so assign_bond_strengths rescales each bond to its own radius:
  /// the model's strengths do not depend on this choice, only the reported numbers do.
  double particle_diameter = 0;
  /// Throws plydem::Error naming a negative or non-finite entry.
  void validate() const;
};

/// One bond family's strength, for the bonds and for reports.
struct FamilyStrength {
  std::string label;                                          ///< as the family's FamilyCalibration
  double tensile = std::numeric_limits<double>::infinity();   ///< sigma_c [Pa]
  double cohesion = std::numeric_limits<double>::infinity();  ///< c [Pa]
  double friction = 0;                                        ///< tan(phi)
  double radius = 0;                                          ///< R of the section [m]
  double crack_area = 0;                                      ///< A_crack [m^2]
  double ductility = 1;                                       ///< kappa_u (1 = brittle)
  double fracture_energy = 0;  ///< G of the family (G_fibre or G_matrix) [J/m^2]; 0 = brittle
  /// The bond's energy at its calibrated first failure [J] (0 if no target loads it), from which
  /// ductility = bond_ductility(fracture_energy, crack_area, peak_energy).
  double peak_energy = 0;
  /// Which target set each strength ("XT", "YT", "S12"; "" if no target loads the mode).
  std::string tensile_set_by, cohesion_set_by;
};

/// A target strength beside the model's first failure under the same loading.
struct StrengthTarget {
  std::string name;   ///< "XT", "YT", "S12", "XC", "YC"
  double target = 0;  ///< [Pa]; 0 if the material does not give it
  double model = std::numeric_limits<double>::infinity();  ///< first-failure stress [Pa]
  bool calibrated = false;  ///< solved for (XT, YT, S12), not only reported (XC, YC)
  std::string family;       ///< label of the family that breaks first
  std::string mode;         ///< "tension" or "shear"
};

class StrengthCalibration {
 public:
  std::vector<FamilyStrength> families;  ///< index = Bonds::family of the ply's in-ply bonds
  std::vector<StrengthTarget> targets;   ///< XT, YT, S12, XC, YC in that order
  double ply_angle = 0;                  ///< [rad]
  /// The factor by which the uniform ply stress `stress` must be scaled for the first bond of the
  /// relaxed bulk to fail (+inf if never): the model's first-failure surface, as the engine
  /// simulates it, for the envelopes (sigma1-sigma2, sigma2-tau12).
  double first_failure_factor(const PlyStress& stress) const;
  /// The same per bond family (index = Bonds::family): the factor at which the family's most
  /// loaded cell bond fails (+inf for a family the stress does not load).
  std::vector<double> family_failure_factors(const PlyStress& stress) const;

  /// Per cell bond (one entry each; a cell may hold several bonds of a family) and unit ply stress
  /// component (sigma1, sigma2, tau12 = 1 Pa, columns), the bond's resultants in the relaxed bulk,
  /// for first_failure_factor: rows F_n [N], F_s (3) [N], M_b (3) [N m], M_t [N m], linear in the
  /// stress, for a bond of its family's section radius. Filled by calibrate_strengths.
  struct UnitResponse {
    int family = 0;
    Eigen::Matrix<double, 8, 3> resultants = Eigen::Matrix<double, 8, 3>::Zero();
  };
  std::vector<UnitResponse> responses;
};

/// Calibrates the strengths of a ply of `material` (its strength block: XT, YT, S12 required) at
/// `ply_angle` built by `strategy` with stiffness `calibration` at `thickness`. Throws
/// plydem::Error naming the cause: strengths missing (require_strengths), a strategy without a unit
/// cell (lattice's random packing: no uniform bond state), or a target that the strategy cannot
/// meet: which, the model's nearest first-failure stresses, and which registered strategies meet
/// all three at this angle.
StrengthCalibration calibrate_strengths(const Strategy& strategy, const Calibration& calibration,
                                        const Material& material, double ply_angle,
                                        double thickness, const StrengthOptions& options = {});

/// The strength fields of interface bond `b` (BondKind::kInterface, its strength_radius set) that
/// stands for `area` [m^2] of interface, for the mixed-mode law (core/bond_failure.hpp): section
/// strengths normal area / (pi R^2) and shear area / (pi R^2) (a strength not given (0) is +inf),
/// so that U = sqrt((<F_n> / (normal area))^2 + (|F_s| / (shear area))^2); no friction;
/// mixed_mode_exponent = bk_exponent; ductility kappa_I = GIc area / E_I with E_I =
/// (normal area)^2 / (2 k_n), the energy at onset in pure mode I (at least 1); fracture energy
/// ratio mode_II_energy() / GIc; peak energy ratio E_II / E_I with E_II = (shear area)^2 / (2 k_s).
/// Without GIc the bond is brittle (kappa_I = ratios = 1). Throws plydem::Error for a bond that is
/// not an interface bond, a non-positive area or radius.
void set_interface_bond_strength(Bonds& bonds, int b, double area,
                                 const InterfaceStrength& interface);

/// Writes the strength fields of every bond of a built specimen: in-ply bonds of ply p from
/// plies[p] by their Bonds::family, scaled by their stiffness weight (k_n of the bond over its
/// family's bulk k_n, as boundary cells scale the stiffness: an edge bond is as utilised as a bulk
/// one under the same strain), times a Weibull factor (-ln U)^(1/m) / Gamma(1 + 1/m) per bond when
/// `weibull_modulus` m > 0 (random stream from `seed`: the same seed, the same strengths);
/// interface bonds from `interface` (unbreakable when not given). Throws plydem::Error if the
/// plies do not match the specimen.
///  - Section radius: the smaller particle radius of the bond. Strengths are rescaled from the
///    family's radius to the bond's as 1/R (StrengthOptions::particle_diameter).
///  - Scatter: draw k of std::mt19937_64(seed) belongs to bond row k (every row draws, interface
///    bonds too, which do not use it), U = (draw / 2^11 + 1/2) / 2^53; tensile strength and
///    cohesion of a bond share its factor; its ductility keeps G A_crack / E_peak with the peak
///    energy of its own strength.
///  - Interface bonds: a bond of interface area a (its particles' areas split over their interface
///    bonds, as strategies/laminate.hpp gives it k_n = K_n a) breaks when F_n / a reaches `normal`
///    or |F_s| / a reaches `shear`: section strengths normal a / (pi R^2), shear a / (pi R^2), no
///    friction; no scatter; the mixed-mode law with GIc, GIIc and bk_exponent
///    (set_interface_bond_strength).
///  - `scattered_plies`: the plies whose bonds get the scatter (index = ply; empty = every ply);
///    the others keep their calibrated strengths (every row still draws).
///  - `per_crack_site`: the scatter is drawn per crack site instead of per bond: a ply's flaws
///    run along its fibres, so every bond that crosses the same band between two particle rows
///    along the fibre (its midpoint's distance across the fibre from the ply's lowest particle,
///    in half diameters, rounded: the gaps between rows are the odd bands) shares one factor,
///    (-ln U)^(1/m) / Gamma(1 + 1/m) with U from a hash of (seed, ply, band). A transverse crack
///    then runs through its whole band, as a cross-ply's 90° cracks do, instead of damage spread
///    over the weakest single bonds. Exact for rows along the fibre (square at 0° and 90°); for
///    other lattices the bands are strips half a diameter wide along the fibre.
///  - The specimen must be intact (no damaged or broken bond).
void assign_bond_strengths(Specimen& specimen, const std::vector<StrengthCalibration>& plies,
                           const InterfaceStrength& interface = {}, double weibull_modulus = 0,
                           std::uint64_t seed = 1, const std::vector<bool>& scattered_plies = {},
                           bool per_crack_site = false);

/// The Weibull factor (modulus m > 0, mean 1) of crack band `band` of ply `ply`, as
/// assign_bond_strengths' per_crack_site scatter draws it: (-ln U)^(1/m) / Gamma(1 + 1/m) with U
/// from a hash of (seed, ply, band); the same band, the same factor, in any order.
double crack_band_factor(double weibull_modulus, std::uint64_t seed, int ply, long band);

}  // namespace plydem
