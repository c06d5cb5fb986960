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
///
/// run() is the run loop (the PFC "cycle N / solve ratio" of the paper's Sec. 2.1): it takes the
/// state into the kernel's order once, cycles in chunks of `check_interval`, and at each check
/// (the last cycle of a chunk computes the unbalanced-force ratio and the energies) tests the stop
/// conditions and calls the hooks; a hook reads the state it needs through gather(). At the end
/// the whole state goes back into the model. cycle() and advance() are one-chunk runs.

#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string_view>
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

/// Why run() stopped.
enum class RunStop {
  kQuasiStatic,  ///< the unbalanced-force ratio fell to the tolerance
  kCycleLimit,   ///< the run did its cycles
  kTimeLimit,    ///< the wall-time limit passed
  kHook,         ///< the check hook asked to stop
};

/// "quasi-static", "cycle limit", "time limit", "hook".
std::string_view to_string(RunStop stop);

/// What the hooks see at a check of run(). The particles' state stays in the kernel: a hook that
/// needs some of it calls ExplicitIntegrator::gather(); the model's force and torque arrays hold
/// the last cycle's forces (those of the state before its update).
struct RunCheck {
  long cycles = 0;             ///< cycles of the integrator so far
  long run_cycles = 0;         ///< cycles of this run so far
  CycleReport report;          ///< of the last cycle
  double elapsed_seconds = 0;  ///< since run() started
  /// Estimated seconds to the first stop condition: the cycles left (cycle limit), the ratio's
  /// exponential decay between the last two checks (tolerance), the wall-time limit; negative
  /// when none of them gives an estimate yet.
  double seconds_left = -1;
};

/// How run() runs and when it stops. At least one stop condition must be set; conditions are
/// tested at checks only, in the order ratio, cycles, time, and a run does at least one cycle.
struct RunControl {
  /// Cycles between checks (>= 1). A check costs about one cycle; its cycle also computes the
  /// energies and the ratio, which plain cycles skip.
  long check_interval = 1000;
  /// Cycles of this run (> 0), the last one always a check; 0 = no cycle limit.
  long max_cycles = 0;
  /// Stop at the first check whose unbalanced-force ratio is <= tolerance (> 0); 0 = off.
  double tolerance = 0;
  /// Stop at the first check at or past this many seconds of wall time (> 0); 0 = off.
  double time_limit_seconds = 0;
  /// Progress: called at checks, at most once per `progress_seconds` (the first after that long).
  std::function<void(const RunCheck&)> on_progress;
  double progress_seconds = 2.0;
  /// Sampling: called at every check; may read the state (gather()) and set prescribed motions.
  /// Returning false stops the run (RunStop::kHook).
  std::function<bool(const RunCheck&)> on_check;

  /// Throws plydem::Error naming the first bad field.
  void validate() const;
};

/// What run() did.
struct RunReport {
  long cycles = 0;  ///< of this run
  long checks = 0;
  RunStop stop = RunStop::kCycleLimit;
  CycleReport last;             ///< of the last cycle (its ratio is the run's final ratio)
  double kernel_seconds = 0;    ///< cycling, check cycles included
  double check_seconds = 0;     ///< stop conditions and hooks
  double transfer_seconds = 0;  ///< the state into kernel order and back into the model
  double wall_seconds = 0;      ///< the whole run
};

/// Where gather() reads the displacements and rotations from.
enum class StateAt {
  kCurrent,  ///< after the last cycle's update
  /// the state the last cycle's forces were computed from (before its update); velocities are
  /// the updated ones either way
  kForces,
};

/// The critical time step of the model's bonds: 2 / sqrt(lambda_max) with lambda_max bounded by
/// Gershgorin's theorem on M^-1/2 K M^-1/2. Throws plydem::Error if the model has no stiffness.
double critical_time_step(const Model& model);

class ExplicitIntegrator {
 public:
  /// Validates the settings (validate() above) and the model. The masses, moments of inertia and
  /// bonds are read here, once; the particles' state is read at the start of every run()
  /// (cycle(), advance()) and written back at its end.
  ExplicitIntegrator(Model& model, const ExplicitSettings& settings);
  ~ExplicitIntegrator();
  ExplicitIntegrator(ExplicitIntegrator&&) noexcept;

  /// Replaces the prescribed motions. A particle in a listed group has the given components fixed.
  /// Allowed between runs and from a run's check hook (it takes effect from the next cycle).
  void set_prescribed_motions(const std::vector<PrescribedMotion>& motions);

  double time_step() const { return time_step_; }
  double time() const { return time_; }
  long cycles() const { return cycles_; }

  /// Cycles until a stop condition of `control` holds (see RunControl). The model's arrays are
  /// read at the start and written at the end (displacements, rotations, velocities; forces and
  /// torques of the last cycle); in between the state is the kernel's. The result equals, bit for
  /// bit, the same number of cycle() calls, whatever the check interval. Throws plydem::Error for
  /// a bad control or when called from a hook; an exception from a hook ends the run with the
  /// model written back.
  RunReport run(const RunControl& control);

  /// One cycle: forces at the current state, then velocities and displacements. The model's
  /// force and torque are the bond forces the cycle used (at the state before its update).
  CycleReport cycle();

  /// `cycles` cycles (>= 1): run() with one check, at the end; the report is the last cycle's.
  CycleReport advance(long cycles);

  /// During a run (from a hook): copies the state of the listed model particles from the kernel
  /// into `into` (displacement, rotation, velocity, angular velocity, force, torque rows; `into`
  /// has the model's particle count, and the other rows are left alone). Outside a run the model
  /// holds the state and this copies from it. `into` may be the model's own particles except
  /// with StateAt::kForces (the model is the live state of the reference kernel).
  void gather(std::span<const int> particles, Particles& into,
              StateAt at = StateAt::kCurrent) const;

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
  // `cycles` cycles of the active kernel on its own state; the last one computes the report.
  CycleReport step(long cycles);
  void load_kernel();
  void store_kernel();

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
  bool running_ = false;
  // Reference kernel: displacements and rotations before the last cycle of a chunk.
  Vector3Array previous_displacement_, previous_rotation_;
  std::unique_ptr<Fused> fused_;
};

}  // namespace plydem
