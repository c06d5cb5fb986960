#include "solvers/stiffness_assembly.hpp"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <numeric>
#include <utility>

#include "contacts/bond_kernel.hpp"
#include "core/parallel_bond.hpp"

namespace plydem {

EliminationOrder EliminationOrder::identity(int particles) {
  EliminationOrder o;
  o.order.resize(particles);
  std::iota(o.order.begin(), o.order.end(), 0);
  o.rank = o.order;
  return o;
}

EliminationOrder EliminationOrder::minimum_degree(const Model& model) {
  const int n = model.particles.size();
  const Bonds& bonds = model.bonds;
  std::vector<Eigen::Triplet<double>> edges;
  edges.reserve(bonds.size() + n);
  // Eigen's AMD orders the pattern of A + A^T; without the diagonal it returns the identity.
  for (int i = 0; i < n; ++i) edges.emplace_back(i, i, 1.0);
  for (int b = 0; b < bonds.size(); ++b) edges.emplace_back(bonds.second(b), bonds.first(b), 1.0);
  Eigen::SparseMatrix<double> graph(n, n);
  graph.setFromTriplets(edges.begin(), edges.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> permutation;
  Eigen::AMDOrdering<int>()(graph, permutation);
  EliminationOrder o;
  // Eigen's orderings return the inverse permutation: entry k is the k-th particle eliminated.
  o.order.assign(permutation.indices().data(), permutation.indices().data() + n);
  o.rank.assign(n, 0);
  for (int k = 0; k < n; ++k) o.rank[o.order[k]] = k;
  return o;
}

const double* BlockStiffness::block(int column, int row) const {
  const auto first = neighbour.begin() + start[column];
  const auto last = neighbour.begin() + start[column + 1];
  return value.data() +
         36 * static_cast<std::size_t>(std::lower_bound(first, last, row) - neighbour.begin());
}

double* BlockStiffness::block(int column, int row) {
  return const_cast<double*>(std::as_const(*this).block(column, row));
}

Eigen::MatrixXd BlockStiffness::multiply(const Eigen::MatrixXd& x) const {
  using Block6 = Eigen::Map<const Eigen::Matrix<double, 6, 6>>;
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(x.rows(), x.cols());
  for (int c = 0; c < particles(); ++c)
    for (int slot = start[c]; slot < start[c + 1]; ++slot) {
      const int r = neighbour[slot];
      const Block6 k(value.data() + 36 * static_cast<std::size_t>(slot));
      y.middleRows<6>(6 * r).noalias() += k * x.middleRows<6>(6 * c);
      if (r != c) y.middleRows<6>(6 * c).noalias() += k.transpose() * x.middleRows<6>(6 * r);
    }
  return y;
}

BlockStiffness block_stiffness(const Model& model, const EliminationOrder& order,
                               const std::vector<char>* rows) {
  const int n = model.particles.size();
  const Bonds& bonds = model.bonds;
  const std::vector<int>& rank = order.rank;
  // Whether bond b's blocks between its particles are kept (all but the diagonal ones are left
  // out for a bond that reaches no flagged particle).
  auto coupled = [&](int b) {
    return !rows || (*rows)[static_cast<std::size_t>(bonds.first(b))] ||
           (*rows)[static_cast<std::size_t>(bonds.second(b))];
  };
  // Pattern: for each column rank, itself and the larger ranks bonded to it (compressed rows,
  // counted first: no vector per particle).
  BlockStiffness k;
  std::vector<int> begin(n + 1, 0);
  for (int b = 0; b < bonds.size(); ++b)
    if (coupled(b)) ++begin[std::min(rank[bonds.first(b)], rank[bonds.second(b)]) + 1];
  for (int c = 0; c < n; ++c) begin[c + 1] += begin[c] + 1;  // + 1: the diagonal block
  std::vector<int> entries(begin[n]);
  std::vector<int> cursor(begin.begin(), begin.end() - 1);
  for (int c = 0; c < n; ++c) entries[cursor[c]++] = c;
  for (int b = 0; b < bonds.size(); ++b) {
    if (!coupled(b)) continue;
    const int ri = rank[bonds.first(b)], rj = rank[bonds.second(b)];
    entries[cursor[std::min(ri, rj)]++] = std::max(ri, rj);
  }
  k.start.assign(n + 1, 0);
  k.neighbour.reserve(entries.size());
  for (int c = 0; c < n; ++c) {
    const auto first = entries.begin() + begin[c], last = entries.begin() + begin[c + 1];
    std::sort(first, last);
    k.neighbour.insert(k.neighbour.end(), first, std::unique(first, last));
    k.start[c + 1] = static_cast<int>(k.neighbour.size());
  }
  k.value.assign(36 * k.neighbour.size(), 0.0);

  for (int b = 0; b < bonds.size(); ++b) {
    const Matrix12d full = parallel_bond_stiffness(bond_parameters(bonds, b));
    // B^T D B is symmetric up to rounding; make it exactly so (the solvers read one triangle).
    const Matrix12d sym = 0.5 * (full + full.transpose());
    const int r[2] = {rank[bonds.first(b)], rank[bonds.second(b)]};
    const bool between = coupled(b);
    for (int cb = 0; cb < 2; ++cb)
      for (int rb = 0; rb < 2; ++rb) {
        if (r[rb] < r[cb]) continue;  // upper triangle: the transpose of a stored block
        if (rb != cb && !between) continue;
        double* v = k.block(r[cb], r[rb]);
        for (int c = 0; c < 6; ++c)
          for (int i = 0; i < 6; ++i) v[6 * c + i] += sym(6 * rb + i, 6 * cb + c);
      }
  }
  return k;
}

Eigen::SparseMatrix<double> compress_lower(const BlockStiffness& k,
                                           const std::vector<int>& free_index, int size,
                                           const Eigen::VectorXd& scale) {
  const int n = k.particles();
  // Two passes, counting then filling the matrix's own arrays: no growing vectors, no copy (in a
  // virtual machine the page faults of large fresh buffers cost more than the arithmetic).
  // Columns come in increasing order (free_index increases with the dof) and so do rows within a
  // column (increasing neighbour ranks, then components): the result is a valid compressed matrix.
  Eigen::SparseMatrix<double> out(size, size);
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Index entries = 0;
    for (int c = 0; c < n; ++c)
      for (int j = 0; j < 6; ++j) {
        const int column = free_index[6 * c + j];
        if (column < 0) continue;
        for (int slot = k.start[c]; slot < k.start[c + 1]; ++slot) {
          const int r = k.neighbour[slot];
          const double* v = k.value.data() + 36 * static_cast<std::size_t>(slot) + 6 * j;
          for (int i = 0; i < 6; ++i) {
            const int row = free_index[6 * r + i];
            if (row < column || v[i] == 0) continue;  // row < 0 (not kept) included
            if (pass == 1) {
              out.innerIndexPtr()[entries] = row;
              out.valuePtr()[entries] = scale(row) * v[i] * scale(column);
            }
            ++entries;
          }
        }
        if (pass == 1) out.outerIndexPtr()[column + 1] = static_cast<int>(entries);
      }
    if (pass == 0) out.resizeNonZeros(entries);
  }
  return out;
}

}  // namespace plydem
