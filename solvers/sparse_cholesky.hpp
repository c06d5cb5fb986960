#pragma once
/// \file
/// Sparse Cholesky factorization A = L L^T of a symmetric positive semi-definite matrix,
/// supernodal and multifrontal: columns whose factor columns share one sparsity pattern are
/// factorized together as dense blocks with Eigen's dense kernels. On lattice stiffness matrices,
/// where every particle couples its dofs to its neighbours' as dense blocks, this is several times
/// faster than a column-by-column (simplicial) factorization such as Eigen::SimplicialLDLT. The
/// static solver (solvers/static_solver.hpp) and the periodic homogenization
/// (solvers/periodic_homogenization.hpp) solve with it.
///
/// Ordering. The matrix is factorized in the order it is given: the caller chooses a fill-reducing
/// order (plydem orders particles, not dofs, with AMD: see solvers/stiffness_assembly.hpp).
/// Internally the columns are renumbered by a postorder of the elimination tree, which changes no
/// fill but makes every supernode a contiguous range of columns.
///
/// Zero pivots. A pivot d_k (the pivot of the LDL^T form, L_kk^2) at or below tolerance * A_kk
/// means that dof k is not restrained by the dofs eliminated before it. The factorization records
/// the dof and goes on as if it were prescribed at zero (its row and column removed), and solve()
/// returns zero there. For a positive semi-definite A each such pivot (in exact arithmetic) belongs
/// to one independent null vector of A supported on the dofs eliminated up to it, so one pass
/// finds the whole null space: the number of zero pivots is its dimension, and for a right-hand
/// side orthogonal to it the solution with those dofs at zero is an exact solution.

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cstddef>
#include <memory>
#include <vector>

namespace plydem {

class SupernodalCholesky {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double>;

  /// Symbolic analysis of the lower triangle `lower` (compressed column storage, every diagonal
  /// entry stored, entries above the diagonal ignored).
  void analyze(const SparseMatrix& lower);
  /// Numeric factorization of a matrix with the pattern given to analyze(). A pivot at or below
  /// `pivot_tolerance` times its diagonal entry is a zero pivot (see the file comment).
  void factorize(const SparseMatrix& lower, double pivot_tolerance);

  /// The dofs whose pivot was zero, in the matrix's numbering, increasing.
  const std::vector<int>& zero_pivots() const { return zero_pivots_; }
  /// The LDL^T pivots d_k, in the matrix's numbering (before a zero pivot was discarded).
  Eigen::VectorXd pivots() const;
  /// Solves A X = B for every column of `b`, in place; dofs with a zero pivot get 0.
  void solve_in_place(Eigen::MatrixXd& b) const;
  void solve_in_place(Eigen::VectorXd& b) const;

  int size() const { return static_cast<int>(postorder_.size()); }
  int supernode_count() const { return static_cast<int>(first_column_.size()) - 1; }
  /// Stored entries of L (the dense supernode panels, diagonal blocks whole).
  Eigen::Index factor_entries() const { return panel_start_.empty() ? 0 : panel_start_.back(); }
  /// Floating-point operations of factorize(), from the analysis: for each supernode of k columns
  /// and m rows, the dense Cholesky of its k pivots, the triangular solve of the m - k rows below
  /// and the update of the parent's front, k^3 / 3 + k^2 (m - k) + k (m - k)^2.
  double factor_flops() const;

 private:
  // Symbolic: postorder_[old] = new column; original_[new] = old. Supernode s owns the columns
  // first_column_[s] .. first_column_[s + 1] - 1 and the rows rows_[row_start_[s] ..
  // row_start_[s + 1]) (its own columns first, then the rows below, increasing); its dense panel
  // (rows x own columns, column-major) starts at panel_start_[s]. Children: supernodes whose
  // parent is s, child_[child_start_[s] .. child_start_[s + 1]).
  std::vector<int> postorder_, original_;
  std::vector<int> first_column_, row_start_, rows_, child_start_, child_;
  std::vector<Eigen::Index> panel_start_;
  std::size_t largest_update_ = 1, stack_size_ = 1;  // factorization workspace [doubles]
  // Numeric.
  std::unique_ptr<double[]> panel_;
  std::vector<double> pivot_;  // in the new numbering
  std::vector<int> zero_pivots_;
  std::vector<char> is_zero_pivot_;  // in the new numbering

  // Steps of analyze() (sparse_cholesky.cpp).
  void find_children(const std::vector<int>& new_parent);
  void find_row_patterns(const SparseMatrix& lower, const std::vector<int>& expected_rows);
  void size_workspace(const std::vector<int>& expected_rows);
};

}  // namespace plydem
