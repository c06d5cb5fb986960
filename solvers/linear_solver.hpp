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
/// kAuto picks by size (linear_solver_for): the hand-written one up to kAutoDirectMaxDofs free
/// dofs, where it is as fast, CHOLMOD above (bench/static_bench, README "Benchmarks").
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
  kAuto,    ///< kDirect up to kAutoDirectMaxDofs unknowns, kCholmod above
  kDirect,  ///< SupernodalCholesky (solvers/sparse_cholesky.hpp)
  kCholmod  ///< CHOLMOD's supernodal Cholesky (SuiteSparse)
};

/// Largest system kAuto gives to the hand-written Cholesky (see README, Benchmarks).
inline constexpr int kAutoDirectMaxDofs = 50000;

/// "auto", "direct" or "cholmod".
const char* linear_solver_name(LinearSolverKind kind);
/// Parses "auto", "direct" or "cholmod". Throws plydem::Error for anything else, and says so
/// explicitly for "petsc", which is not built in (issue 15).
LinearSolverKind parse_linear_solver(std::string_view name);
/// The solver kAuto means for a system of `unknowns` (other kinds are returned as they are).
LinearSolverKind linear_solver_for(LinearSolverKind kind, int unknowns);

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
  /// E.g. "supernodal Cholesky (AMD on particles)" or "CHOLMOD supernodal (METIS)".
  virtual std::string name() const = 0;
  /// Stored entries of the factor L.
  virtual double factor_entries() const = 0;

  void solve_in_place(Eigen::VectorXd& b) const;
};

/// A solver of `kind` for a system of `unknowns` (kAuto resolved by linear_solver_for).
std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind, int unknowns);

}  // namespace plydem
