#pragma once
/// \file
/// The sparse direct solvers of the static solve behind one interface: factor a symmetric positive
/// (semi-)definite matrix once, then solve with it for as many right-hand sides as needed. The
/// static solver (solvers/static_solver.hpp) factors K_ff through it, and StaticSystem reuses one
/// factor for every solve with the same matrix and prescribed dofs (the specimen stiffness' three
/// strain cases, experiments/protocols/stiffness_test.cpp).
///
/// Two implementations:
/// - kDirect: plydem's own supernodal multifrontal Cholesky (solvers/sparse_cholesky.hpp), in the
///   order the matrix is given (the static solver orders particles with AMD);
/// - kCholmod: CHOLMOD (SuiteSparse), supernodal LL^T, with the fill-reducing order CHOLMOD
///   chooses itself (AMD, METIS where AMD fills in much, on the dofs).
/// kAuto chooses after the hand-written solver's symbolic analysis, which costs little: CHOLMOD
/// where the factor fills in densely (more than kAutoCholmodFill entries per unknown, as in a
/// stacked laminate, whose factor is a band the width of its cross-section) and CHOLMOD's BLAS
/// is an optimized one (OpenBLAS); the hand-written one otherwise. Measured on one thread
/// (README, Benchmarks): on single plies (64-100 entries per unknown) the hand-written solver is
/// as fast or faster at every size; on the [0/45/-45/90]s coupon (880 per unknown) CHOLMOD with
/// METIS and OpenBLAS is 2.4x faster, while with the reference BLAS it is 2x slower.
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
  kAuto,    ///< by the fill of the factor and the BLAS (see the file comment)
  kDirect,  ///< SupernodalCholesky (solvers/sparse_cholesky.hpp)
  kCholmod  ///< CHOLMOD's supernodal Cholesky (SuiteSparse)
};

/// Entries of the hand-written factor per unknown above which kAuto factors with CHOLMOD.
inline constexpr double kAutoCholmodFill = 300;

/// "auto", "direct" or "cholmod".
const char* linear_solver_name(LinearSolverKind kind);
/// Parses "auto", "direct" or "cholmod". Throws plydem::Error for anything else, and says so
/// explicitly for "petsc", which is not built in (issue 15).
LinearSolverKind parse_linear_solver(std::string_view name);
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
  /// The unknowns whose pivot was zero, in the matrix's numbering, increasing; empty for a
  /// positive definite matrix.
  virtual const std::vector<int>& zero_pivots() const = 0;
  /// The LDL^T pivots, in the matrix's numbering (meaningful where zero_pivots() is not empty).
  virtual Eigen::VectorXd pivots() const = 0;
  /// Solves A X = B for every column of `b`, in place (zero at zero pivots).
  virtual void solve_in_place(Eigen::MatrixXd& b) const = 0;
  /// E.g. "supernodal Cholesky (AMD on particles)" or "CHOLMOD supernodal (METIS)"; kAuto's
  /// names the one it chose.
  virtual std::string name() const = 0;
  /// Stored entries of the factor L.
  virtual double factor_entries() const = 0;

  void solve_in_place(Eigen::VectorXd& b) const;
};

/// A solver of `kind`. The hand-written one and kAuto factor in the order the matrix is given
/// (give it a fill-reducing one); CHOLMOD orders it itself.
std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind);

}  // namespace plydem
