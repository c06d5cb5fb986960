#pragma once
/// \file
/// Linear statics: the equilibrium of a Model under prescribed displacements and rotations, solved
/// in one sparse linear solve instead of thousands of damped explicit cycles.
///
/// The global stiffness is assembled from parallel_bond_stiffness (core/parallel_bond.hpp),
/// the same bond law the explicit kernel integrates, so a static solution is the state the damped
/// explicit run converges to (docs/tension-test.md, "How the tension test works"), up to
/// round-off. Each particle has six degrees of freedom (dofs), numbered
/// dof = 6 * particle + component with the components
/// ux uy uz theta_x theta_y theta_z (enum Dof). Every dof is either prescribed (DofConstraints) or
/// free; there are no external loads, so the free dofs satisfy
///   K_ff u_f = -K_fp u_p,
/// and the supports apply the reactions r = (K u)_p.
///
/// Rigid-body modes. The bond law is invariant under any rigid translation and infinitesimal
/// rotation, so each bonded cluster of particles has six zero-energy modes, and the constraints
/// must remove them all or K_ff is singular. A hex2d layer loaded in its plane is the usual trap:
/// its out-of-plane dofs (uz, theta_x, theta_y) decouple from the in-plane ones, so grips that
/// prescribe only ux leave translation along y and z and rotation about x and y free.
/// solve_static refuses such constraints with an error that names the free modes and the dofs
/// that would remove them; pin_rigid_modes (or StaticSettings::pin_rigid_modes) adds exactly those
/// constraints, at value zero. Because the model carries no external load, the pinned dofs then
/// carry zero reaction: pinning picks one of the equivalent solutions and changes no force.

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "solvers/linear_solver.hpp"

namespace plydem {

/// The components of a particle's six degrees of freedom, in the order of the global stiffness
/// matrix: dof = kDofsPerParticle * particle + component.
enum class Dof : int { kUx = 0, kUy = 1, kUz = 2, kThetaX = 3, kThetaY = 4, kThetaZ = 5 };
inline constexpr int kDofsPerParticle = 6;

/// "ux", "uy", "uz", "theta_x", "theta_y" or "theta_z".
const char* dof_name(Dof dof);

using DofArray = Eigen::Array<double, Eigen::Dynamic, kDofsPerParticle>;
using DofFlags = Eigen::Array<bool, Eigen::Dynamic, kDofsPerParticle>;

/// Which dofs are prescribed and their values: one row per particle, columns in Dof order
/// (translations in m, rotations in rad). A dof that is not fixed is free.
struct DofConstraints {
  DofFlags fixed;
  DofArray value;

  DofConstraints() = default;
  /// Constraints for `particles` particles, all free.
  explicit DofConstraints(int particles);

  /// Prescribes one dof.
  void fix(int particle, Dof dof, double value = 0);
  /// Prescribes all six dofs of a particle: displacement `u` [m] and rotation `theta` [rad].
  void fix_particle(int particle, const Eigen::Vector3d& u = Eigen::Vector3d::Zero(),
                    const Eigen::Vector3d& theta = Eigen::Vector3d::Zero());
  /// Prescribes `dof` of every particle in `group`; returns how many particles that was.
  int fix_group(const Particles& particles, BoundaryGroup group, Dof dof, double value = 0);
  /// Number of prescribed dofs.
  int prescribed_count() const;
};

/// One dof that pin_rigid_modes fixed (at zero).
struct PinnedDof {
  int particle = 0;
  Dof dof = Dof::kUx;
};

/// The fewest dofs to fix so that no cluster of bonded particles keeps a free rigid-body mode under
/// `constraints`: for each cluster, the rigid modes (3 translations, 3 rotations about its
/// centroid) that vanish on all its prescribed dofs, and one free dof per such mode, chosen
/// greedily for the best-conditioned choice (the far corners for rotations; for a lone translation,
/// the particle nearest the centroid). Empty when every rigid mode is already removed. Particles
/// without bonds are left alone (solve_static refuses them). Throws plydem::Error if `constraints`
/// does not match the model's size.
std::vector<PinnedDof> rigid_mode_pins(const Model& model, const DofConstraints& constraints);

/// Adds the constraints of rigid_mode_pins to `constraints`, each at value 0, and returns them.
std::vector<PinnedDof> pin_rigid_modes(const Model& model, DofConstraints& constraints);

/// The global stiffness matrix (6n x 6n, both triangles stored, exactly symmetric): the sum of
/// parallel_bond_stiffness over the bonds (each symmetrized, (K + K^T) / 2, to remove round-off).
/// The bonds' generalized forces are -K u with u = (u_0, theta_0, u_1, theta_1, ...). Exact zeros
/// are not stored (a layer in the x-y plane keeps its in-plane and out-of-plane blocks apart, so
/// the ordering sees that they are independent).
Eigen::SparseMatrix<double> assemble_stiffness(const Model& model);

enum class StaticMethod {
  kAuto,      ///< kDirect up to StaticSettings::direct_max_dofs free dofs, iterative above (PETSc
              ///< where built, see linear_solver_use; kIterative otherwise)
  kDirect,    ///< StaticSettings::linear_solver (solvers/linear_solver.hpp): sparse Cholesky, or
              ///< PETSc's CG + AMG (kPetsc), which likewise sets up once for many solves
  kIterative  ///< preconditioned conjugate gradient (Eigen::ConjugateGradient)
};

enum class StaticPreconditioner { kIncompleteCholesky, kDiagonal };

struct StaticSettings {
  StaticMethod method = StaticMethod::kAuto;
  /// Largest number of free dofs solved directly under kAuto. The direct solver's memory grows
  /// faster than the system (fill): measured on hex2d coupons of the paper's shape, 6e5 free dofs
  /// (1e5 particles) take 0.9 GiB and 6 s CPU, where CG takes 190 s; 1.8e6 free dofs take 2.9 GiB
  /// and 23 s (bench/static_solve).
  int direct_max_dofs = 2000000;
  /// The direct method's factorization: the hand-written supernodal Cholesky, CHOLMOD, or by size.
  LinearSolverKind linear_solver = LinearSolverKind::kAuto;
  /// Few solves per factor (kAuto may pick PETSc), or many (the events solver's updates: a direct
  /// factor always). With PETSc built, kFewSolves and linear_solver kAuto or kPetsc, the method
  /// kAuto solves above direct_max_dofs by PETSc's CG + AMG instead of Eigen's CG.
  LinearSolverUse linear_solver_use = LinearSolverUse::kFewSolves;
  /// How many solves the caller makes with one StaticSystem (a tension pull 1, the specimen
  /// stiffness 3): kAuto weighs a factorization, paid once, against the solves with it
  /// (solvers/linear_solver.hpp).
  int expected_solves = 1;
  /// Factor even where kAuto's symbolic analysis finds that the factor does not fit in the
  /// available memory and PETSc cannot take over (the user's --force); refused otherwise.
  bool force = false;
  StaticPreconditioner preconditioner = StaticPreconditioner::kIncompleteCholesky;
  /// Conjugate gradient stops when |A y - b| <= tolerance |b| on the Jacobi-scaled system.
  double cg_tolerance = 1e-13;
  /// Iteration cap of the conjugate gradient; 0 = twice the number of free dofs (Eigen's default).
  int cg_max_iterations = 0;
  /// A pivot (of the LDL^T form) of the Jacobi-scaled K_ff (unit diagonal) at or below
  /// pivot_tolerance * max(free dofs, 1000) is taken as zero: the free dofs are not restrained
  /// there. The round-off in a zero pivot grows with the size of the system (see the .cpp); this
  /// test is a heuristic for mechanisms, while free rigid-body modes are found exactly, from the
  /// geometry, before factorizing.
  double pivot_tolerance = 1e-12;
  /// Add the constraints of pin_rigid_modes instead of refusing free rigid-body modes.
  bool pin_rigid_modes = false;
};

/// Throws plydem::Error if a setting is out of range.
void validate(const StaticSettings& settings);

/// Whether the bonds let each bonded cluster of `model` move freely only as a rigid body (a
/// sufficient test from the bonds alone, see the .cpp): then, with the clusters' rigid modes
/// prescribed, the free-free stiffness is positive definite, and PETSc skips its mechanism probe.
/// False where it cannot tell (an intact bond with no normal or shear stiffness, point bonds at
/// collinear contacts, a piece that only broken bonds join to the rest of its cluster), not only
/// where there is a mechanism. Broken bonds count for nothing else: a cracked coupon whose intact
/// bonds still hold it together skips the probe (the coupled criterion's layer cracks, each
/// solved by PETSc afresh, bond_events.hpp).
bool free_motions_are_rigid(const Model& model);

/// Wall-clock seconds of each phase (std::chrono::steady_clock).
struct StaticTimings {
  double checks = 0;         ///< input checks and the rigid-mode analysis
  double assembly = 0;       ///< K, the free-free block, its scaling and the right-hand side
  double factorization = 0;  ///< Cholesky (ordering included), or the preconditioner for CG
  double solve = 0;          ///< triangular solves, or the CG iterations
  double total() const { return checks + assembly + factorization + solve; }
};

struct StaticResult {
  StaticMethod method = StaticMethod::kDirect;  ///< kDirect or kIterative, as used
  std::string method_name;                      ///< e.g. "supernodal Cholesky (AMD on particles)"
  /// What kAuto chose and why (LinearSolver::choice(): "chosen by auto: predicted ..."); "" for a
  /// solver the caller named.
  std::string linear_solver_choice;
  /// The factorization (or preconditioner) was made for an earlier solve of the same StaticSystem:
  /// `seconds` then holds this solve's right-hand side (assembly) and solve only.
  bool reused_factorization = false;
  double factor_entries = 0;  ///< stored entries of the Cholesky factor (0 for kIterative)
  double factor_flops = 0;    ///< floating-point operations of the factorization (0 without one)
  int dofs = 0;
  int free_dofs = 0;
  int prescribed_dofs = 0;              ///< pins included
  Eigen::Index stiffness_nonzeros = 0;  ///< in the lower triangle of K_ff
  /// Of them, the entries this MPI rank assembled (under mpiexec with PETSc, the rows of its own
  /// particles: linear_solver.hpp, rank_particles); stiffness_nonzeros on one rank.
  Eigen::Index rank_stiffness_nonzeros = 0;
  int iterations = 0;            ///< conjugate gradient iterations (0 for kDirect but with kPetsc)
  double relative_residual = 0;  ///< |A y - b| / |b| of the scaled free-free system
  double strain_energy = 0;      ///< of the solution [J]
  /// The generalized force each support applies to its particle [N, N m]: (K u) on prescribed
  /// dofs, 0 on free ones. It is taken from the kernel's forces at the solution (reaction =
  /// -particles.force / torque there), so it is the grip force an explicit run would report.
  DofArray reaction;
  std::vector<PinnedDof> pinned;  ///< dofs added by StaticSettings::pin_rigid_modes
  StaticTimings seconds;
};

/// Solves the linear static problem and writes the state into `model.particles`: displacement and
/// rotation (prescribed dofs get their values; the bonds' free offsets, Bonds::free_offset, are a
/// load: the forces they exert at zero displacement, strategies/cure_stress.hpp), and force and
/// torque as compute_bond_forces gives them (about zero on free dofs, minus the reaction on
/// prescribed ones), so that callers sum grip forces as after an explicit run. Velocities are left
/// as they were.
///
/// Throws plydem::Error, naming the cause, for: constraints of the wrong size or non-finite values;
/// a bond with a negative or non-finite stiffness (an unstable calibration); a particle with a free
/// dof and no bonds (it floats); a free dof with zero stiffness; a free rigid-body mode (unless
/// pin_rigid_modes, see the file comment); zero pivots of the direct factorization (a mechanism:
/// the bonds do not restrain some free dofs); a conjugate gradient that does not converge; a
/// non-finite solution. The iterative method cannot certify that K_ff is non-singular: a mechanism
/// that the right-hand side does not load converges to one of its solutions. A refused solve leaves
/// the model unchanged.
StaticResult solve_static(Model& model, const DofConstraints& constraints,
                          const StaticSettings& settings = {});

/// One stiffness matrix and set of prescribed dofs, factorized once and solved for any number of
/// prescribed values: solve_static is StaticSystem(model, constraints, settings).solve(model,
/// constraints.value). The constructor does the checks, the rigid-mode pins (from which dofs are
/// fixed, not their values), the assembly of K_ff and its factorization (or CG's preconditioner);
/// each solve() only builds the right-hand side -K_fp u_p and back-substitutes. The constructor
/// throws plydem::Error as solve_static does and leaves the model alone.
class StaticSystem {
 public:
  StaticSystem(const Model& model, const DofConstraints& constraints,
               const StaticSettings& settings = {});
  ~StaticSystem();
  StaticSystem(StaticSystem&&) noexcept;
  StaticSystem& operator=(StaticSystem&&) noexcept;

  /// Solves with the prescribed dofs at `values` (one row per particle, Dof columns; read only
  /// where the constructor's constraints fix a dof; pinned dofs stay at zero) and writes the state
  /// into `model`, as solve_static does. `model` must be the one the system was built from, or a
  /// copy of it (same particles and bonds; not checked beyond its size). An iterative solver (CG,
  /// kPetsc) starts from the model's current displacements and rotations, so that a caller's
  /// estimate of the solution (the specimen stiffness' affine field) saves iterations; a direct
  /// factor solves exactly whatever the state. Throws plydem::Error for values of the wrong size
  /// or non-finite ones, or (CG) no convergence.
  StaticResult solve(Model& model, const DofArray& values) const;
  /// The same with the bonds' free offsets as a load (what solve() does) or
  /// without them (false: the state's response to the prescribed values alone, whose sum with
  /// the offsets' own response is the state of both; the events solver's unit load).
  StaticResult solve(Model& model, const DofArray& values, bool with_free_offsets) const;

  /// Factorizations done (1 for the direct method once the constructor returned; 0 for CG) and
  /// solves so far.
  int factorizations() const;
  int solves() const;

  // For solvers that reuse the factor with their own right-hand sides (the events solver's
  // low-rank updates, solvers/bond_events.hpp).

  /// The constraints the system solves with: the constructor's and the rigid-mode pins (at zero).
  const DofConstraints& constraints() const;
  /// The free dofs, as solve_free_in_place numbers them: free_dofs()[f] = 6 * particle + component.
  const std::vector<int>& free_dofs() const;
  /// Solves K_ff X = B in place for every column of `b` (one row per free dof, in free_dofs()
  /// order), K_ff the free-free block of the stiffness the system was built from. Direct method
  /// only: throws plydem::Error for the iterative one (it keeps no factor) or for `b` of the wrong
  /// row count.
  void solve_free_in_place(Eigen::MatrixXd& b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The particles' displacements and rotations as one vector in dof order (6 * particle +
/// component: u_x, u_y, u_z, theta_x, theta_y, theta_z): a static solve's state as a vector.
Eigen::VectorXd particle_state_vector(const Particles& p);

}  // namespace plydem
