#pragma once
/// \file
/// Explicit dynamics: central differences (leapfrog) with PFC-style local damping, an automatic
/// critical time step, and prescribed velocities on particle groups (paper Sec. 2.1, Fig. 2).
/// Each cycle: bond forces at the current displacements (the shared kernel), then velocities and
/// displacements of every free degree of freedom.

#include <Eigen/Dense>
#include <vector>

#include "core/model.hpp"

namespace plydem {

struct ExplicitSettings {
  /// PFC local damping coefficient alpha: the force on each degree of freedom is reduced by
  /// alpha |F| sign(v). 0 = undamped.
  double local_damping = 0.7;
  /// Time step as a fraction of the critical one (a Gershgorin bound, so 1.0 is still stable).
  double safety_factor = 0.8;
  /// A fixed time step [s]; 0 = automatic.
  double time_step = 0;
};

/// Throws plydem::Error naming the first setting out of range.
void validate(const ExplicitSettings& settings);

/// Velocities imposed on every particle of a boundary group. A component whose `fix_*` flag is
/// false stays free.
struct PrescribedMotion {
  BoundaryGroup group = BoundaryGroup::kFree;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
  std::array<bool, 3> fix_velocity{false, false, false};
  std::array<bool, 3> fix_angular_velocity{false, false, false};
};

/// What one cycle measured, at the displacements the forces were computed from.
struct CycleReport {
  double strain_energy = 0;  ///< [J]
  /// Leapfrog kinetic energy 1/2 m v(n-1/2).v(n+1/2) (and rotations): with the strain energy it is
  /// exactly conserved by the undamped central-difference scheme for a linear model.
  double kinetic_energy = 0;
  /// Mean unbalanced force on the free particles over the mean bond force (PFC's ratio).
  double unbalanced_force_ratio = 0;
};

/// The critical time step of the model's bonds: 2 / sqrt(lambda_max) with lambda_max bounded by
/// Gershgorin's theorem on M^-1/2 K M^-1/2. Throws plydem::Error if the model has no stiffness.
double critical_time_step(const Model& model);

class ExplicitIntegrator {
 public:
  /// Validates the settings (validate() above) and the model.
  ExplicitIntegrator(Model& model, const ExplicitSettings& settings);

  /// Replaces the prescribed motions. A particle in a listed group has the given components fixed.
  void set_prescribed_motions(const std::vector<PrescribedMotion>& motions);

  double time_step() const { return time_step_; }
  double time() const { return time_; }
  long cycles() const { return cycles_; }

  /// One cycle: forces at the current state, then velocities and displacements.
  CycleReport cycle();

 private:
  Model& model_;
  ExplicitSettings settings_;
  double time_step_ = 0;
  double time_ = 0;
  long cycles_ = 0;
  // Per particle and component: 1 where prescribed (translation, rotation).
  Eigen::Array<bool, Eigen::Dynamic, 3> fixed_velocity_;
  Eigen::Array<bool, Eigen::Dynamic, 3> fixed_angular_velocity_;
  Vector3Array prescribed_velocity_;
  Vector3Array prescribed_angular_velocity_;
  int free_particles_ = 0;
};

}  // namespace plydem
