#pragma once
/// \file
/// Disjoint sets of the indices 0 .. n-1 (union-find with path halving). A set's representative
/// is its lowest index, so whatever a caller derives from the representatives (cluster order,
/// labels) does not depend on the order of the joins.

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace plydem {

class DisjointSets {
 public:
  /// n sets of one index each.
  explicit DisjointSets(int n) : parent_(static_cast<std::size_t>(n)) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }

  /// The representative of i's set: its lowest index.
  int find(int i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }

  /// Joins the sets of i and j; false where they were one already.
  bool join(int i, int j) {
    const int a = find(i), b = find(j);
    if (a == b) return false;
    parent_[std::max(a, b)] = std::min(a, b);
    return true;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace plydem
