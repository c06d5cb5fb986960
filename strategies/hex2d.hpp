#pragma once
/// \file
/// Hex2D, the paper's "extended 2D hexagonal" strategy (Sec. 3.3): one hexagonal layer per ply in
/// the x-y plane, six neighbours, plane stress. The lattice is turned with the ply so that bond
/// family 1 lies along the fibre (ERRATA §2: this keeps shear springs non-negative at any angle).
/// Bond stiffnesses start from the corrected eq. (27), which is exact for the affine lattice sum,
/// and are then re-solved on the relaxed unit cell so that the model with freely spinning particles
/// has the target stiffness (ERRATA §3).

#include <array>

#include "strategies/boundary_cells.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// Corrected eq. (27): the six springs (k_n, k_s of families 1..3 at 0, +60, +120 deg from the
/// lattice x axis) of a hexagonal layer whose affine lattice sum equals the plane-stress
/// stiffness `c` (expressed in the lattice frame) for a layer of thickness `thickness`.
std::array<FamilyStiffness, 3> hexagonal_springs_eq27(const Eigen::Matrix3d& c, double thickness);

/// eq. (27) exactly as printed, with C11 + C22 in k_n2 and k_n3 (ERRATA §2): kept so that
/// experiments can show what the printed formula does.
std::array<FamilyStiffness, 3> hexagonal_springs_eq27_as_printed(const Eigen::Matrix3d& c,
                                                                 double thickness);

/// The springs of a hexagonal layer whose particles spin freely (as the engine simulates them)
/// with the plane-stress stiffness `c` (lattice frame), in closed form. With spins relaxed the
/// shear springs' energy is sum_f k_f (a_f - a)^2, a_f the tangential strain of family f and a
/// their k-weighted mean (the common spin). The three a_f sum to zero, so this is the energy of
/// the triangle of families with edge weights w_jk = k_j k_k / K (K = k_1 + k_2 + k_3), which
/// equals the affine energy of shear springs D_i = 2 (w_ij + w_ik) - w_jk. Hence from eq. (27)'s
/// shear springs D: w_jk = (2/3 sum D - D_i) / 3, and k_i = sqrt(K w_ij w_ik / w_jk) with
/// sqrt(K) = sum_i sqrt(w_ij w_ik / w_jk). The normal springs are eq. (27)'s (spins do not load
/// them). Positive springs exist if and only if every k_n and every w is positive; in the fibre
/// frame (C16 = C26 = 0) w_1 > 0 reads C66 < C22 - 2 C12, which carbon/epoxy plies break
/// (T300/914C: C66 = 5.5 GPa, C22 - 2 C12 = 4.87 GPa).
struct HexagonalRelaxedSprings {
  std::array<double, 3> normal{};  ///< k_n of families 1..3 [N/m]
  std::array<double, 3> weight{};  ///< w_i: the shear weight of the two families other than i
  std::array<double, 3> shear{};   ///< k_s of families 1..3 [N/m], where reachable
  bool reachable = false;          ///< every k_n and every w positive
};
HexagonalRelaxedSprings hexagonal_springs_relaxed(const Eigen::Matrix3d& c, double thickness);

/// The conditions hexagonal_springs_relaxed() needs, in the fibre frame, with the ones `c` (fibre
/// frame) violates and their numbers in GPa: the reason of hex2d's refusal.
std::string hexagonal_relaxed_limits(const Eigen::Matrix3d& c);

class Hex2dStrategy : public Strategy {
 public:
  /// `edge_equilibrium` (strategies/boundary_cells.hpp): 1 (default) or 0.
  std::vector<StrategyOption> options() const override;
  void set_option(const std::string& name, double value) override;
  std::string description() const override;
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override;
  Model assemble(const CouponSpec& coupon, const Calibration& calibration) const override;
  BoundaryCompletion boundary_completion() const override;
  /// The one-particle hexagonal cell of unit spacing turned by calibration.lattice_angle.
  std::optional<UnitCell> unit_cell(const Calibration& calibration,
                                    double thickness) const override;

 protected:
  EdgeTreatment edge_treatment_ = EdgeTreatment::kEquilibrium;
};

/// `hex2d-paper`: the paper's Hex2D as printed: the lattice fixed with family 1 along x
/// (Fig. 9), eq. (27) as printed applied to the ply's Q-bar, no relaxation. Its calibration
/// reports the stiffness the engine will really simulate and its error; negative springs (any
/// ply whose fibre is not along a bond family, the paper's 30 and 90 deg remark) are refused,
/// never run.
class Hex2dPaperStrategy : public Hex2dStrategy {
 public:
  /// Edges by the count completion unless the option says otherwise (the paper had neither).
  Hex2dPaperStrategy() { edge_treatment_ = EdgeTreatment::kCellCompletion; }
  std::string description() const override;
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override;
};

}  // namespace plydem
