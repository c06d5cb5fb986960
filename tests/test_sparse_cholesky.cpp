// The supernodal Cholesky factorization against Eigen's simplicial LDL^T and dense solves: the
// same pivots in the same order, the same solutions, and one zero pivot per independent null
// vector of a positive semi-definite matrix.
#include <doctest/doctest.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <random>

#include "solvers/sparse_cholesky.hpp"

using namespace plydem;

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

// A positive semi-definite "lattice" matrix: an n x n grid of nodes with `dofs` dofs each, every
// pair of neighbours (and every diagonal pair with probability 1/2) coupled by a random element
// B^T B with B of rank `rank` < 2 dofs; plus `shift` on the diagonal. Nodes are numbered in a
// random order, so the symbolic analysis sees an irregular pattern.
SparseMatrix lattice_matrix(int n, int dofs, int rank, double shift, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<int> label(n * n);
  for (int i = 0; i < n * n; ++i) label[i] = i;
  std::shuffle(label.begin(), label.end(), rng);
  std::vector<Eigen::Triplet<double>> t;
  auto element = [&](int a, int b) {
    Eigen::MatrixXd bm(rank, 2 * dofs);
    for (int r = 0; r < rank; ++r)
      for (int c = 0; c < 2 * dofs; ++c) bm(r, c) = g(rng);
    const Eigen::MatrixXd e = bm.transpose() * bm;
    const int node[2] = {label[a], label[b]};
    for (int p = 0; p < 2; ++p)
      for (int q = 0; q < 2; ++q)
        for (int i = 0; i < dofs; ++i)
          for (int j = 0; j < dofs; ++j)
            if (dofs * node[p] + i >= dofs * node[q] + j)
              t.emplace_back(dofs * node[p] + i, dofs * node[q] + j, e(dofs * p + i, dofs * q + j));
  };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      if (x + 1 < n) element(y * n + x, y * n + x + 1);
      if (y + 1 < n) element(y * n + x, (y + 1) * n + x);
      if (x + 1 < n && y + 1 < n && rng() % 2) element(y * n + x, (y + 1) * n + x + 1);
    }
  for (int i = 0; i < dofs * n * n; ++i) t.emplace_back(i, i, shift);
  SparseMatrix a(dofs * n * n, dofs * n * n);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

}  // namespace

TEST_CASE("supernodal Cholesky: Eigen's LDL^T pivots and solutions on positive definite matrices") {
  for (unsigned seed : {1u, 2u, 3u}) {
    CAPTURE(seed);
    const SparseMatrix a = lattice_matrix(12, 3, 4, 0.1, seed);
    SupernodalCholesky cholesky;
    cholesky.analyze(a);
    cholesky.factorize(a, 1e-12);
    CHECK(cholesky.zero_pivots().empty());
    CHECK(cholesky.supernode_count() < a.cols());
    // Same order (natural), so the same pivots: LDL^T pivots are unique for an order.
    Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::NaturalOrdering<int>> reference(a);
    REQUIRE(reference.info() == Eigen::Success);
    const Eigen::VectorXd d = reference.vectorD();
    CHECK((cholesky.pivots() - d).cwiseAbs().maxCoeff() < 1e-10 * d.cwiseAbs().maxCoeff());
    Eigen::MatrixXd b = Eigen::MatrixXd::Random(a.rows(), 3);
    const Eigen::MatrixXd expected = reference.solve(b);
    cholesky.solve_in_place(b);
    CHECK((b - expected).norm() < 1e-10 * expected.norm());
  }
}

TEST_CASE("supernodal Cholesky: one zero pivot per null vector, and the solution on the rest") {
  // A graph Laplacian (one dof per node, unit springs) of a 10 x 10 grid cut into two halves, and
  // a third part of one isolated node: its null space is the constant vector on each part, so 3
  // zero pivots; a right-hand side summing to zero on each part has exact solutions.
  const int n = 10;
  std::vector<Eigen::Triplet<double>> t;
  auto spring = [&](int i, int j) {
    t.emplace_back(i, i, 1.0);
    t.emplace_back(j, j, 1.0);
    t.emplace_back(std::max(i, j), std::min(i, j), -1.0);
  };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int i = y * n + x;
      if (x + 1 < n && x + 1 != n / 2) spring(i, i + 1);
      if (y + 1 < n) spring(i, i + n);
    }
  const int isolated = n * n;
  t.emplace_back(isolated, isolated, 0.0);
  SparseMatrix a(n * n + 1, n * n + 1);
  a.setFromTriplets(t.begin(), t.end());
  SupernodalCholesky cholesky;
  cholesky.analyze(a);
  cholesky.factorize(a, 1e-10);
  CHECK(cholesky.zero_pivots().size() == 3);
  CHECK(std::find(cholesky.zero_pivots().begin(), cholesky.zero_pivots().end(), isolated) !=
        cholesky.zero_pivots().end());

  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd b(n * n + 1);
  for (int i = 0; i < n * n + 1; ++i) b(i) = g(rng);
  double left = 0, right = 0;
  for (int i = 0; i < n * n; ++i) (i % n < n / 2 ? left : right) += b(i);
  for (int i = 0; i < n * n; ++i) b(i) -= (i % n < n / 2 ? left : right) / (n * n / 2);
  b(isolated) = 0;
  Eigen::VectorXd x = b;
  cholesky.solve_in_place(x);
  const Eigen::VectorXd residual = a.selfadjointView<Eigen::Lower>() * x - b;
  CHECK(residual.norm() < 1e-12 * b.norm());
  for (int z : cholesky.zero_pivots()) CHECK(x(z) == 0);
}

TEST_CASE("supernodal Cholesky counts the floating-point operations of its factorization") {
  // A dense matrix is one supernode of n columns: n^3 / 3.
  const int n = 30;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Random(n, n);
  dense = dense * dense.transpose() + n * Eigen::MatrixXd::Identity(n, n);
  const SparseMatrix full = dense.sparseView();
  const SparseMatrix lower = full.triangularView<Eigen::Lower>();
  SupernodalCholesky one;
  one.analyze(lower);
  CHECK(one.supernode_count() == 1);
  CHECK(one.factor_flops() == doctest::Approx(n * n * n / 3.0));
  // A diagonal matrix: one operation per pivot, however it is grouped.
  const SparseMatrix diagonal =
      Eigen::VectorXd::Constant(n, 2.0).asDiagonal().toDenseMatrix().sparseView();
  SupernodalCholesky none;
  none.analyze(diagonal);
  CHECK(none.factor_flops() == doctest::Approx(n / 3.0).epsilon(1.0));
  // Larger and denser fronts cost more: a finer grid of the same lattice takes more per unknown.
  SupernodalCholesky small, large;
  const SparseMatrix a = lattice_matrix(8, 3, 4, 0.1, 1), b = lattice_matrix(16, 3, 4, 0.1, 1);
  small.analyze(a);
  large.analyze(b);
  CHECK(small.factor_flops() > small.factor_entries());
  CHECK(large.factor_flops() / b.rows() > small.factor_flops() / a.rows());
}
