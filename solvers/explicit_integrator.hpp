#pragma once
/// \file
/// Explicit dynamics: central differences (leapfrog) with PFC-style local damping, an automatic
/// critical time step, and prescribed velocities on particle groups (paper Sec. 2.1, Fig. 2).
/// Each cycle: bond forces at the current displacements, then velocities and displacements of
/// every free degree of freedom.
///
/// Two kernels run the same cycle. The fused kernel (default) renumbers the particles for locality
/// (contacts/particle_ordering.hpp: lattice lines for a regular packing, else a Hilbert curve),
/// keeps its own copy of the state in that order, and in one pass per cycle lets each particle sum
/// its own bonds (contacts/bond_kernel.hpp, gather form) and advance, eight particles at a time in
/// SIMD lanes, split between OpenMP threads (OMP_NUM_THREADS). Each particle's result is
/// independent of the thread count, and a run is bitwise reproducible. The reference kernel is the
/// plain loop: compute_bond_forces, then one update per degree of freedom; tests hold the fused
/// kernel to it.

#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "contacts/particle_ordering.hpp"
#include "core/model.hpp"

namespace plydem {

/// Which implementation advances the model (see the file comment).
enum class ExplicitKernel { kFused, kReference };

struct ExplicitSettings {
  /// PFC local damping coefficient alpha: the force on each degree of freedom is reduced by
  /// alpha |F| sign(v). 0 = undamped.
  double local_damping = 0.7;
  /// Time step as a fraction of the critical one (a Gershgorin bound, so 1.0 is still stable).
  double safety_factor = 0.8;
  /// A fixed time step [s]; 0 = automatic.
  double time_step = 0;
  ExplicitKernel kernel = ExplicitKernel::kFused;
  /// How the fused kernel numbers the particles internally (results do not depend on it).
  ParticleOrder particle_order = ParticleOrder::kAutomatic;
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
  /// Validates the settings (validate() above) and the model. The masses, moments of inertia and
  /// bonds are read here, once; the particles' state is read at every cycle() and advance().
  ExplicitIntegrator(Model& model, const ExplicitSettings& settings);
  ~ExplicitIntegrator();
  ExplicitIntegrator(ExplicitIntegrator&&) noexcept;

  /// Replaces the prescribed motions. A particle in a listed group has the given components fixed.
  void set_prescribed_motions(const std::vector<PrescribedMotion>& motions);

  double time_step() const { return time_step_; }
  double time() const { return time_; }
  long cycles() const { return cycles_; }

  /// One cycle: forces at the current state, then velocities and displacements. The model's
  /// force and torque are the bond forces the cycle used (at the state before its update).
  CycleReport cycle();

  /// `cycles` cycles (>= 1), the same as calling cycle() that many times, but the report is
  /// computed for the last cycle only and the model's arrays are read at the start and written at
  /// the end only (displacements, rotations, velocities; forces and torques of the last cycle).
  /// This is the fast way to run: a caller that needs the unbalanced-force ratio every N cycles
  /// calls advance(N).
  CycleReport advance(long cycles);

  /// Removes bond `bond` (an index into the model's bonds) for the rest of the run: the model's
  /// bonds lose it (the later ones move down by one; the reference kernel reads them), and the
  /// fused kernel empties its slots without rebuilding its table (GatherBonds::drop_bond). The
  /// time step is kept: a bond fewer leaves the model no stiffer. Throws plydem::Error for a bond
  /// that does not exist.
  void drop_bond(int bond);

  /// Bytes the fused kernel holds for the run (its state, the gather lists, the bond types, the
  /// renumbering), or 0 for the reference kernel. The model's own arrays are not counted.
  std::size_t kernel_bytes() const;

 private:
  struct Fused;
  CycleReport reference_cycle();

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
  std::unique_ptr<Fused> fused_;
};

}  // namespace plydem
