#pragma once
/// \file
/// Calibration on the relaxed unit cell: solve for the bond-family stiffnesses so that the
/// stiffness of the model *as the engine simulates it* (spins and shifts relaxed, ERRATA §3)
/// equals the target plane-stress stiffness. Gauss-Newton from a starting guess (usually the
/// corrected closed form, which is exact for the affine lattice sum).

#include <functional>
#include <string>
#include <vector>

#include "core/homogenizer.hpp"

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

/// "C66 = 1.23 GPa (target 4.56)" for the entry of `reached` furthest from `target` (relative to
/// |target|), then all six entries side by side, in GPa: the words of an unreachable-target error.
std::string describe_unreachable(const Eigen::Matrix3d& reached, const Eigen::Matrix3d& target);

}  // namespace plydem
