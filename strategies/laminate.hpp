#pragma once
/// \file
/// Laminates (paper Sec. 3.5): plies stacked along z, each a particle layer (or layers) built by a
/// strategy at its own fibre angle with its own calibration, and adjacent plies joined by
/// interface bonds found by contact detection across the interface.
///
/// Interface bonds. Each particle on the top surface of ply k (within half a diameter of the ply's
/// highest centre) is bonded to every particle on the bottom surface of ply k+1 whose centre lies
/// within `lateral_radius` particle diameters of it in the x-y plane (0.75 by default: every point
/// of a hexagonal or square layer lies within d/sqrt(3) < 0.75 d of a site, so no surface particle
/// is left out). A bond carries a normal and a shear stiffness per unit area of interface
/// (InterfaceStiffness) times its share of the area: the particles' areas (volume over
/// ply thickness) split evenly over their interface bonds, half from each end. Interface bonds have
/// no bending or twisting stiffness.
///
/// Under a uniform membrane strain an interface bond is loaded only through its lateral offset
/// (small against the ply spacing), but plies whose lattices are turned against each other offset
/// every bond differently, and the bulk of the laminate is stiffer than CLT's A/h by what they
/// hold: measured in the interior of 3 x 0.83 mm coupons (experiments/protocols/stiffness.hpp,
/// tests/test_laminate.cpp), the largest entry of A/h is off by 1.0%, 0.73% and 1.27% for [0/90]s,
/// [45/-45]s and [0/45/-45/90]s with the default interface below, 0.48%, 0.03% and 0.60% with the
/// paper's 1e14 / 1e13 N/m^3.

#include <string>
#include <vector>

#include "strategies/specimen.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// A layup string, bottom ply first: "[0/90/0]", "[0/30/45]s" (symmetric), "[45/-45]s",
/// "[0/90]2s" (the group twice, then mirrored), "[0/±45/90]s" ("±45" and "+-45" stand for 45/-45),
/// "[0/90_2]s" (a count after '_' repeats the ply: 0/90/90/90/90/0), "[0_16]".
/// Returns the ply angles in radians. Throws plydem::Error naming the malformed part.
std::vector<double> parse_layup(const std::string& layup);

/// The layup written back, e.g. "[0/30/45/45/30/0]" (degrees).
std::string format_layup(const std::vector<double>& ply_angles);

/// Stiffness of the interface bonds per unit area of interface [N/m^3]. 0 = the default, ten
/// times the ply's own through-thickness stiffness: 10 E2 / t (normal) and 10 G12 / t (shear).
/// The interface has two opposite errors against classical lamination theory (perfect bonding):
///  - too soft: the plies of a narrow coupon slide against each other over a shear-lag length
///    sqrt(E2 t / K_s). With the paper's 1e14 / 1e13 (about E2/t and G12/t; 0.57 mm for E-glass,
///    t = 0.2 mm) a [0/90/0] coupon 0.83 mm wide measures nu_xy 0.203 against CLT's 0.173;
///  - too stiff: an interface bond between plies whose lattices do not line up has a lateral
///    offset, which a membrane strain stretches: at 100 E2/t, 100 G12/t the same coupon is 5%
///    too stiff in Ex and 15% in Gxy.
/// Ten times is the compromise measured on that coupon (3 mm long): Ex +0.6%, Ey +0.9%,
/// nu_xy +0.0125, Gxy +1.5% against CLT.
///
/// Transverse shear in the plies (`transverse_shear`). A ply of one particle layer has no
/// transverse shear stiffness of its own but its in-plane bonds' shear springs, which are
/// calibrated for the membrane (square, E-glass: about 0.4 of G t / 3), and particle spin relieves
/// the interface bonds' shear: where load must pass between plies around a crack, the laminate is
/// too soft in interlaminar shear. A [0/90_2]s coupon with 1 and 3 transverse cracks loses 5% and
/// 7% more stiffness than CalculiX of the same cracks (tests/test_cracked_laminate.cpp). With
/// `transverse_shear`, every ply's in-plane bonds carry the ply's transverse shear stiffness
/// t diag(G13, G23) (in ply axes; G13 = G12) through their out-of-plane shear (Bonds::
/// out_of_plane_shear_ratio), as in a layerwise plate theory, and the interface bonds are the
/// continuity between the plies' faces, a stiff penalty: the shear default is then 100 G12 / t
/// (the normal one stays 10 E2 / t). Penalty and layer in series leave 1% of the shear compliance
/// too little. The fit: k_z of bond b = w_b (L^T Q L) / |L|^4 (L the bond vector, w_b its
/// boundary-completion weight, k_s over its family's bulk k_s) with the symmetric 2 x 2 Q solved so
/// that sum_b k_z L L^T = A t G_t over the ply (A its area): the energy of a uniform transverse
/// shear (w = gamma . x) is the ply's. Only single-layer plies (hex2d, square: every in-ply bond in
/// the plane) can take it; for other strategies build_laminate refuses. A stiff penalty over
/// lattices that do not line up (hex2d at different angles) stiffens the membrane (above), so
/// this serves plies whose lattices coincide (square at 0° and 90°). The explicit kernels refuse
/// such a model (core/parallel_bond.hpp).
struct InterfaceStiffness {
  double normal = 0;              ///< [N/m^3]; 0 = 10 E2 / t (above)
  double shear = 0;               ///< [N/m^3]; 0 = 10 G12 / t, 100 G12 / t with transverse_shear
  double lateral_radius = 0.75;   ///< in particle diameters, see the file comment
  bool transverse_shear = false;  ///< the plies carry G13, G23 (above)
  /// Throws plydem::Error naming a non-finite or negative stiffness or a non-positive radius.
  void validate() const;
  /// The stiffnesses with 0 replaced by the default values for `material` at ply thickness
  /// `thickness`.
  InterfaceStiffness resolved(const Material& material, double thickness) const;
};

struct LaminateSpec {
  /// Material, size, particle diameter and the thickness of ONE ply (its ply_angle is ignored).
  CouponSpec coupon;
  std::vector<double> ply_angles;  ///< bottom to top [rad]
  InterfaceStiffness interface;
};

/// The plies as CLT sees them (material, angle, thickness), bottom to top.
std::vector<Ply> laminate_plies(const LaminateSpec& spec);

/// Builds every ply with `strategy` (ply k shifted by k * ply thickness along z, particles'
/// `ply` = k), then the interface bonds (kind BondKind::kInterface, family = k for the interface
/// above ply k). The model's thickness is the laminate's. Throws plydem::Error for an empty layup,
/// a bad interface stiffness, or an interface with no bonds. The specimen's ply_calibrations are
/// the plies', bottom to top; `builder` calibrates and builds each distinct ply once (and
/// remembers both for later builds: SpecimenBuilder::ply).
Specimen build_laminate(SpecimenBuilder& builder, const LaminateSpec& spec);
/// The same with a builder of its own.
Specimen build_laminate(const Strategy& strategy, const LaminateSpec& spec);

}  // namespace plydem
