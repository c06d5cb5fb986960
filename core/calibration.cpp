#include "core/calibration.hpp"

#include <cmath>

#include "core/error.hpp"

namespace plydem {
namespace {

Eigen::Matrix<double, 6, 1> independent_entries(const Eigen::Matrix3d& c) {
  Eigen::Matrix<double, 6, 1> v;
  v << c(0, 0), c(1, 1), c(0, 1), c(0, 2), c(1, 2), c(2, 2);
  return v;
}

}  // namespace

RelaxedCalibration calibrate_relaxed_layer(const UnitCell& cell, const Eigen::Matrix3d& target,
                                           const std::vector<FamilyStiffness>& start,
                                           const FamilyStiffnessRule& rule, double tolerance,
                                           int max_iterations) {
  const int families = static_cast<int>(start.size());
  require(families == cell.family_count, "relaxed calibration: one start value per bond family");
  const int unknowns = 2 * families;
  Eigen::VectorXd p(unknowns);
  for (int f = 0; f < families; ++f) {
    p(2 * f) = start[f].normal;
    p(2 * f + 1) = start[f].shear;
  }
  const double scale = std::max(p.cwiseAbs().maxCoeff(), 1e-300);
  auto stiffness_of = [&](const Eigen::VectorXd& q) {
    std::vector<FamilyStiffness> k(families);
    for (int f = 0; f < families; ++f) k[f] = rule(q(2 * f), q(2 * f + 1));
    return k;
  };
  auto relaxed_of = [&](const Eigen::VectorXd& q) {
    return in_plane_block(relaxed_stiffness(cell, stiffness_of(q)));
  };
  const Eigen::Matrix<double, 6, 1> goal = independent_entries(target);
  const double goal_norm = target.norm();

  RelaxedCalibration result;
  Eigen::Matrix3d current = relaxed_of(p);
  for (int iteration = 0;; ++iteration) {
    result.iterations = iteration;
    const Eigen::Matrix<double, 6, 1> residual = independent_entries(current) - goal;
    result.relative_error = (current - target).norm() / goal_norm;
    if (result.relative_error < tolerance || iteration >= max_iterations) break;
    // Central differences: the map is smooth (rational in the stiffnesses).
    Eigen::MatrixXd jacobian(6, unknowns);
    const double h = 1e-6 * scale;
    for (int k = 0; k < unknowns; ++k) {
      Eigen::VectorXd plus = p, minus = p;
      plus(k) += h;
      minus(k) -= h;
      jacobian.col(k) =
          (independent_entries(relaxed_of(plus)) - independent_entries(relaxed_of(minus))) /
          (2 * h);
    }
    const Eigen::VectorXd step = jacobian.completeOrthogonalDecomposition().solve(-residual);
    // Halve the step until the error falls (robust far from the solution).
    double lambda = 1.0;
    bool improved = false;
    for (int tries = 0; tries < 30; ++tries, lambda *= 0.5) {
      const Eigen::VectorXd trial = p + lambda * step;
      const Eigen::Matrix3d c = relaxed_of(trial);
      if ((c - target).norm() < (current - target).norm()) {
        p = trial;
        current = c;
        improved = true;
        break;
      }
    }
    if (!improved) break;
  }
  result.families = stiffness_of(p);
  result.relaxed = current;
  return result;
}

}  // namespace plydem
