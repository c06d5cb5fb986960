#include "solvers/sparse_cholesky.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/progress.hpp"

namespace plydem {

namespace {

// The strictly lower entries of A by row: column[begin[i] .. begin[i + 1]) lists the columns
// j < i with A(i, j) stored.
struct RowPattern {
  std::vector<int> begin, column;
};

RowPattern strictly_lower_rows(const Eigen::SparseMatrix<double>& a) {
  const int n = static_cast<int>(a.cols());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  RowPattern rows;
  std::vector<int>& row_begin = rows.begin;
  row_begin.assign(n + 1, 0);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] > j) ++row_begin[inner[p] + 1];
  for (int i = 0; i < n; ++i) row_begin[i + 1] += row_begin[i];
  rows.column.resize(row_begin[n]);
  std::vector<int> cursor(row_begin.begin(), row_begin.end() - 1);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] > j) rows.column[cursor[inner[p]]++] = j;
  return rows;
}

// The elimination tree (parent, -1 at a root) and the number of entries below the diagonal in
// each column of L.
struct EliminationTree {
  std::vector<int> parent, count;
};

EliminationTree elimination_tree(const RowPattern& rows) {
  const int n = static_cast<int>(rows.begin.size()) - 1;
  const std::vector<int>& row_begin = rows.begin;
  const std::vector<int>& row_column = rows.column;
  EliminationTree tree;
  std::vector<int>& parent = tree.parent;
  std::vector<int>& count = tree.count;
  parent.assign(n, -1);
  count.assign(n, 0);
  std::vector<int> ancestor(n, -1), tag(n);
  for (int k = 0; k < n; ++k) {
    for (int p = row_begin[k]; p < row_begin[k + 1]; ++p) {
      for (int i = row_column[p]; i != -1 && i < k;) {
        const int next = ancestor[i];
        ancestor[i] = k;
        if (next == -1) parent[i] = k;
        i = next;
      }
    }
  }
  for (int k = 0; k < n; ++k) {
    tag[k] = k;
    for (int p = row_begin[k]; p < row_begin[k + 1]; ++p)
      for (int i = row_column[p]; tag[i] != k; i = parent[i]) {
        ++count[i];
        tag[i] = k;
      }
  }
  return tree;
}

// A postorder of the tree: postorder[old] = new column, original[new] = old. A child whose column
// continues its parent's supernode (same pattern below) is visited last, so that it ends up right
// before its parent.
void postorder_tree(const EliminationTree& tree, std::vector<int>& postorder,
                    std::vector<int>& original) {
  const std::vector<int>& parent = tree.parent;
  const std::vector<int>& count = tree.count;
  const int n = static_cast<int>(parent.size());
  std::vector<int> child_begin(n + 1, 0);
  for (int j = 0; j < n; ++j)
    if (parent[j] >= 0) ++child_begin[parent[j] + 1];
  for (int j = 0; j < n; ++j) child_begin[j + 1] += child_begin[j];
  std::vector<int> children(child_begin[n]);
  {
    std::vector<int> cursor(child_begin.begin(), child_begin.end() - 1);
    for (int j = 0; j < n; ++j)
      if (parent[j] >= 0) children[cursor[parent[j]]++] = j;
  }
  for (int j = 0; j < n; ++j) {
    const auto first = children.begin() + child_begin[j];
    const auto last = children.begin() + child_begin[j + 1];
    const auto chain = std::find_if(first, last, [&](int c) { return count[c] == count[j] + 1; });
    if (chain != last) std::rotate(chain, chain + 1, last);
  }
  postorder.assign(n, -1);
  original.assign(n, -1);
  int label = 0;
  std::vector<int> stack, next_child(child_begin.begin(), child_begin.end() - 1);
  for (int root = 0; root < n; ++root) {
    if (parent[root] != -1) continue;
    stack.push_back(root);
    while (!stack.empty()) {
      const int j = stack.back();
      if (next_child[j] < child_begin[j + 1]) {
        stack.push_back(children[next_child[j]++]);
      } else {
        stack.pop_back();
        original[label] = j;
        postorder[j] = label++;
      }
    }
  }
}

// The tree in the new numbering.
EliminationTree renumbered(const EliminationTree& tree, const std::vector<int>& postorder) {
  const int n = static_cast<int>(postorder.size());
  EliminationTree out;
  out.parent.resize(n);
  out.count.resize(n);
  for (int j = 0; j < n; ++j) {
    out.parent[postorder[j]] = tree.parent[j] < 0 ? -1 : postorder[tree.parent[j]];
    out.count[postorder[j]] = tree.count[j];
  }
  return out;
}

// Fundamental supernodes of the (postordered) tree, by first column, n appended: column j - 1
// joins column j when j is its parent and its pattern below the diagonal is j's pattern plus j.
std::vector<int> fundamental_supernodes(const EliminationTree& tree) {
  const std::vector<int>& new_parent = tree.parent;
  const std::vector<int>& new_count = tree.count;
  const int n = static_cast<int>(new_parent.size());
  std::vector<int> fundamental;
  for (int j = 0; j < n; ++j)
    if (j == 0 || !(new_parent[j - 1] == j && new_count[j - 1] == new_count[j] + 1))
      fundamental.push_back(j);
  fundamental.push_back(n);
  return fundamental;
}

// The supernodes after amalgamation: first columns (n appended) and each one's panel rows.
struct Supernodes {
  std::vector<int> first_column, rows;
};

// Relaxed amalgamation: a supernode merges into its parent when it ends right where the parent
// begins and the explicit zeros this adds to the dense panels stay few (CHOLMOD's default rule:
// always up to 4 columns, up to 16 with 80 % zeros, up to 48 with 10 %, any size with 5 %).
// Small supernodes waste the dense kernels: a particle's dofs alone make 3-column supernodes.
Supernodes amalgamate(const EliminationTree& tree, const std::vector<int>& fundamental) {
  const std::vector<int>& new_parent = tree.parent;
  const std::vector<int>& new_count = tree.count;
  const int n = static_cast<int>(new_parent.size());
  std::vector<int> column_owner(n);
  const int fundamental_count = static_cast<int>(fundamental.size()) - 1;
  for (int s = 0; s < fundamental_count; ++s)
    for (int j = fundamental[s]; j < fundamental[s + 1]; ++j) column_owner[j] = s;
  struct Group {
    int first, end, rows;  // columns first .. end - 1, rows of the panel
    double zeros;          // explicit zeros in the panel
    int merged_into = -1;
  };
  std::vector<Group> group(fundamental_count);
  for (int s = 0; s < fundamental_count; ++s)
    group[s] = {fundamental[s], fundamental[s + 1], new_count[fundamental[s]] + 1, 0.0};
  auto root_of = [&](int s) {
    while (group[s].merged_into >= 0) s = group[s].merged_into;
    return s;
  };
  for (int s = 0; s < fundamental_count; ++s) {
    const int up = new_parent[group[s].end - 1];
    if (up < 0) continue;
    const int p = root_of(column_owner[up]);
    Group& child = group[s];
    Group& par = group[p];
    if (child.end != par.first) continue;
    const int k_child = child.end - child.first, k = par.end - child.first;
    const int m = k_child + par.rows;
    const double zeros =
        child.zeros + par.zeros + static_cast<double>(k_child) * (k_child + par.rows - child.rows);
    const double fraction = zeros / (static_cast<double>(k) * m);
    if (k <= 4 || (k <= 16 && fraction <= 0.8) || (k <= 48 && fraction <= 0.1) ||
        fraction <= 0.05) {
      par.first = child.first;
      par.rows = m;
      par.zeros = zeros;
      child.merged_into = p;
    }
  }
  Supernodes out;
  for (int s = 0; s < fundamental_count; ++s)
    if (group[s].merged_into < 0) {
      out.first_column.push_back(group[s].first);
      out.rows.push_back(group[s].rows);
    }
  out.first_column.push_back(n);
  return out;
}

}  // namespace

// The symbolic analysis follows Davis, "Direct Methods for Sparse Linear Systems" (SIAM 2006):
// elimination tree (Liu's algorithm, sec. 4.1), column counts by traversing row subtrees (as
// Eigen's SimplicialCholesky does, sec. 4.2), postorder (sec. 4.3), and the multifrontal method
// with fundamental supernodes (sec. 9.1, 9.2).
void SupernodalCholesky::analyze(const SparseMatrix& a) {
  require(a.rows() == a.cols() && a.isCompressed(),
          "sparse Cholesky: the matrix must be square and compressed");
  const EliminationTree tree = elimination_tree(strictly_lower_rows(a));
  postorder_tree(tree, postorder_, original_);
  // Supernodes in the new numbering.
  const EliminationTree new_tree = renumbered(tree, postorder_);
  Supernodes supernodes = amalgamate(new_tree, fundamental_supernodes(new_tree));
  first_column_ = std::move(supernodes.first_column);
  find_children(new_tree.parent);
  find_row_patterns(a, supernodes.rows);
  size_workspace(supernodes.rows);
  panel_.reset();
  pivot_.clear();
  zero_pivots_.clear();
  is_zero_pivot_.clear();
}

// Supernode children (in increasing order: every child before its parent), from the parents of
// the columns in the new numbering.
void SupernodalCholesky::find_children(const std::vector<int>& new_parent) {
  const int n = static_cast<int>(new_parent.size());
  const int supernodes = supernode_count();
  std::vector<int> supernode_of(n);
  for (int s = 0; s < supernodes; ++s)
    for (int j = first_column_[s]; j < first_column_[s + 1]; ++j) supernode_of[j] = s;
  child_start_.assign(supernodes + 1, 0);
  std::vector<int> super_parent(supernodes, -1);
  for (int s = 0; s < supernodes; ++s) {
    const int up = new_parent[first_column_[s + 1] - 1];
    if (up >= 0) {
      super_parent[s] = supernode_of[up];
      ++child_start_[super_parent[s] + 1];
    }
  }
  for (int s = 0; s < supernodes; ++s) child_start_[s + 1] += child_start_[s];
  child_.assign(child_start_[supernodes], 0);
  std::vector<int> cursor(child_start_.begin(), child_start_.end() - 1);
  for (int s = 0; s < supernodes; ++s)
    if (super_parent[s] >= 0) child_[cursor[super_parent[s]]++] = s;
}

// Row patterns: a supernode's own columns, then the rows below from A and from its children;
// `expected_rows` (from the column counts) checks them.
void SupernodalCholesky::find_row_patterns(const SparseMatrix& a,
                                           const std::vector<int>& expected_rows) {
  const int n = static_cast<int>(a.cols());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const int supernodes = supernode_count();
  std::size_t total = 0;
  for (int s = 0; s < supernodes; ++s) total += static_cast<std::size_t>(expected_rows[s]);
  rows_.clear();
  rows_.reserve(total);
  row_start_.assign(1, 0);
  panel_start_.assign(1, 0);
  std::vector<int> mark(n, -1);
  for (int s = 0; s < supernodes; ++s) {
    const int f = first_column_[s], e = first_column_[s + 1];
    for (int j = f; j < e; ++j) rows_.push_back(j);
    const std::size_t below = rows_.size();
    auto add = [&](int r) {
      if (r >= e && mark[r] != s) {
        mark[r] = s;
        rows_.push_back(r);
      }
    };
    for (int j = f; j < e; ++j) {
      const int old = original_[j];
      for (int p = outer[old]; p < outer[old + 1]; ++p)
        if (inner[p] > old) add(postorder_[inner[p]]);
    }
    for (int c = child_start_[s]; c < child_start_[s + 1]; ++c) {
      const int ch = child_[c];
      const int width = first_column_[ch + 1] - first_column_[ch];
      for (int p = row_start_[ch] + width; p < row_start_[ch + 1]; ++p) add(rows_[p]);
    }
    std::sort(rows_.begin() + static_cast<std::ptrdiff_t>(below), rows_.end());
    const int m = static_cast<int>(rows_.size()) - row_start_.back();
    if (m != expected_rows[s])
      throw Error(
          fmt::format("sparse Cholesky: internal error, supernode {} has {} rows where the "
                      "column counts give {}",
                      s, m, expected_rows[s]));
    row_start_.push_back(static_cast<int>(rows_.size()));
    panel_start_.push_back(panel_start_.back() + static_cast<Eigen::Index>(m) * (e - f));
  }
}

// Workspace of the factorization: the largest update matrix, and the most that the stack of
// pending updates holds at once (children wait until their parent is assembled).
void SupernodalCholesky::size_workspace(const std::vector<int>& expected_rows) {
  largest_update_ = 1;
  stack_size_ = 1;
  std::size_t depth = 0;
  std::vector<std::size_t> pending;
  for (int s = 0; s < supernode_count(); ++s) {
    const int children = child_start_[s + 1] - child_start_[s];
    for (int c = 0; c < children; ++c) {
      depth -= pending.back();
      pending.pop_back();
    }
    const std::size_t mu = static_cast<std::size_t>(expected_rows[s]) -
                           static_cast<std::size_t>(first_column_[s + 1] - first_column_[s]);
    pending.push_back(mu * mu);
    depth += mu * mu;
    largest_update_ = std::max(largest_update_, mu * mu);
    stack_size_ = std::max(stack_size_, depth);
  }
}

namespace {

// Column-by-column (left-looking) Cholesky of the k columns of an m x k panel, with the zero-pivot
// rule of the file comment; returns the pivots through `pivot` and flags through `is_zero`.
void factor_columns_carefully(Eigen::Ref<Eigen::MatrixXd> front, int k, const double* diagonal,
                              double tolerance, double* pivot, char* is_zero) {
  const Eigen::Index m = front.rows();
  for (int c = 0; c < k; ++c) {
    if (c > 0)
      front.col(c).segment(c, m - c).noalias() -=
          front.block(c, 0, m - c, c) * front.row(c).head(c).transpose();
    const double d = front(c, c);
    pivot[c] = d;
    if (!(d > tolerance * diagonal[c])) {
      is_zero[c] = 1;
      front.col(c).segment(c, m - c).setZero();
      front(c, c) = 1;
    } else {
      const double l = std::sqrt(d);
      front(c, c) = l;
      front.col(c).segment(c + 1, m - c - 1) /= l;
    }
  }
}

}  // namespace

void SupernodalCholesky::factorize(const SparseMatrix& a, double pivot_tolerance) {
  const int n = size();
  require(a.rows() == n && a.cols() == n && a.isCompressed(),
          "sparse Cholesky: factorize() needs the analysed matrix");
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  const int supernodes = supernode_count();

  // Each supernode's panel (its k columns of the front) is assembled and factorized in place;
  // the rest of the front, the update for the parent, in `update` (lower triangle). Updates wait
  // on a stack: in postorder a supernode's children are the last ones pushed. Buffers are not
  // value-initialized: every entry read is written first.
  panel_.reset(new double[static_cast<std::size_t>(factor_entries())]);
  const std::unique_ptr<double[]> update_buffer(new double[largest_update_]);
  const std::unique_ptr<double[]> stack(new double[stack_size_]);
  std::vector<std::size_t> stack_top;  // where each pending update starts
  std::size_t stack_end = 0;
  pivot_.assign(n, 0.0);
  is_zero_pivot_.assign(n, 0);
  zero_pivots_.clear();
  std::vector<int> local(n, 0), map;
  std::vector<double> diagonal;
  Eigen::MatrixXd saved;
  // Progress by the supernodes' share of the work, k m^2 each (panel k columns, front m rows).
  auto work_of = [&](int s) {
    const double k = first_column_[s + 1] - first_column_[s];
    const double m = row_start_[s + 1] - row_start_[s];
    return k * m * m;
  };
  double total_work = 0, work_done = 0;
  for (int s = 0; s < supernodes; ++s) total_work += work_of(s);
  ProgressMeter meter(fmt::format("factorizing K ({} unknowns, {:.3g} factor entries)", n,
                                  static_cast<double>(factor_entries())),
                      total_work, "");
  for (int s = 0; s < supernodes; ++s) {
    meter.update(work_done);
    work_done += work_of(s);
    const int f = first_column_[s], k = first_column_[s + 1] - f;
    const int* rows = rows_.data() + row_start_[s];
    const int m = row_start_[s + 1] - row_start_[s], mu = m - k;
    for (int r = 0; r < m; ++r) local[rows[r]] = r;

    // The front: A's columns of this supernode, plus the children's updates.
    Eigen::Map<Eigen::MatrixXd> panel(panel_.get() + panel_start_[s], m, k);
    Eigen::Map<Eigen::MatrixXd> update(update_buffer.get(), mu, mu);
    panel.setZero();
    for (int c = 0; c < mu; ++c) update.col(c).tail(mu - c).setZero();
    diagonal.assign(k, 0.0);
    for (int c = 0; c < k; ++c) {
      const int old = original_[f + c];
      for (int p = outer[old]; p < outer[old + 1]; ++p) {
        if (inner[p] < old) continue;
        panel(local[postorder_[inner[p]]], c) += value[p];
        if (inner[p] == old) diagonal[c] = value[p];
      }
    }
    const int children = child_start_[s + 1] - child_start_[s];
    for (int c = 0; c < children; ++c) {
      const int ch = child_[child_start_[s] + c];
      const int width = first_column_[ch + 1] - first_column_[ch];
      const int* child_rows = rows_.data() + row_start_[ch] + width;
      const int mc = row_start_[ch + 1] - row_start_[ch] - width;
      const double* u = stack.get() + stack_top[stack_top.size() - children + c];
      map.resize(mc);
      for (int t = 0; t < mc; ++t) map[t] = local[child_rows[t]];
      for (int t2 = 0; t2 < mc; ++t2) {
        // Rows map[t1] >= map[t2] (both increase with t): the lower triangle of the front.
        const double* source = u + static_cast<std::size_t>(t2) * mc;
        const int column = map[t2];
        if (column < k) {
          double* target = panel.data() + static_cast<Eigen::Index>(column) * m;
          for (int t1 = t2; t1 < mc; ++t1) target[map[t1]] += source[t1];
        } else {
          double* target = update.data() + static_cast<Eigen::Index>(column - k) * mu;
          for (int t1 = t2; t1 < mc; ++t1) target[map[t1] - k] += source[t1];
        }
      }
    }
    if (children > 0) {
      stack_end = stack_top[stack_top.size() - children];
      stack_top.resize(stack_top.size() - children);
    }

    // Dense Cholesky of the k pivot columns: blocked (Eigen's LLT, then a triangular solve) when
    // every pivot is clearly positive, column by column with zero pivots dropped otherwise.
    auto p11 = panel.topRows(k);
    auto p21 = panel.bottomRows(mu);
    saved = p11;
    bool clean = Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>>(p11).info() == Eigen::Success;
    for (int c = 0; clean && c < k; ++c) {
      const double d = p11(c, c) * p11(c, c);
      pivot_[f + c] = d;
      clean = d > pivot_tolerance * diagonal[c];
    }
    if (clean) {
      p11.triangularView<Eigen::Lower>().transpose().solveInPlace<Eigen::OnTheRight>(p21);
    } else {
      p11 = saved;
      factor_columns_carefully(panel, k, diagonal.data(), pivot_tolerance, pivot_.data() + f,
                               is_zero_pivot_.data() + f);
    }
    if (mu > 0) {
      update.selfadjointView<Eigen::Lower>().rankUpdate(p21, -1.0);
      stack_top.push_back(stack_end);
      std::copy(update.data(), update.data() + static_cast<std::size_t>(mu) * mu,
                stack.get() + stack_end);
      stack_end += static_cast<std::size_t>(mu) * mu;
    }
  }
  for (int j = 0; j < n; ++j)
    if (is_zero_pivot_[j]) zero_pivots_.push_back(original_[j]);
  std::sort(zero_pivots_.begin(), zero_pivots_.end());
}

double SupernodalCholesky::factor_flops() const {
  double flops = 0;
  for (int s = 0; s < supernode_count(); ++s) {
    const double k = first_column_[s + 1] - first_column_[s];
    const double below = row_start_[s + 1] - row_start_[s] - k;
    flops += k * k * k / 3 + k * k * below + k * below * below;
  }
  return flops;
}

Eigen::VectorXd SupernodalCholesky::pivots() const {
  Eigen::VectorXd d(size());
  for (int old = 0; old < size(); ++old) d(old) = pivot_[postorder_[old]];
  return d;
}

void SupernodalCholesky::solve_in_place(Eigen::MatrixXd& b) const {
  const int n = size();
  require(static_cast<int>(pivot_.size()) == n && b.rows() == n,
          "sparse Cholesky: solve() needs a factorized matrix and a right-hand side of its size");
  const Eigen::Index r = b.cols();
  Eigen::MatrixXd x(n, r), t;
  for (int old = 0; old < n; ++old) x.row(postorder_[old]) = b.row(old);
  const int supernodes = supernode_count();
  for (int s = 0; s < supernodes; ++s) {
    const int f = first_column_[s], k = first_column_[s + 1] - f;
    const int* rows = rows_.data() + row_start_[s];
    const int m = row_start_[s + 1] - row_start_[s];
    const Eigen::Map<const Eigen::MatrixXd> l(panel_.get() + panel_start_[s], m, k);
    auto x1 = x.middleRows(f, k);
    l.topRows(k).triangularView<Eigen::Lower>().solveInPlace(x1);
    if (m > k) {
      t.noalias() = l.bottomRows(m - k) * x1;
      for (int q = 0; q < m - k; ++q) x.row(rows[k + q]) -= t.row(q);
    }
  }
  // A zero pivot's column of L is zero, so its entry of x reached no other row; zero it before
  // the backward pass reads it.
  for (int j = 0; j < n; ++j)
    if (is_zero_pivot_[j]) x.row(j).setZero();
  for (int s = supernodes - 1; s >= 0; --s) {
    const int f = first_column_[s], k = first_column_[s + 1] - f;
    const int* rows = rows_.data() + row_start_[s];
    const int m = row_start_[s + 1] - row_start_[s];
    const Eigen::Map<const Eigen::MatrixXd> l(panel_.get() + panel_start_[s], m, k);
    auto x1 = x.middleRows(f, k);
    if (m > k) {
      t.resize(m - k, r);
      for (int q = 0; q < m - k; ++q) t.row(q) = x.row(rows[k + q]);
      x1.noalias() -= l.bottomRows(m - k).transpose() * t;
    }
    l.topRows(k).triangularView<Eigen::Lower>().transpose().solveInPlace(x1);
  }
  for (int old = 0; old < n; ++old) b.row(old) = x.row(postorder_[old]);
}

void SupernodalCholesky::solve_in_place(Eigen::VectorXd& b) const {
  Eigen::MatrixXd column = b;
  solve_in_place(column);
  b = column.col(0);
}

}  // namespace plydem
