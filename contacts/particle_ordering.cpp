#include "contacts/particle_ordering.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <tuple>

#include "core/error.hpp"

namespace plydem {
namespace {

// Hilbert index of a point with integer coordinates x[0 .. dims-1] < 2^bits, by J. Skilling,
// "Programming the Hilbert curve", AIP Conf. Proc. 707 (2004) 381: the coordinates are turned
// in place into the "transposed" index, whose bits are then interleaved.
std::uint64_t hilbert_index(std::array<std::uint32_t, 3> x, int dims, int bits) {
  const std::uint32_t top = 1u << (bits - 1);
  for (std::uint32_t q = top; q > 1; q >>= 1) {
    const std::uint32_t p = q - 1;
    for (int i = 0; i < dims; ++i) {
      if (x[i] & q) {
        x[0] ^= p;
      } else {
        const std::uint32_t t = (x[0] ^ x[i]) & p;
        x[0] ^= t;
        x[i] ^= t;
      }
    }
  }
  for (int i = 1; i < dims; ++i) x[i] ^= x[i - 1];
  std::uint32_t t = 0;
  for (std::uint32_t q = top; q > 1; q >>= 1) {
    if (x[dims - 1] & q) t ^= q - 1;
  }
  for (int i = 0; i < dims; ++i) x[i] ^= t;
  std::uint64_t index = 0;
  for (int b = bits - 1; b >= 0; --b) {
    for (int i = 0; i < dims; ++i) index = (index << 1) | ((x[i] >> b) & 1u);
  }
  return index;
}

}  // namespace

std::vector<int> space_filling_curve_order(const Vector3Array& position) {
  const int n = static_cast<int>(position.rows());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  if (n < 2) return order;
  require(position.isFinite().all(), "a particle position is not finite: no space-filling order");
  const Eigen::Array3d low = position.colwise().minCoeff().transpose();
  const Eigen::Array3d extent = position.colwise().maxCoeff().transpose() - low;
  const double largest = extent.maxCoeff();
  if (!(largest > 0)) return order;  // every particle at one point
  // Drop the axes the particles do not spread along (a layer is planar).
  std::array<int, 3> axis{};
  int dims = 0;
  for (int c = 0; c < 3; ++c) {
    if (extent(c) > 1e-9 * largest) axis[dims++] = c;
  }
  // One scale for every axis keeps the curve's cells square, whatever the aspect ratio.
  const int bits = dims == 3 ? 21 : (dims == 2 ? 31 : 62);
  std::vector<std::uint64_t> key(n);
  if (dims == 1) {
    const double scale = std::ldexp(1.0, 52) / largest;
    for (int i = 0; i < n; ++i)
      key[i] = static_cast<std::uint64_t>((position(i, axis[0]) - low(axis[0])) * scale);
  } else {
    const double cells = std::ldexp(1.0, bits) - 1.0;
    const double scale = cells / largest;
    for (int i = 0; i < n; ++i) {
      std::array<std::uint32_t, 3> x{};
      for (int d = 0; d < dims; ++d) {
        const double q = std::min(cells, (position(i, axis[d]) - low(axis[d])) * scale);
        x[d] = static_cast<std::uint32_t>(q);
      }
      key[i] = hilbert_index(x, dims, bits);
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
  return order;
}

namespace {

// Cluster ids of values that lie on a few well-separated levels (lattice rows, layers): sorted,
// a new level starts where the gap exceeds `tolerance`.
std::vector<int> levels(const Eigen::ArrayXd& value, double tolerance) {
  const int n = static_cast<int>(value.size());
  std::vector<int> by_value(n);
  std::iota(by_value.begin(), by_value.end(), 0);
  std::sort(by_value.begin(), by_value.end(), [&](int a, int b) { return value(a) < value(b); });
  std::vector<int> level(n, 0);
  int current = 0;
  for (int k = 1; k < n; ++k) {
    if (value(by_value[k]) - value(by_value[k - 1]) > tolerance) ++current;
    level[by_value[k]] = current;
  }
  return level;
}

}  // namespace

std::vector<int> lattice_line_order(const Model& model, int strip_length) {
  require(strip_length >= 1, "the strip length of a lattice-line order must be at least 1");
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  const int n = p.size();
  if (n < 2 || bonds.size() == 0) return {};
  // Distinct bond vectors up to sign.
  constexpr int kMaxDirections = 16;
  std::vector<Eigen::Vector3d> bond_vectors;
  for (int b = 0; b < bonds.size(); ++b) {
    Eigen::Vector3d d = bonds.normal.row(b).matrix().transpose();
    const int lead = std::abs(d.x()) > 1e-9 ? 0 : (std::abs(d.y()) > 1e-9 ? 1 : 2);
    if (d(lead) < 0) d = -d;
    const auto same = [&](const Eigen::Vector3d& v) { return (v.normalized() - d).norm() < 1e-9; };
    if (std::none_of(bond_vectors.begin(), bond_vectors.end(), same)) {
      if (static_cast<int>(bond_vectors.size()) == kMaxDirections) return {};
      bond_vectors.push_back(bonds.length(b) * d);
    }
  }
  // Candidate line directions: the bonds, then sums and differences of two bonds (the second
  // neighbours: a hexagonal layer's rows across its bonds).
  double shortest = bond_vectors[0].norm();
  for (const Eigen::Vector3d& v : bond_vectors) shortest = std::min(shortest, v.norm());
  std::vector<Eigen::Vector3d> candidates;
  auto add = [&](const Eigen::Vector3d& v) {
    if (v.norm() < 0.5 * shortest) return;
    const Eigen::Vector3d e = v.normalized();
    for (Eigen::Vector3d& c : candidates) {
      if (std::abs(std::abs(c.normalized().dot(e)) - 1) < 1e-12) {
        if (v.norm() < c.norm()) c = v;
        return;
      }
    }
    candidates.push_back(v);
  };
  for (const Eigen::Vector3d& v : bond_vectors) add(v);
  for (std::size_t i = 0; i < bond_vectors.size(); ++i)
    for (std::size_t j = i + 1; j < bond_vectors.size(); ++j) {
      add(bond_vectors[i] + bond_vectors[j]);
      add(bond_vectors[i] - bond_vectors[j]);
    }
  constexpr std::size_t kMaxCandidates = 12;
  if (candidates.size() > kMaxCandidates) candidates.resize(kMaxCandidates);

  // Lines along a candidate: particles with the same coordinates across it (by layer, then row).
  struct Lines {
    std::vector<int> layer, row;
    Eigen::ArrayXd along;
    int count = 0;
  };
  auto lines_along = [&](const Eigen::Vector3d& v) {
    const Eigen::Vector3d e = v.normalized();
    const Eigen::Vector3d helper =
        std::abs(e.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d across_layers = (helper - helper.dot(e) * e).normalized();
    const Eigen::Vector3d across_rows = across_layers.cross(e);
    const double tolerance = 1e-3 * shortest;
    Lines l;
    l.layer = levels((p.reference_position.matrix() * across_layers).array(), tolerance);
    l.row = levels((p.reference_position.matrix() * across_rows).array(), tolerance);
    l.along = (p.reference_position.matrix() * e).array();
    std::vector<std::pair<int, int>> keys(n);
    for (int i = 0; i < n; ++i) keys[i] = {l.layer[i], l.row[i]};
    std::sort(keys.begin(), keys.end());
    l.count = static_cast<int>(std::unique(keys.begin(), keys.end()) - keys.begin());
    return l;
  };
  // The longest lines: the fewest of them.
  std::size_t best = 0;
  Lines lines = lines_along(candidates[0]);
  for (std::size_t c = 1; c < candidates.size(); ++c) {
    Lines other = lines_along(candidates[c]);
    if (other.count < lines.count) {
      lines = std::move(other);
      best = c;
    }
  }
  const double spacing = candidates[best].norm();
  const double a_min = lines.along.minCoeff();
  std::vector<long> strip(n);
  for (int i = 0; i < n; ++i) {
    strip[i] = static_cast<long>(
        std::floor((lines.along(i) - a_min + 1e-3 * spacing) / (strip_length * spacing)));
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int x, int y) {
    return std::tie(strip[x], lines.layer[x], lines.row[x], lines.along(x)) <
           std::tie(strip[y], lines.layer[y], lines.row[y], lines.along(y));
  });
  return order;
}

std::vector<int> kernel_order(const Model& model, ParticleOrder choice) {
  if (choice == ParticleOrder::kAsBuilt) {
    std::vector<int> order(model.particles.size());
    std::iota(order.begin(), order.end(), 0);
    return order;
  }
  if (choice == ParticleOrder::kAutomatic) {
    std::vector<int> lines = lattice_line_order(model);
    if (!lines.empty()) return lines;
  }
  return space_filling_curve_order(model.particles.reference_position);
}

void check_permutation(const std::vector<int>& order, int count) {
  if (static_cast<int>(order.size()) != count) {
    throw Error(fmt::format("a particle ordering lists {} particles, the model has {}",
                            order.size(), count));
  }
  std::vector<char> seen(count, 0);
  for (int k = 0; k < count; ++k) {
    const int i = order[k];
    if (!(i >= 0 && i < count) || seen[i]) {
      throw Error(
          fmt::format("a particle ordering is not a permutation: entry {} names particle {} {}", k,
                      i, (i >= 0 && i < count) ? "twice" : "that does not exist"));
    }
    seen[i] = 1;
  }
}

void renumber(Model& model, const std::vector<int>& order) {
  Particles& p = model.particles;
  const int n = p.size();
  check_permutation(order, n);
  p.permute(order);

  Bonds& b = model.bonds;
  std::vector<int> new_index(n);
  for (int k = 0; k < n; ++k) new_index[order[k]] = k;
  b.rename_particles(new_index);
  std::vector<int> bond_order(b.size());
  std::iota(bond_order.begin(), bond_order.end(), 0);
  auto low_high = [&](int e) {
    return std::pair(std::min(b.first(e), b.second(e)), std::max(b.first(e), b.second(e)));
  };
  std::stable_sort(bond_order.begin(), bond_order.end(),
                   [&](int x, int y) { return low_high(x) < low_high(y); });
  b.permute(bond_order);
}

}  // namespace plydem
