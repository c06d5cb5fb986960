#pragma once
/// \file
/// What the explicit integrator's run loop (solvers/explicit_integrator.hpp) asks of a backend,
/// and the backends (solvers/backend_kind.hpp), chosen at run time as OpenMM chooses a platform:
///
///  - reference (solvers/reference_backend.cpp): the model's own arrays, a scatter pass over the
///    bonds (compute_bond_forces) and the failure law bond by bond, then the shared update
///    (solvers/particle_step.hpp advance_particle); the slow path tests hold the others to;
///  - cpu (solvers/cpu_backend.cpp): the state in kernel order (solvers/kernel_order_backend.hpp),
///    each block of eight particles summing its own bonds and advancing in SIMD lanes
///    (step_particle), the blocks split between OpenMP threads;
///  - emulation and cuda (solvers/kernel_order_backend.cpp, MirroredBackend): the same state
///    mirrored on a device (solvers/device_backend.hpp), one particle per thread.
///
/// A backend holds the particles' state during a run (between load() and store()) in its own
/// layout and runs batches of cycles; the loop owns time, cycles, stop rules, prescribed motions,
/// hooks, the break log, the energy account's totals and the contacts' skin checks. Every backend
/// decides breaks with the one failure law and returns the damage steps of a batch, whose last
/// cycle is the first that took one, for the loop to resolve (ExplicitIntegrator::resolve_events).

#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "contacts/particle_ordering.hpp"
#include "contacts/unbonded_contacts.hpp"
#include "core/model.hpp"
#include "solvers/backend_kind.hpp"
#include "solvers/kernel_arrays.hpp"

namespace plydem {

struct RankPartition;

/// Velocities imposed on every particle of a boundary group, or on one particle. A component whose
/// `fix_*` flag is false stays free.
struct PrescribedMotion {
  BoundaryGroup group = BoundaryGroup::kFree;
  /// >= 0: this one particle (a model index; `group` is not read), whose motion replaces its
  /// group's: grips that hold a uniform strain move each particle at its own velocity.
  int particle = -1;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
  std::array<bool, 3> fix_velocity{false, false, false};
  std::array<bool, 3> fix_angular_velocity{false, false, false};
};

/// Where gather() reads the displacements and rotations from.
enum class StateAt {
  kCurrent,  ///< after the last cycle's update
  /// the state the last cycle's forces were computed from (before its update); velocities are
  /// the updated ones either way
  kForces,
};

/// One end of a bond as the active backend holds it (ExplicitIntegrator::bond_ends).
struct BondEnd {
  bool holds = false;  ///< the bond is intact at this end
  double damage = 0;
  double kappa = 1;  ///< largest utilisation so far (softening; 1 otherwise)
};

/// The prescribed motions per model particle and component (true where prescribed), with the
/// imposed values, as the run loop keeps them, and the motions they came from.
struct MotionTable {
  Eigen::Array<bool, Eigen::Dynamic, 3> fixed_velocity, fixed_angular_velocity;
  Vector3Array velocity, angular_velocity;
  std::vector<PrescribedMotion> motions;
};

/// The bonds' intact stiffnesses (0 for a bond that came broken) and softening histories, in model
/// order: the run loop's, which the backends read and (the reference) update.
struct BondHistory {
  Eigen::ArrayXd intact[4];  ///< normal, shear, bending, twisting
  Eigen::ArrayXd kappa;      ///< largest utilisation so far (1 for a bond that never softened)
};

/// What a batch of cycles needs besides the state.
struct CycleStep {
  long first_cycle = 0;  ///< the integrator's number of the batch's first cycle
  double dt = 0;
  double alpha = 0;  ///< local damping
  /// Contacts between unbonded particles (null if none): a pass at every cycle.
  UnbondedContacts* contacts = nullptr;
};

/// What a batch of cycles did.
struct CycleBatch {
  long cycles = 0;        ///< run: fewer than asked when a cycle took a damage step (the last)
  bool reported = false;  ///< the last cycle reported: `sums` hold its report sums
  /// strain energy, sum of bond force magnitudes, 2 x kinetic energy, unbalanced force, and the
  /// account's second halves - F . v(n+1/2) (prescribed), damping . v(n+1/2) (free).
  double sums[kParticlePartials] = {};
  std::vector<SlotEvent> events;  ///< the damage steps of the last cycle (first ends)
};

/// The account's per-particle sums and the last contact forces, in model order (checkpoints).
struct AccountArrays {
  Eigen::ArrayXd work, damping;
  Vector3Array contact_force, contact_torque;
};

class KernelBackend {
 public:
  virtual ~KernelBackend() = default;
  virtual ExplicitBackend kind() const = 0;
  /// Whether the state lives apart from the model, in kernel order (all but the reference).
  virtual bool kernel_order() const = 0;
  /// Bytes the backend holds for a run besides the model (its state, tables, renumbering).
  virtual std::size_t bytes() const = 0;

  /// Replaces the prescribed motions (between runs or during one: from the next batch on).
  virtual void set_motions(const MotionTable& table) = 0;
  /// Bonds can break from now on: the breaking kernel, the account's sums, contact arrays.
  virtual void start_breaking(bool softening) = 0;
  /// Whether the backend runs contacts between unbonded particles; `why` gets the reason if not.
  virtual bool supports_contacts(std::string* why) const = 0;

  /// The model's state into the backend (the start of a run) and back (its end: displacements,
  /// rotations, velocities).
  virtual void load() = 0;
  virtual void store() = 0;
  /// Up to `cycles` cycles (>= 1); stops after the first cycle that took a damage step. The last
  /// cycle reports when `report_last` (and then writes the model's force and torque: the forces
  /// of the state before its update).
  virtual CycleBatch run_cycles(long cycles, bool report_last, const CycleStep& step) = 0;

  /// During a run: the listed model particles' displacement, rotation, velocity and angular
  /// velocity rows into `into` (StateAt::kForces: the state the last cycle's forces came from).
  virtual void gather(std::span<const int> particles, Particles& into, StateAt at) const = 0;
  /// During a run: model particle i's current displacement (or rotation) component c.
  virtual double state(int i, int c, bool rotation) const = 0;
  /// During a run: the current state as the contacts read it, and their numbering of the model's
  /// particles (index[i] = the array index of model particle i).
  virtual ContactState contact_state() const = 0;
  virtual std::vector<int> contact_index() const = 0;
  /// After a contact pass restored from a checkpoint: the particles its forces touch.
  virtual void touch_contacts(const std::vector<int>& touched) = 0;

  /// Breaks bond b by hand (its slots emptied), from the next cycle on.
  virtual void clear_bond(int bond) = 0;
  virtual std::array<BondEnd, 2> bond_ends(int bond) const = 0;
  /// The bonds as the backend holds them, written into `bonds` and `kappa` (damage and stiffness
  /// of softened bonds); throws plydem::Error if the two ends of a bond disagree.
  virtual void store_bonds(Bonds& bonds, Eigen::ArrayXd& kappa) const = 0;
  /// From a checkpoint: the bonds broken since the table was built, the softening histories.
  virtual void restore_bonds(const Bonds& bonds, const Eigen::ArrayXd& kappa) = 0;

  virtual AccountArrays account() const = 0;
  virtual void set_account(const AccountArrays& account) = 0;
  /// On N ranks, how the particles are shared (solvers/rank_exchange.hpp); null on one.
  virtual const RankPartition* partition() const { return nullptr; }
};

/// What a backend is built on: the model (which outlives it), the bonds' history (the run loop's,
/// which outlives it too), and how the kernel is laid out.
struct BackendSetup {
  Model* model = nullptr;
  BondHistory* history = nullptr;
  bool breaking = false;
  bool softening = false;
  StrengthStorage strength_storage = StrengthStorage::kAutomatic;
  ParticleOrder particle_order = ParticleOrder::kAutomatic;
  /// Under mpiexec -n N (N > 1): each rank runs its share of the particles (the cpu and
  /// reference backends, solvers/rank_exchange.hpp); false: every rank runs the whole model.
  bool split_between_ranks = false;
};

/// The backend `kind` on `setup`. Throws plydem::Error when it cannot run here (cuda: naming why).
std::unique_ptr<KernelBackend> make_kernel_backend(ExplicitBackend kind, const BackendSetup& setup);

/// The reference backend, the host's SIMD backend, and a kernel-order backend mirrored on a device.
std::unique_ptr<KernelBackend> make_reference_backend(const BackendSetup& setup);
std::unique_ptr<KernelBackend> make_cpu_backend(const BackendSetup& setup);
std::unique_ptr<KernelBackend> make_mirrored_backend(const BackendSetup& setup,
                                                     ExplicitBackend kind);

}  // namespace plydem
