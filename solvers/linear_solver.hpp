#pragma once
/// \file
/// The sparse direct solvers of the static solve behind one interface: factor a symmetric positive
/// (semi-)definite matrix once, then solve with it for as many right-hand sides as needed. The
/// static solver (solvers/static_solver.hpp) factors K_ff through it, and StaticSystem reuses one
/// factor for every solve with the same matrix and prescribed dofs (the specimen stiffness' three
/// strain cases, experiments/protocols/stiffness.cpp).
///
/// Three implementations:
/// - kDirect: plydem's own supernodal multifrontal Cholesky (solvers/sparse_cholesky.hpp), in the
///   order the matrix is given (the static solver orders particles with AMD);
/// - kCholmod: CHOLMOD (SuiteSparse), supernodal LL^T, with the fill-reducing order CHOLMOD
///   chooses itself (AMD, METIS where AMD fills in much, on the dofs);
/// - kPetsc: PETSc's conjugate gradient preconditioned by its smoothed-aggregation algebraic
///   multigrid (GAMG), block size 6 (a particle's six dofs), with the six rigid-body modes of the
///   particles as near-null space, rotation dofs included (translation: u = e, theta = 0;
///   rotation: u = e x (x - x0), theta = e). Tuned as issue 15 measured it (threshold -1,
///   Chebyshev-Jacobi smoothing, relative tolerance 1e-12); any PETSc option overrides these
///   (set_petsc_options, `--petsc-options`). The hierarchy is built once by factor() and reused by
///   every solve. Under `mpiexec -n N` the matrix is a distributed PETSc matrix, each rank owning
///   a slice of the particles along the model's longest extent (see ParallelSession). Built when
///   PETSc is found (optional).
/// kAuto chooses by predicted time, from the entries and floating-point operations of the factor
/// in the order given, which CHOLMOD's column counts give before any numeric work at the cost of
/// a pass over the matrix (the solver taken then analyses it for itself; a hand-written analysis
/// first, to decide, took 0.3 s of each [0/45/-45/90]s solve that PETSc then made):
/// - memory first: where the direct factor with its workspace (on each MPI rank) would take more
///   than kAutoMemoryShare of the available memory, PETSc if it is built and the caller makes few
///   solves (LinearSolverUse::kFewSolves: a tension pull, the specimen stiffness' three); else it
///   refuses, with the estimate (not built, or kManySolves: the events solver,
///   solvers/bond_events.hpp, updates the factor by Woodbury's identity, many solves that want a
///   direct factor), unless forced;
/// - a factorization of at most kAutoSmallFactorFlops is the hand-written one's (a fraction of a
///   second on any machine: single plies up to about 10^4 particles, the default job);
/// - otherwise the solver of the least time predict_linear_solvers gives for this factor and
///   the caller's number of solves (StaticSettings::expected_solves), on this machine's rates
///   (solvers/machine_rates.hpp: its BLAS, Eigen's kernels and memory, measured at first use and
///   cached per machine), among the hand-written factor, CHOLMOD, and PETSc where it may take
///   few solves. The model and its constants were fitted to bench/static_solve's runs of the
///   paper's plies and laminates with both Debian BLAS (bench/README.md, "Static solves with
///   PETSc"); LinearSolver::choice() says what was predicted.
///
/// Zero pivots. Both report the same diagnosis: the dofs whose LDL^T pivot is at or below
/// `pivot_tolerance` times their diagonal entry (sparse_cholesky.hpp). CHOLMOD stops at the first
/// non-positive pivot, and its pivots belong to another order; when it finds a pivot that small,
/// the matrix is factored again by the hand-written solver, whose one pass names every zero pivot,
/// so that a mechanism is reported the same way whichever solver ran.

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace plydem {

enum class LinearSolverKind {
  kAuto,     ///< by the fill of the factor and the BLAS (see the file comment)
  kDirect,   ///< SupernodalCholesky (solvers/sparse_cholesky.hpp)
  kCholmod,  ///< CHOLMOD's supernodal Cholesky (SuiteSparse)
  kPetsc     ///< PETSc CG + GAMG with the rigid-body near-null space (needs petsc_available())
};

/// Floating-point operations of the hand-written factorization up to which kAuto takes it
/// without pricing the others (about 0.3 s on the development VM's Eigen kernels; the paper's
/// single ply takes 1.1e8, its [0/45/-45/90]s laminate 1.6e11).
inline constexpr double kAutoSmallFactorFlops = 2e9;
/// The share of the available memory (core/machine_memory.hpp) a direct factor may take under
/// kAuto; above it kAuto takes PETSc (few solves) or refuses with the estimate.
inline constexpr double kAutoMemoryShare = 0.8;
/// The multifrontal workspace beside a direct factor, as a fraction of it (hcp: about 0.4
/// measured; experiments/protocols/resource_estimate.hpp).
inline constexpr double kDirectFactorWorkspace = 0.5;
/// Bytes of a direct factor of `factor_entries` entries with its workspace.
double direct_factor_bytes(double factor_entries);

/// How many solves a caller makes with one factor(): kAuto picks an iterative solver (PETSc) only
/// for few (a static solve, the specimen stiffness' three), never for the events solver, whose
/// Woodbury updates solve with the factor for every column of every change.
enum class LinearSolverUse { kFewSolves, kManySolves };

/// "auto", "direct", "cholmod" or "petsc".
const char* linear_solver_name(LinearSolverKind kind);
/// Parses "auto", "direct", "cholmod" or "petsc". Throws plydem::Error for anything else, and for
/// "petsc" in a build without PETSc.
LinearSolverKind parse_linear_solver(std::string_view name);
/// Whether this build has PETSc (found at configure time, not in the sanitizer build).
bool petsc_available();
/// Adds PETSc options (e.g. "-ksp_rtol 1e-10 -pc_type hypre") to PETSc's options database, read
/// by every later kPetsc factor(); they override plydem's defaults (file comment). Throws
/// plydem::Error without PETSc or for options PETSc cannot parse.
void set_petsc_options(const std::string& options);

/// PETSc and MPI for the life of a program (construct first thing in main): initializes them with
/// the program's arguments, finalizes them at the end. Without PETSc, or without this object,
/// there is one rank. Under `mpiexec -n N`, every rank runs the whole program on the same input
/// (model building and the right-hand sides are replicated, deterministically); where PETSc
/// solves, each rank assembles only the rows of its own slice of particles (rank_particles) and
/// hands them to PETSc, which distributes the matrix, the AMG hierarchy and the CG iterations,
/// and gathers the solution back to every rank. The explicit engine splits the particles between
/// the ranks likewise (solvers/rank_exchange.hpp). Only rank 0 should print (is_root()).
class ParallelSession {
 public:
  ParallelSession(int* argc, char*** argv);
  ~ParallelSession();
  ParallelSession(const ParallelSession&) = delete;
  ParallelSession& operator=(const ParallelSession&) = delete;
};
/// This process' rank and the number of ranks (0 and 1 without an MPI run).
int mpi_rank();
int mpi_size();
inline bool is_root() {
  return mpi_rank() == 0;
}
/// The particles whose rows of a kPetsc matrix this rank hands to PETSc (1 = its own), for a
/// caller that assembles only those rows (StaticSystem under mpiexec); `position` holds every
/// particle's reference position. Empty on one rank (every row is its own).
std::vector<char> rank_particles(const Eigen::Array<double, Eigen::Dynamic, 3>& position);
/// Every rank's `count` values summed, on every rank (nothing on one rank).
void sum_over_ranks(double* values, int count);

/// Where the unknowns of a static solve sit, for the solvers that build the rigid-body modes
/// (kPetsc): unknown k is dof `dofs[k]` = 6 * particle + component (increasing), its value is
/// the physical one divided by `scale[k]` (the static solver's Jacobi scaling); `position` holds
/// every particle's reference position [m].
struct UnknownLayout {
  std::vector<int> dofs;
  Eigen::VectorXd scale;
  Eigen::Array<double, Eigen::Dynamic, 3> position;
  /// The matrix is positive definite by construction (StaticSystem: the bonds let each bonded
  /// cluster move freely only as a rigid body, see free_motions_are_rigid in static_solver.cpp,
  /// and each cluster's rigid modes are prescribed); kPetsc then skips its mechanism probe.
  bool positive_definite = false;
  /// The matrix holds only the rows of this MPI rank's particles (rank_particles) and their
  /// transposes: kPetsc reads no others, and names no mechanism (it needs the whole matrix).
  bool own_rows_only = false;
};
/// What kAuto knows of a matrix before it chooses (its factor counted in the order given), and how
/// it is used.
struct AutoProblem {
  double unknowns = 0;
  double nonzeros = 0;        ///< stored entries of the lower triangle
  double factor_entries = 0;  ///< of the factor in the order given (AMD on particles)
  double factor_flops = 0;    ///< of its factorization
  int solves = 1;             ///< with one factorization (StaticSettings::expected_solves)
  int ranks = 1;              ///< MPI ranks: PETSc distributes, a direct factor is every rank's
};
/// Predicted seconds of one factorization (PETSc: its setup) and problem.solves solves.
struct AutoPrediction {
  double direct = 0, cholmod = 0, petsc = 0;
};
struct MachineRates;
/// kAuto's model (linear_solver.cpp, fitted on the development VM): each factorization's
/// floating-point operations (counted in the order given, for CHOLMOD's own order too) at a share
/// of its kernel's rate, plus each solve streaming the factor; PETSc's setup and CG iterations
/// stream the matrix a fitted number of times, divided among the ranks.
AutoPrediction predict_linear_solvers(const AutoProblem& problem, const MachineRates& rates);

/// Whether the BLAS that CHOLMOD calls is an optimized one (OpenBLAS, found at run time: the
/// Debian alternative libblas.so.3 or LD_LIBRARY_PATH decide which one is loaded).
bool optimized_blas();

class LinearSolver {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double>;
  virtual ~LinearSolver() = default;

  /// Analysis and numeric factorization of the lower triangle `lower` (compressed column storage,
  /// every diagonal entry stored and positive, entries above the diagonal ignored). A pivot at or
  /// below `pivot_tolerance` times its diagonal entry is a zero pivot (see the file comment).
  /// Throws plydem::Error if the library fails (out of memory, say).
  virtual void factor(const SparseMatrix& lower, double pivot_tolerance) = 0;
  /// Tells the solver where the unknowns of the next factor() sit; the direct solvers ignore it,
  /// kPetsc needs it (it treats the unknowns as single dofs without it).
  virtual void set_layout(const UnknownLayout& /*layout*/) {}
  /// Krylov iterations of the last solve (0 for the direct solvers).
  virtual int iterations() const { return 0; }
  /// The unknowns whose pivot was zero, in the matrix's numbering, increasing; empty for a
  /// positive definite matrix.
  virtual const std::vector<int>& zero_pivots() const = 0;
  /// The LDL^T pivots, in the matrix's numbering (meaningful where zero_pivots() is not empty).
  virtual Eigen::VectorXd pivots() const = 0;
  /// Solves A X = B for every column of `b`, in place (zero at zero pivots).
  virtual void solve_in_place(Eigen::MatrixXd& b) const = 0;
  /// Solves A x = b with `x` as the first iterate of an iterative solver (kPetsc: its CG starts
  /// there, and stops at the same residual relative to b as from zero); a direct solver ignores
  /// it (x = A^-1 b exactly as solve_in_place). One column.
  virtual void solve_from(Eigen::VectorXd& x, const Eigen::VectorXd& b) const {
    x = b;
    solve_in_place(x);
  }
  /// E.g. "supernodal Cholesky (AMD on particles)" or "CHOLMOD supernodal (METIS)"; kAuto's
  /// names the one it chose.
  virtual std::string name() const = 0;
  /// Stored entries of the factor L.
  virtual double factor_entries() const = 0;
  /// Floating-point operations of the factorization (its symbolic analysis' count; 0 for PETSc).
  virtual double factor_flops() const { return 0; }
  /// kAuto's: what it chose and why ("chosen by auto: predicted ... against ..."); "" for the
  /// others.
  virtual std::string choice() const { return ""; }

  void solve_in_place(Eigen::VectorXd& b) const;
};

/// A solver of `kind`. The hand-written one and kAuto factor in the order the matrix is given
/// (give it a fill-reducing one); CHOLMOD orders it itself; kPetsc numbers the particles itself
/// (slices along the model's longest extent are the ranks' shares). Throws plydem::Error for kPetsc
/// without PETSc. `force`: kAuto factors even where the factor does not fit and PETSc cannot take
/// over. `expected_solves`: how many solves the caller makes with one factor() (kAuto's
/// prediction).
std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind,
                                                 LinearSolverUse use = LinearSolverUse::kFewSolves,
                                                 bool force = false, int expected_solves = 1);

}  // namespace plydem
