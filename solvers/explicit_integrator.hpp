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
///
/// Breaking. When the model's bonds can break (Bonds::breakable) or some are broken, both kernels
/// decide every bond at every cycle through the one failure law (core/bond_failure.hpp, applied by
/// update_bond_damage in contacts/bond_kernel.hpp) from the deformation they computed its force
/// from: a brittle bond breaks at utilisation 1, a softening one loses stiffness along its
/// softening line and breaks when its damage reaches 1. A break or a damage step decided at cycle
/// n acts from cycle n + 1 on. The fused kernel decides at both ends of a bond alike, each
/// particle clearing its own slot (no rebuild of the table, no atomics), and logs at the first
/// end. Particles no intact bond joins interact by contacts (contacts/unbonded_contacts.hpp), and
/// the run keeps an energy account (energy()). The model's bonds get their new state, damage and
/// stiffness as breaks happen and at the end of each run; the broken bonds keep their rows.
///
/// Backends (ExplicitSettings::backend). The fused kernel's cycles run on the host or on a device
/// (solvers/device_backend.hpp: CUDA, or its code emulated on the host), which holds the kernel's
/// arrays for the whole run and runs solvers/particle_step.hpp, the same half-bond math and failure
/// law, once per particle: same motions, damping, breaks in the same order, and reports reduced on
/// the device in a fixed order. The host copy is brought up to date after every batch of cycles,
/// so checks, hooks, gather() and the break log read it as they read the host kernel's.

#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "contacts/particle_ordering.hpp"
#include "contacts/unbonded_contacts.hpp"
#include "core/bond_failure.hpp"
#include "core/checkpoint.hpp"
#include "core/model.hpp"
#include "solvers/device_backend.hpp"

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
  /// Keep the energy account (energy()) in a model that cannot break too (a model that can, or has
  /// broken bonds, always keeps it). Off, an elastic model runs the elastic kernel unchanged.
  bool energy_account = false;
  /// Contacts between particles that no intact bond joins, in runs that keep the account.
  bool contacts = true;
  ContactSettings contact;
  /// Where the fused kernel keeps breakable bonds' strengths (contacts/bond_kernel.hpp).
  StrengthStorage strength_storage = StrengthStorage::kAutomatic;
  /// Where the fused kernel runs (solvers/device_backend.hpp): the host, a CUDA device, or the
  /// device's code emulated on the host. A device backend runs the fused kernel only, and no
  /// contacts between unbonded particles yet (a breaking run needs `contacts` off).
  ExplicitBackend backend = ExplicitBackend::kCpu;
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

/// The energy account of an explicit run, consistent with leapfrog: a cycle n with forces F_n at
/// u_n and velocities v(n -+ 1/2) adds F_n . (v(n-1/2) + v(n+1/2)) dt / 2 per degree of freedom,
/// which sums, over cycles, to the trapezoidal work 1/2 (F_n + F_n+1) . (u_n+1 - u_n) that makes
/// strain + leapfrog kinetic energy change exactly by the work of the other forces (for linear
/// bonds). The account runs from the integrator's first cycle to the state of the last one (its
/// second half step not yet counted), so that
///   initial + boundary_work = strain + kinetic + damping + released + contact + friction
/// up to rounding for an elastic model; a break, decided at u_n and acting from n + 1, is off by
/// the bond's energy change over that one cycle, and contacts (not linear in u) by their own.
struct EnergyAccount {
  double initial = 0;  ///< strain + kinetic energy (free dofs) before the first cycle [J]
  /// Work of the prescribed motions on the particles: - F . v over the prescribed components,
  /// F the bond and contact forces on them [J].
  double boundary_work = 0;
  double strain_energy = 0;   ///< in the bonds, at the last cycle's state [J]
  double kinetic_energy = 0;  ///< leapfrog, free components, at the last cycle [J]
  double damping = 0;         ///< dissipated by local damping [J]
  /// Released by breaking and softening: what a bond gives up at each damage step (all its
  /// strain energy, for a brittle break), from the breaks decided before the last cycle [J].
  double released = 0;
  double contact_energy = 0;  ///< held by touching contacts, at the last cycle [J]
  double friction = 0;        ///< dissipated by contact slip [J]

  /// initial + boundary_work - (strain + kinetic + damping + released + contact + friction).
  double balance() const {
    return initial + boundary_work -
           (strain_energy + kinetic_energy + damping + released + contact_energy + friction);
  }
};

/// One end of a bond as the active kernel holds it (ExplicitIntegrator::bond_ends).
struct BondEnd {
  bool holds = false;  ///< the bond is intact at this end
  double damage = 0;
  double kappa = 1;  ///< largest utilisation so far (softening; 1 otherwise)
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

  /// Breaks bond `bond` (an index into the model's bonds) by hand, from the next cycle on: its row
  /// stays (state `mode`, damage 1, zero stiffness), the fused kernel empties its two slots
  /// without rebuilding its table, and its particles interact by contact (if settings.contacts).
  /// The first break of an integrator that ran the elastic kernel switches it to the breaking one
  /// (its table is built once more, and the energy account starts at the next cycle). The time
  /// step is kept: a broken bond leaves the model no stiffer. Not logged in breaks(). Throws
  /// plydem::Error for a bond that does not exist or is broken already, or a mode that is no
  /// break.
  void break_bond(int bond, BondState mode = BondState::kBrokenTension);

  /// The bonds the failure law broke, in the order they broke (then by bond): at = the cycle's
  /// state time (cycle number x time step) [s], load = 0 (the integrator knows no load; the
  /// caller does: the grips' travel at that time), position = the contact point X_first +
  /// lever_first n + u_first.
  const std::vector<BondBreak>& breaks() const { return breaks_; }

  /// The energy account (EnergyAccount) at the last cycle; zeros where the integrator keeps none
  /// (an elastic model without ExplicitSettings::energy_account).
  EnergyAccount energy() const;

  /// Whether the integrator runs the breaking kernel (and keeps the account and the contacts).
  bool breaking() const { return breaking_; }

  /// Bond `bond` as each of its two ends holds it in the active kernel: the fused kernel keeps
  /// both ends apart and they must agree to the bit (the reference kernel keeps one bond).
  std::array<BondEnd, 2> bond_ends(int bond) const;

  /// The contacts (null unless the run has them).
  const UnbondedContacts* contacts() const { return contacts_.get(); }

  /// Checkpoint (core/checkpoint.hpp): writes the model as the integrator holds it (between runs,
  /// or from a run's hook: the state is then read from the kernel) and everything the next cycles
  /// depend on: the time and cycle count, softening histories, the break log, the energy account,
  /// the contacts and their history. The prescribed motions are the caller's to restore.
  void save(CheckpointWriter& out) const;
  /// Between runs, on an integrator constructed with the same settings on the model as it was when
  /// the saved integrator was constructed: restores what save() wrote (into the model and the
  /// kernel), so that the cycles that follow are, bit for bit, those the saved integrator would
  /// have run (after the caller sets the same prescribed motions). Throws plydem::Error for a
  /// checkpoint of another model or other settings (naming the field or setting that differs).
  void restore(CheckpointReader& in);

  /// Bytes the fused kernel holds for the run (its state, the gather lists, the bond types, the
  /// renumbering), or 0 for the reference kernel. The model's own arrays are not counted.
  std::size_t kernel_bytes() const;

 private:
  struct Fused;
  CycleReport reference_cycle(bool last);
  // `cycles` cycles of the active kernel on its own state; the last one computes the report.
  CycleReport step(long cycles);
  void load_kernel();
  void store_kernel();
  // Breaking: set up the breaking kernel, its account and its contacts.
  void start_breaking();
  void make_contacts();
  long fused_cycles(long cycles, bool report_last);
  // fused_cycles on a device backend; the host copy brought up to date after the batch.
  long device_cycles(long cycles, bool report_last);
  // The fused step's KernelMode (solvers/particle_step.hpp) for the bonds as they are.
  int kernel_mode() const;
  // Resolves damage steps against the state after their cycle: the energy each released
  // (SlotEvent), breaks logged; the steps of `report_cycle` are counted at the next step.
  void resolve_events(std::vector<SlotEvent>& events, long report_cycle);
  // The current state as the contacts read it (the kernel's or the model's arrays).
  ContactState contact_state() const;
  // Writes the fused kernel's bond damage back to the model; throws if two ends disagree.
  void store_bonds();
  // restore()'s parts: the breaking run's energy account of n particles, and the fused kernel's
  // slots (broken bonds cleared, softening histories) from the checkpoint's bonds and kappa.
  void restore_account(CheckpointReader& in, int n);
  void restore_slots(const Bonds& bonds, const Eigen::ArrayXd& kappa);
  void log_break(int bond, BondState mode, long cycle, const double* first_displacement);

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

  // Breaking, account and contacts.
  bool breaking_ = false, softening_ = false;
  // The bonds' intact stiffnesses (0 for a bond that came broken), their softening history.
  Eigen::ArrayXd intact_[4];  // normal, shear, bending, twisting
  Eigen::ArrayXd kappa_;      // reference kernel
  std::vector<BondBreak> breaks_;
  std::unique_ptr<UnbondedContacts> contacts_;
  long contact_countdown_ = 0;
  bool initial_set_ = false;
  double initial_energy_ = 0;
  CycleReport last_report_;
  double pending_work_ = 0, pending_damping_ = 0;  // the last cycle's second halves (x dt / 2)
  // Reference kernel: per-particle sums of F (v_old + v_new), released energy.
  Eigen::ArrayXd work_sum_, damping_sum_;
  Vector3Array contact_force_, contact_torque_;
  double released_ = 0, released_pending_ = 0;
};

}  // namespace plydem
