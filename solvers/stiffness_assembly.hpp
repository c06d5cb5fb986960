#pragma once
/// \file
/// The bonds' stiffness as 6x6 particle blocks, built from parallel_bond_stiffness
/// (core/parallel_bond.hpp), in a fill-reducing particle order, and its compression to the
/// sparse matrix of the dofs a solver keeps. The static solver (solvers/static_solver.hpp) and the
/// periodic homogenization (solvers/periodic_homogenization.hpp) assemble through these, so both
/// see exactly the bond law the explicit kernel integrates.
///
/// Dofs are numbered by rank: dof 6 * rank + component, where rank is the particle's position in
/// the order (EliminationOrder). Components are those of solvers/static_solver.hpp's Dof enum.

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cstddef>
#include <vector>

#include "core/model.hpp"

namespace plydem {

/// A permutation of the particles: order[rank] = particle, rank[particle] = its position.
struct EliminationOrder {
  std::vector<int> order;
  std::vector<int> rank;

  /// The particles in their given order.
  static EliminationOrder identity(int particles);
  /// A fill-reducing order for sparse Cholesky: approximate minimum degree (Eigen::AMDOrdering) on
  /// the graph of bonded particles. Ordering particles instead of dofs keeps each particle's dofs
  /// together (their blocks are dense) and orders a graph 36 times smaller.
  static EliminationOrder minimum_degree(const Model& model);
};

/// The lower block triangle of the stiffness in rank order: for each column rank c, the blocks
/// K(row rank r, c) with r >= c, including the diagonal block, each the sum of its bonds' blocks.
struct BlockStiffness {
  std::vector<int> start;      ///< blocks of column rank c: start[c] .. start[c + 1]
  std::vector<int> neighbour;  ///< row rank of each block, increasing (the first is c itself)
  std::vector<double> value;   ///< 36 per block, column-major: K(6 r + i, 6 c + j) at 6 j + i

  int particles() const { return static_cast<int>(start.size()) - 1; }
  /// The block K(row, column) for row >= column; the pair must be bonded (or the same particle).
  const double* block(int column, int row) const;
  double* block(int column, int row);
  /// The diagonal entry of dof (rank, component).
  double diagonal(int rank, int component) const { return block(rank, rank)[7 * component]; }
  /// K x for dof vectors in rank order (both triangles).
  Eigen::MatrixXd multiply(const Eigen::MatrixXd& x) const;
};

/// Sums parallel_bond_stiffness over the bonds (each made exactly symmetric, (K + K^T) / 2) into
/// blocks in the rank order of `order`. With `rows` (one flag per particle), the blocks between
/// two particles are those of the bonds that reach a flagged particle only: the rows of the
/// flagged particles are whole (every entry the same bits as without `rows`), the others are not,
/// and every diagonal block is whole (the solvers scale by the diagonal). A rank's share of a
/// distributed matrix (linear_solver.hpp, rank_particles).
BlockStiffness block_stiffness(const Model& model, const EliminationOrder& order,
                               const std::vector<char>* rows = nullptr);

/// The lower triangle of the matrix over the dofs d with free_index[d] >= 0 (in that numbering,
/// which must increase with the rank-ordered dof d), each entry times scale(row) scale(column).
/// Exact zeros are not stored: a layer in the x-y plane keeps its in-plane and out-of-plane blocks
/// apart, so that the factorization sees two independent problems.
Eigen::SparseMatrix<double> compress_lower(const BlockStiffness& k,
                                           const std::vector<int>& free_index, int size,
                                           const Eigen::VectorXd& scale);

}  // namespace plydem
