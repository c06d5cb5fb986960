#pragma once
/// \file
/// Calibration on the relaxed unit cell: solve for the bond-family stiffnesses so that the
/// stiffness of the model *as the engine simulates it* (spins and shifts relaxed, ERRATA §3)
/// equals the target plane-stress stiffness. Gauss-Newton from a starting guess (usually the
/// corrected closed form, which is exact for the affine lattice sum).

#include <functional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/homogenizer.hpp"
#include "core/material.hpp"

namespace plydem {

/// Turns (k_n, k_s) of a family into its full stiffness (adds bending and twisting).
using FamilyStiffnessRule = std::function<FamilyStiffness(double normal, double shear)>;

struct RelaxedCalibration {
  std::vector<FamilyStiffness> families;
  Eigen::Matrix3d relaxed = Eigen::Matrix3d::Zero();
  double relative_error = 0;  ///< |relaxed - target|_F / |target|_F
  int iterations = 0;
};

/// Gauss-Newton on the 6 independent entries of the in-plane relaxed stiffness of a layer cell,
/// over the normal and shear stiffness of every family, starting from `start`. Stops at a relative
/// error below `tolerance` or after `max_iterations`; returns the best iterate (the caller checks
/// relative_error and the signs of the stiffnesses).
RelaxedCalibration calibrate_relaxed_layer(const UnitCell& cell, const Eigen::Matrix3d& target,
                                           const std::vector<FamilyStiffness>& start,
                                           const FamilyStiffnessRule& rule,
                                           double tolerance = 1e-13, int max_iterations = 50);

/// The nearest stiffness a layer cell can reach with non-negative springs: projected Gauss-Newton
/// (least squares on the 6 independent in-plane entries, relative to |target|) over k_n, k_s >= 0,
/// from `start` clipped to non-negative values. For refusing an unreachable target with the
/// stiffness that can be had instead.
RelaxedCalibration nearest_non_negative_layer(const UnitCell& cell, const Eigen::Matrix3d& target,
                                              const std::vector<FamilyStiffness>& start,
                                              const FamilyStiffnessRule& rule,
                                              int max_iterations = 100);

/// min |a x - b| over x >= 0, exactly: the least-squares solution on every support (active set)
/// is tried and the best non-negative one kept. For the handful of unknowns of a unit cell (at
/// most 16); throws plydem::Error beyond.
Eigen::VectorXd non_negative_least_squares(const Eigen::MatrixXd& a, const Eigen::VectorXd& b);

/// The six independent in-plane entries (C11, C22, C12, C16, C26, C66), the off-diagonal ones
/// times sqrt(2), so that their Euclidean norm is the Frobenius norm of the 3x3 matrix.
Eigen::Matrix<double, 6, 1> frobenius_entries(const Eigen::Matrix3d& c);

/// A ply a strategy cannot represent, in numbers: what `plydem calibrate --json` reports and what
/// UnreachableStiffness's message says.
struct Unreachable {
  std::string strategy;  ///< the strategy that refuses
  std::string material;  ///< the material's name
  double ply_angle = 0;  ///< [rad]
  std::string reason;    ///< why, in the strategy's terms (the condition the target violates)
  std::string frame;     ///< the frame of target and nearest ("fibre frame", "specimen frame")
  Eigen::Matrix3d target = Eigen::Matrix3d::Zero();   ///< plane-stress stiffness [Pa]
  Eigen::Matrix3d nearest = Eigen::Matrix3d::Zero();  ///< the nearest reachable one [Pa]
  /// The entries of `nearest` off their target by more than 0.1% ("C66", ...).
  std::vector<std::string> components;
  /// The registered strategies that calibrate the ply exactly (strategies_representing).
  std::vector<std::string> representing;
  bool looked_up = false;  ///< false inside a lookup: `representing` was not computed

  /// |nearest - target|_F / |target|_F.
  double relative_error() const;
  /// The full sentence: components, reason, nearest entries in GPa with their relative errors,
  /// the strategies that can represent the ply.
  std::string message() const;
};

/// The refusal of a ply a strategy cannot represent. Never "did not converge": a target the
/// strategy can reach is reached.
class UnreachableStiffness : public Error {
 public:
  explicit UnreachableStiffness(Unreachable refusal)
      : Error(refusal.message()), refusal_(std::move(refusal)) {}
  const Unreachable& refusal() const { return refusal_; }

 private:
  Unreachable refusal_;
};

/// Fills `refusal.components` from target and nearest and `refusal.representing` by trying every
/// other registered strategy on the ply (strategies_representing), then throws it.
[[noreturn]] void refuse_unreachable(Unreachable refusal, const Material& material,
                                     double thickness);

/// "C66 = 1.23 GPa (target 4.56)" for the entry of `reached` furthest from `target` (relative to
/// |target|), then all six entries side by side, in GPa: the words of an unreachable-target error.
std::string describe_unreachable(const Eigen::Matrix3d& reached, const Eigen::Matrix3d& target);

}  // namespace plydem
