#include "strategies/calibration.hpp"

#include <fmt/format.h>

#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/units.hpp"
#include "strategies/registry.hpp"

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

RelaxedCalibration nearest_non_negative_layer(const UnitCell& cell, const Eigen::Matrix3d& target,
                                              const std::vector<FamilyStiffness>& start,
                                              const FamilyStiffnessRule& rule, int max_iterations) {
  const int families = static_cast<int>(start.size());
  require(families == cell.family_count, "nearest stiffness: one start value per bond family");
  const int unknowns = 2 * families;
  Eigen::VectorXd p(unknowns);
  for (int f = 0; f < families; ++f) {
    p(2 * f) = std::max(start[f].normal, 0.0);
    p(2 * f + 1) = std::max(start[f].shear, 0.0);
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
  Eigen::Matrix3d current = relaxed_of(p);
  RelaxedCalibration result;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    result.iterations = iteration + 1;
    const Eigen::Matrix<double, 6, 1> residual = independent_entries(current) - goal;
    Eigen::MatrixXd jacobian(6, unknowns);
    const double h = 1e-6 * scale;
    for (int k = 0; k < unknowns; ++k) {
      // One-sided at the bound, so that no spring is evaluated negative.
      Eigen::VectorXd plus = p, minus = p;
      plus(k) += h;
      minus(k) = std::max(minus(k) - h, 0.0);
      jacobian.col(k) =
          (independent_entries(relaxed_of(plus)) - independent_entries(relaxed_of(minus))) /
          (plus(k) - minus(k));
    }
    // Springs at zero whose gradient pushes them below zero stay there (the active set).
    const Eigen::VectorXd gradient = jacobian.transpose() * residual;
    std::vector<int> free;
    for (int k = 0; k < unknowns; ++k) {
      if (p(k) > 0 || gradient(k) < 0) free.push_back(k);
    }
    if (free.empty()) break;
    Eigen::MatrixXd reduced(6, static_cast<int>(free.size()));
    for (int c = 0; c < static_cast<int>(free.size()); ++c) reduced.col(c) = jacobian.col(free[c]);
    const Eigen::VectorXd step = reduced.completeOrthogonalDecomposition().solve(-residual);
    double lambda = 1.0;
    bool improved = false;
    for (int tries = 0; tries < 30 && !improved; ++tries, lambda *= 0.5) {
      Eigen::VectorXd trial = p;
      for (int c = 0; c < static_cast<int>(free.size()); ++c) {
        // Bounded above too: a spring that no longer changes the relaxed stiffness (a shear
        // spring whose work the spins take over) must not drift without limit.
        trial(free[c]) = std::clamp(p(free[c]) + lambda * step(c), 0.0, 100 * scale);
      }
      const Eigen::Matrix3d c = relaxed_of(trial);
      if ((c - target).norm() < (current - target).norm() * (1 - 1e-12)) {
        p = trial;
        current = c;
        improved = true;
      }
    }
    if (!improved) break;
  }
  result.families = stiffness_of(p);
  result.relaxed = current;
  result.relative_error = (current - target).norm() / target.norm();
  return result;
}

Eigen::VectorXd non_negative_least_squares(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  const int n = static_cast<int>(a.cols());
  require(n <= 16,
          fmt::format("non-negative least squares by active sets: {} unknowns (at most 16)", n));
  Eigen::VectorXd best = Eigen::VectorXd::Zero(n);
  double best_residual = b.norm();
  for (unsigned support = 1; support < (1u << n); ++support) {
    std::vector<int> free;
    for (int k = 0; k < n; ++k) {
      if (support & (1u << k)) free.push_back(k);
    }
    Eigen::MatrixXd reduced(a.rows(), static_cast<int>(free.size()));
    for (int c = 0; c < static_cast<int>(free.size()); ++c) reduced.col(c) = a.col(free[c]);
    const Eigen::VectorXd x = reduced.completeOrthogonalDecomposition().solve(b);
    if ((x.array() < 0).any()) continue;
    const double residual = (reduced * x - b).norm();
    if (residual < best_residual) {
      best_residual = residual;
      best.setZero();
      for (int c = 0; c < static_cast<int>(free.size()); ++c) best(free[c]) = x(c);
    }
  }
  return best;
}

Eigen::Matrix<double, 6, 1> frobenius_entries(const Eigen::Matrix3d& c) {
  const double r2 = std::numbers::sqrt2;
  Eigen::Matrix<double, 6, 1> v;
  v << c(0, 0), c(1, 1), r2 * c(0, 1), r2 * c(0, 2), r2 * c(1, 2), c(2, 2);
  return v;
}

namespace {

constexpr int kEntryRows[6] = {0, 1, 0, 0, 1, 2}, kEntryCols[6] = {0, 1, 1, 2, 2, 2};
constexpr const char* kEntryNames[6] = {"C11", "C22", "C12", "C16", "C26", "C66"};

// An entry is missed when it is off by more than 0.1% of itself (of 1e-3 |target| if it is 0).
bool entry_missed(const Eigen::Matrix3d& reached, const Eigen::Matrix3d& target, int e) {
  const double t = target(kEntryRows[e], kEntryCols[e]);
  const double miss = std::abs(reached(kEntryRows[e], kEntryCols[e]) - t);
  return miss > 1e-3 * std::max(std::abs(t), 1e-3 * target.norm());
}

}  // namespace

double Unreachable::relative_error() const {
  return (nearest - target).norm() / target.norm();
}

std::string Unreachable::message() const {
  std::string entries;
  for (int e = 0; e < 6; ++e) {
    const double t = target(kEntryRows[e], kEntryCols[e]);
    const double r = nearest(kEntryRows[e], kEntryCols[e]);
    // + 0.0 turns -0 into 0 for printing; an entry whose target is 0 gets its miss in GPa.
    const std::string error =
        std::abs(t) > 1e-9 * target.norm()
            ? fmt::format("{:+.2f}%", 100 * (r - t) / std::abs(t))
            : fmt::format("target 0, off by {:.2g} GPa", std::abs(r - t) * kGPaPerPa);
    entries += fmt::format("{}{} {:.4g} ({})", e ? ", " : "", kEntryNames[e], r * kGPaPerPa + 0.0,
                           std::abs(t) > 1e-9 * target.norm()
                               ? fmt::format("target {:.4g}, {}", t * kGPaPerPa, error)
                               : error);
  }
  std::string strategies;
  if (!looked_up) {
    strategies = "(Other strategies not tried.)";
  } else if (representing.empty()) {
    strategies = "No registered strategy represents this ply exactly.";
  } else {
    strategies = fmt::format("Strategies that represent this ply exactly: {}.",
                             fmt::join(representing, ", "));
  }
  return fmt::format(
      "{} cannot represent material '{}' at {:.4g} deg: {} cannot be reached ({}). Nearest "
      "reachable stiffness in GPa ({}): {}; relative error {:.3g} (Frobenius). {}",
      strategy, material, ply_angle * 180 / std::numbers::pi,
      components.empty() ? std::string("the target")
                         : fmt::format("{}", fmt::join(components, ", ")),
      reason, frame, entries, relative_error(), strategies);
}

void refuse_unreachable(Unreachable refusal, const Material& material, double thickness) {
  refusal.components.clear();
  for (int e = 0; e < 6; ++e) {
    if (entry_missed(refusal.nearest, refusal.target, e)) {
      refusal.components.push_back(kEntryNames[e]);
    }
  }
  refusal.looked_up = !inside_representation_lookup();
  if (refusal.looked_up) {
    refusal.representing = strategies_representing(default_registry(), material, refusal.ply_angle,
                                                   thickness, refusal.strategy);
  }
  throw UnreachableStiffness(std::move(refusal));
}

std::string describe_unreachable(const Eigen::Matrix3d& reached, const Eigen::Matrix3d& target) {
  const int rows[6] = {0, 1, 0, 0, 1, 2}, cols[6] = {0, 1, 1, 2, 2, 2};
  const char* names[6] = {"C11", "C22", "C12", "C16", "C26", "C66"};
  int worst = 0;
  std::string entries;
  for (int e = 0; e < 6; ++e) {
    const double miss = std::abs(reached(rows[e], cols[e]) - target(rows[e], cols[e]));
    if (miss > std::abs(reached(rows[worst], cols[worst]) - target(rows[worst], cols[worst]))) {
      worst = e;
    }
    // + 0.0 turns -0 into 0 for printing.
    entries += fmt::format("{}{} {:.4g} ({:.4g})", e ? ", " : "", names[e],
                           reached(rows[e], cols[e]) * kGPaPerPa + 0.0,
                           target(rows[e], cols[e]) * kGPaPerPa + 0.0);
  }
  return fmt::format(
      "{} cannot be reached: the nearest stiffness with non-negative springs has {} = {:.4g} GPa "
      "where the target is {:.4g} GPa (relative error {:.3g}); nearest (target) in GPa: {}",
      names[worst], names[worst], reached(rows[worst], cols[worst]) * kGPaPerPa,
      target(rows[worst], cols[worst]) * kGPaPerPa, (reached - target).norm() / target.norm(),
      entries);
}

}  // namespace plydem
