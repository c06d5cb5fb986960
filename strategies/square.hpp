#pragma once
/// \file
/// The paper's square packing (Secs. 3.3/3.4, Fig. 14, eq. (33)): one square layer per ply in the
/// x-y plane, eight neighbours, plane stress (packings/square_layer.hpp). Two strategies:
///  - `square`: the lattice is turned with the ply so that its x axis lies along the fibre, or at
///    45 deg from it (for a 45 deg ply, so that the lattice lies along the coupon; by option; or
///    when the other cannot represent the ply). In its own frame the ply
///    is then orthotropic, or has C16 = C26 at 45 deg, which is all a square lattice can have.
///    Springs start from eq. (33), corrected reading (ERRATA §2: one shared k_s, the diagonals
///    split by C16), which is exact for the affine lattice sum (or, where eq. (33) has a negative
///    spring, from the nearest exact solution with the axial and diagonal shear springs apart),
///    and are re-solved on the relaxed unit cell (ERRATA §3) so that the model with freely
///    spinning particles has the target.
///  - `square-paper`: eq. (33) exactly as printed (C16 and C26 dropped) on a lattice fixed along
///    x: the paper's own 45 deg model, kept to reproduce its formula for comparison. It does not
///    reach the target off-axis; its Calibration reports the true relaxed stiffness and error.
///
/// Lattice sum of the square layer (each bond once, cell area l^2, V = l^2 delta; families x, y
/// at l and the diagonals d+ (+45 deg), d- (135 deg) at l sqrt(2)), in its own frame:
///   C11 delta = k_nx + (k_n+ + k_n-)/2 + (k_s+ + k_s-)/2,  C22 delta: k_ny in place of k_nx,
///   C12 delta = (k_n+ + k_n-)/2 - (k_s+ + k_s-)/2,          C16 = C26 = (k_n+ - k_n-)/(2 delta),
///   C66 delta = (k_n+ + k_n-)/2 + (k_sx + k_sy)/4.
/// Spinning particles relax the shear springs unless k_sx = k_sy and k_s+ = k_s- (ERRATA §3). With
/// those pairs equal (k_sa, k_sd) nothing relaxes and the sum is exact along a one-parameter family
/// (square_springs_non_negative); eq. (33) is its member with k_sa = k_sd. Unequal pairs add
/// nothing reachable for a stiffness with C16 = C26: the relaxed sum has the same form with
/// effective k_sd' = (k_s+ + k_s-)/2 - (k_s+ - k_s-)^2/K >= 0 and k_sa' = (k_sx + k_sy)/2 -
/// (k_sx - k_sy)^2/(2K) >= 0, K = k_sx + k_sy + 2 k_s+ + 2 k_s-. So the family is complete, and
/// C66 >= C12 is necessary; C66 - C12 is invariant under rotation, so a square layer needs
/// G12 >= Q12 = nu12 E2 / (1 - nu12 nu21) whatever its orientation.

#include <array>
#include <optional>

#include "strategies/boundary_cells.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// eq. (33), corrected reading (ERRATA §2: "k_n11" is k_n1; the diagonals split by C16): the
/// springs of families x, y, +45, 135 deg (packings/square_layer.hpp order) of a square layer whose
/// affine lattice sum equals the plane-stress stiffness `c` (in the lattice frame) for a layer of
/// thickness `thickness`:
///   k_nx = (3 C11 + C12 - 4 C66) delta / 3,   k_ny = (C12 + 3 C22 - 4 C66) delta / 3,
///   k_n+- = (C12 + 2 C66) delta / 3 +- C16 delta,   k_s = 2 (C66 - C12) delta / 3 (all families).
/// Throws plydem::Error if C16 and C26 differ (no square lattice has them different in its frame).
std::array<FamilyStiffness, 4> square_springs_eq33(const Eigen::Matrix3d& c, double thickness);

/// The exact springs with non-negative stiffness nearest to eq. (33), for `c` with C16 = C26 (in
/// the lattice frame): eq. (33) itself when that has no negative spring, else the member of the
/// family (per unit thickness, k_sd = diagonal shear of both diagonals, k_sa = axial shear of both
/// axes)
///   k_n+- = (C12 +- C16) delta + k_sd,  k_sa = 2 (C66 - C12) delta - 2 k_sd,
///   k_nx = (C11 - C12) delta - 2 k_sd,  k_ny = (C22 - C12) delta - 2 k_sd
/// whose k_sd is nearest eq. (33)'s 2 (C66 - C12) delta / 3. No member is non-negative (nullopt)
/// unless C66 >= C12, C11 >= C12, C22 >= C12, C66 >= |C16|, C11 + C12 >= 2 |C16| and
/// C22 + C12 >= 2 |C16|.
std::optional<std::array<FamilyStiffness, 4>> square_springs_non_negative(const Eigen::Matrix3d& c,
                                                                          double thickness);

/// eq. (33) exactly as printed: both diagonals get k_n2 = (C12 + 2 C66) delta / 3; C16 and C26
/// are dropped. For the 45 deg E-glass ply this gives the paper's Ex = 17.66 GPa (CLT: 16.461).
std::array<FamilyStiffness, 4> square_springs_eq33_as_printed(const Eigen::Matrix3d& c,
                                                              double thickness);

class SquareStrategy : public Strategy {
 public:
  /// `fibre_offset`: angle of the fibre from the lattice x axis [deg], 0 or 45. -1 (default)
  /// chooses: 45 when that puts the lattice along the specimen axes (ply angles of 45 deg plus a
  /// multiple of 90), else 0; the other one when the first cannot represent the ply.
  /// `edge_equilibrium` (strategies/boundary_cells.hpp): 1 (default) or 0.
  std::vector<StrategyOption> options() const override;
  void set_option(const std::string& name, double value) override;
  std::string description() const override;
  /// Throws plydem::Error naming the conditions of square_springs_non_negative the ply violates
  /// and the nearest stiffness a square layer with non-negative springs reaches.
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override;
  Model assemble(const CouponSpec& coupon, const Calibration& calibration) const override;
  BoundaryCompletion boundary_completion() const override;
  /// The one-particle square cell of unit spacing turned by calibration.lattice_angle.
  std::optional<UnitCell> unit_cell(const Calibration& calibration,
                                    double thickness) const override;

 private:
  double fibre_offset_deg_ = -1;
  EdgeTreatment edge_treatment_ = EdgeTreatment::kEquilibrium;
};

class SquarePaperStrategy : public Strategy {
 public:
  std::string description() const override;
  /// The as-printed eq. (33) on a lattice along x; `relaxed` and `relaxed_error` are the true
  /// stiffness of that lattice with spinning particles. Throws plydem::Error if a printed spring
  /// is negative (the engine cannot simulate it).
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override;
  Model assemble(const CouponSpec& coupon, const Calibration& calibration) const override;
  BoundaryCompletion boundary_completion() const override;
  /// As SquareStrategy's.
  std::optional<UnitCell> unit_cell(const Calibration& calibration,
                                    double thickness) const override;
};

}  // namespace plydem
