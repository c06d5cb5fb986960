#pragma once
// Small coupons and loadings that several test files share (the explicit kernels, the events
// solver, checkpoints), and the check of an error's message. Unlike test_support.hpp this uses the
// library: it builds models, it does not compute references.
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/model.hpp"
#include "solvers/bond_events.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/registry.hpp"

namespace plydem::test {

/// The hex2d E-glass coupon of the explicit-breaking tests (2 x 0.5 mm, 0.1 mm particles by
/// default), its particles within two diameters of each end in the left and right grips.
inline Model small_coupon(double length = 2e-3, double width = 0.5e-3, double diameter = 0.1e-3) {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.length = length;
  spec.width = width;
  spec.particle_diameter = diameter;
  Model m = default_registry().create("hex2d")->build(spec).model;
  Particles& p = m.particles;
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    p.group(i) = static_cast<int>(x <= x_min + 2 * diameter   ? BoundaryGroup::kLeftGrip
                                  : x >= x_max - 2 * diameter ? BoundaryGroup::kRightGrip
                                                              : BoundaryGroup::kFree);
  }
  return m;
}

/// Grips moving apart along x at `speed` each (free laterally), as the tension test pulls.
inline std::vector<PrescribedMotion> pull(double speed) {
  PrescribedMotion left, right;
  left.group = BoundaryGroup::kLeftGrip;
  right.group = BoundaryGroup::kRightGrip;
  left.velocity = Eigen::Vector3d(-speed, 0, 0);
  right.velocity = Eigen::Vector3d(speed, 0, 0);
  for (PrescribedMotion* m : {&left, &right}) {
    m->fix_velocity = {true, false, true};
    m->fix_angular_velocity = {true, true, false};
  }
  return {left, right};
}

/// The events solver's grips: the particles within two diameters `d` of each end held in z and
/// against tilting, the left at ux = 0, the right at ux = `travel` per unit load factor; `reaction`
/// marks the right grip's ux (the reaction the solver sums).
inline void grip_constraints(const Model& m, double d, double travel, DofConstraints& unit,
                             DofFlags& reaction) {
  const Particles& p = m.particles;
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  unit = DofConstraints(p.size());
  reaction = DofFlags::Constant(p.size(), kDofsPerParticle, false);
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    const bool left = x <= x_min + 2 * d, right = x >= x_max - 2 * d;
    if (!left && !right) continue;
    unit.fix(i, Dof::kUx, right ? travel : 0.0);
    unit.fix(i, Dof::kUz);
    unit.fix(i, Dof::kThetaX);
    unit.fix(i, Dof::kThetaY);
    if (right) reaction(i, static_cast<int>(Dof::kUx)) = true;
  }
}

/// Grips that carry a uniform in-plane strain (eps_xx, eps_yy, gamma_xy) per unit load factor: the
/// particles within two diameters `d` of each end held at u = eps x (u_z = 0), so that a coupon
/// whose lattice is uniform under that strain has no grip concentration; `reaction` marks the
/// right grip's ux. Returns how many particles are held.
inline int affine_grips(const Model& m, double d, const Eigen::Vector3d& strain,
                        DofConstraints& unit, DofFlags& reaction) {
  const Particles& p = m.particles;
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  unit = DofConstraints(p.size());
  reaction = DofFlags::Constant(p.size(), kDofsPerParticle, false);
  int held = 0;
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
    const bool left = x <= x_min + 2 * d, right = x >= x_max - 2 * d;
    if (!left && !right) continue;
    ++held;
    unit.fix(i, Dof::kUx, strain(0) * x + 0.5 * strain(2) * y);
    unit.fix(i, Dof::kUy, 0.5 * strain(2) * x + strain(1) * y);
    unit.fix(i, Dof::kUz, 0.0);
    if (right) reaction(i, static_cast<int>(Dof::kUx)) = true;
  }
  return held;
}

/// The message of the plydem::Error that `f` throws, or "(no error)".
inline std::string error_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace plydem::test
