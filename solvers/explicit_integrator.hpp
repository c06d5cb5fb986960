#pragma once
/// \file
/// Explicit dynamics: central differences (leapfrog) with PFC-style local damping, an automatic
/// critical time step, and prescribed velocities on particle groups (paper Sec. 2.1, Fig. 2).
/// Each cycle: bond forces at the current displacements, then velocities and displacements of
/// every free degree of freedom.
///
/// The integrator is a run loop over one backend interface (solvers/explicit_backend.hpp), the
/// backend chosen at run time (ExplicitSettings::backend, like OpenMM's platforms): reference (the
/// model's own arrays, plain loops), cpu (the default: the particles renumbered for locality, each
/// block of eight summing its own bonds and advancing in SIMD lanes, OpenMP threads), emulation
/// and cuda (the same kernel-order state mirrored on a device, one particle per thread). One
/// particle's step (the half-bond law, the update, the energy account) is written once
/// (solvers/particle_step.hpp) and every backend instantiates it; each particle's result is
/// independent of the thread count, and a run is bitwise reproducible. The cpu, emulation and cuda
/// backends compute the same bits (tests hold emulation to cpu); the reference sums its forces in
/// another order and agrees within rounding.
///
/// run() is the run loop (the PFC "cycle N / solve ratio" of the paper's Sec. 2.1): it hands the
/// state to the backend once, cycles in chunks that end at checks (every `check_interval` cycles,
/// and wherever a hook falls due; the last cycle of a chunk computes the unbalanced-force ratio
/// and the energies), tests the stop conditions and calls the periodic hooks due (RunHook:
/// checkpointing, sampling, progress, a user's callback); a hook reads the state it needs through
/// gather(). At the end the whole state goes back into the model. cycle() and advance() are
/// one-chunk runs.
///
/// Breaking. When the model's bonds can break (Bonds::breakable) or some are broken, every backend
/// decides every bond at every cycle through the one failure law (core/bond_failure.hpp, applied
/// by update_bond_damage in contacts/half_bond.hpp) from the deformation it computed its force
/// from: a brittle bond breaks at utilisation 1, a softening one loses stiffness along its
/// softening line and breaks when its damage reaches 1. A break or a damage step decided at cycle
/// n acts from cycle n + 1 on. The kernel-order backends decide at both ends of a bond alike, each
/// particle clearing its own slot (no rebuild of the table, no atomics), and log at the first end.
/// Particles no intact bond joins interact by contacts (contacts/unbonded_contacts.hpp; cpu and
/// reference backends), and the run keeps an energy account (energy()). The model's bonds get
/// their new state, damage and stiffness as breaks happen and at the end of each run; the broken
/// bonds keep their rows.

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
#include "solvers/backend_kind.hpp"
#include "solvers/explicit_backend.hpp"

namespace plydem {

struct ExplicitSettings {
  /// PFC local damping coefficient alpha: the force on each degree of freedom is reduced by
  /// alpha |F| sign(v). 0 = undamped.
  double local_damping = 0.7;
  /// Time step as a fraction of the critical one (a Gershgorin bound, so 1.0 is still stable).
  double safety_factor = 0.8;
  /// A fixed time step [s]; 0 = automatic.
  double time_step = 0;
  /// How the kernel-order backends number the particles internally (results do not depend on it).
  ParticleOrder particle_order = ParticleOrder::kAutomatic;
  /// Keep the energy account (energy()) in a model that cannot break too (a model that can, or has
  /// broken bonds, always keeps it). Off, an elastic model runs the elastic kernel unchanged.
  bool energy_account = false;
  /// Contacts between particles that no intact bond joins, in runs that keep the account.
  bool contacts = true;
  ContactSettings contact;
  /// Where the kernel-order backends keep breakable bonds' strengths (contacts/bond_kernel.hpp).
  StrengthStorage strength_storage = StrengthStorage::kAutomatic;
  /// Which backend runs the cycles (solvers/backend_kind.hpp): cpu, cuda, emulation (the device's
  /// code on the host) or reference. The device backends have no contacts between unbonded
  /// particles yet (a breaking run there needs `contacts` off).
  ExplicitBackend backend = ExplicitBackend::kCpu;
  /// Under `mpiexec -n N` (N > 1), each rank runs its share of the particles and sends its border
  /// to its neighbours every cycle (solvers/rank_exchange.hpp): the cpu backend's blocks or the
  /// reference backend's loops, on N ranks the same bits as that backend on one (the device
  /// backends run on one rank only). False: every rank runs the whole model.
  bool split_between_ranks = true;
};

/// Throws plydem::Error naming the first setting out of range.
void validate(const ExplicitSettings& settings);

/// Whether a run with `settings` here is split between MPI ranks (split_between_ranks, under
/// mpiexec with more than one rank).
bool splits_between_ranks(const ExplicitSettings& settings);

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

/// A periodic hook of run(): checkpointing, sampling, progress, a user's callback. It is called at
/// the checks where it falls due, in the order of RunControl::hooks; returning false stops the run
/// (RunStop::kHook) after the hooks of that check.
struct RunHook {
  /// Every this many cycles of the run (> 0: the run's chunks end there, so the hook sees cycle
  /// counts that are multiples of it), or 0: at every check.
  long every_cycles = 0;
  /// At checks at least this many seconds of wall time after its last call (or the run's start);
  /// 0 = no time condition.
  double every_seconds = 0;
  std::function<bool(const RunCheck&)> call;
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
  /// The periodic hooks (RunHook), called after on_check and before on_progress.
  std::vector<RunHook> hooks;
  /// A hook at every check (sampling): may read the state (gather()) and set prescribed motions.
  /// Returning false stops the run (RunStop::kHook).
  std::function<bool(const RunCheck&)> on_check;
  /// Progress: a hook every `progress_seconds` of wall time (the first after that long).
  std::function<void(const RunCheck&)> on_progress;
  double progress_seconds = 2.0;

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

  /// Replaces the prescribed motions. A particle in a listed group has the given components fixed;
  /// a motion that names a particle (PrescribedMotion::particle) replaces its group's for it.
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

  /// During a run (from a hook): copies the state of the listed model particles from the backend
  /// into `into` (displacement, rotation, velocity, angular velocity, force, torque rows; `into`
  /// has the model's particle count, and the other rows are left alone). Outside a run the model
  /// holds the state and this copies from it. `into` may be the model's own particles except
  /// with StateAt::kForces (the model is the live state of the reference backend).
  void gather(std::span<const int> particles, Particles& into,
              StateAt at = StateAt::kCurrent) const;

  /// Breaks bond `bond` (an index into the model's bonds) by hand, from the next cycle on: its row
  /// stays (state `mode`, damage 1, zero stiffness), the backend empties its two slots
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

  /// Bond `bond` as each of its two ends holds it in the backend: the kernel-order backends keep
  /// both ends apart and they must agree to the bit (the reference keeps one bond).
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

  /// Bytes the backend holds for the run (its state, the gather lists, the bond types, the
  /// renumbering), or 0 for the reference backend. The model's own arrays are not counted.
  std::size_t kernel_bytes() const;
  /// Under mpiexec, how the run is split between the ranks (solvers/rank_exchange.hpp); null
  /// where it is not split.
  const RankPartition* rank_partition() const { return backend_->partition(); }
  /// Which backend runs the cycles.
  ExplicitBackend backend() const { return settings_.backend; }

 private:
  // The chunks of a run: `cycles` cycles of the backend, stopping at breaks to resolve them; the
  // last one computes the report.
  CycleReport step(long cycles);
  // The account starts from the energy the state holds before its first cycle.
  void start_account();
  // Breaking: set up the breaking kernel, its account and its contacts.
  void start_breaking();
  void make_contacts();
  // Resolves damage steps against the state after their cycle: the energy each released
  // (SlotEvent), breaks logged; the steps of `report_cycle` are counted at the next step.
  void resolve_events(std::vector<SlotEvent>& events, long report_cycle);
  // Writes the backend's bond damage back to the model; throws if two ends disagree.
  void store_bonds();
  // restore()'s part: the breaking run's energy account of n particles.
  void restore_account(CheckpointReader& in, int n);
  void log_break(int bond, BondState mode, long cycle, const double* first_displacement);

  Model& model_;
  ExplicitSettings settings_;
  double time_step_ = 0;
  double time_ = 0;
  long cycles_ = 0;
  // Per particle and component: true where prescribed (translation, rotation), and the motions.
  MotionTable motions_;
  int free_particles_ = 0;
  bool running_ = false;
  // The bonds' intact stiffnesses and softening histories, which the backend reads (on the heap:
  // the backend keeps a reference, and the integrator may move).
  std::unique_ptr<BondHistory> history_;
  std::unique_ptr<KernelBackend> backend_;

  // Breaking, account and contacts.
  bool breaking_ = false, softening_ = false;
  std::vector<BondBreak> breaks_;
  std::unique_ptr<UnbondedContacts> contacts_;
  long contact_countdown_ = 0;
  bool initial_set_ = false;
  double initial_energy_ = 0;
  CycleReport last_report_;
  double pending_work_ = 0, pending_damping_ = 0;  // the last cycle's second halves (x dt / 2)
  double released_ = 0, released_pending_ = 0;
};

}  // namespace plydem
