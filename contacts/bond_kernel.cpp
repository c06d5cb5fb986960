#include "contacts/bond_kernel.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "core/error.hpp"
#include "core/particle_ordering.hpp"

namespace plydem {
namespace {

Eigen::Vector3d row3(const Vector3Array& a, int i) {
  return {a(i, 0), a(i, 1), a(i, 2)};
}

void add_row3(Vector3Array& a, int i, const Eigen::Vector3d& v) {
  a(i, 0) += v.x();
  a(i, 1) += v.y();
  a(i, 2) += v.z();
}

BondResponse evaluate(const Particles& p, const Bonds& bonds, int b) {
  const int i = bonds.first(b);
  const int j = bonds.second(b);
  return parallel_bond_response(bond_parameters(bonds, b), row3(p.displacement, i),
                                row3(p.rotation, i), row3(p.displacement, j), row3(p.rotation, j));
}

}  // namespace

BondParameters bond_parameters(const Bonds& bonds, int b) {
  BondParameters params;
  params.normal = row3(bonds.normal, b);
  params.lever_first = bonds.lever_first(b);
  params.lever_second = bonds.lever_second(b);
  params.normal_stiffness = bonds.normal_stiffness(b);
  params.shear_stiffness = bonds.shear_stiffness(b);
  params.bending_stiffness = bonds.bending_stiffness(b);
  params.twisting_stiffness = bonds.twisting_stiffness(b);
  return params;
}

BondPass compute_bond_forces(Particles& particles, const Bonds& bonds) {
  particles.force.setZero();
  particles.torque.setZero();
  BondPass pass;
  for (int b = 0; b < bonds.size(); ++b) {
    const BondResponse r = evaluate(particles, bonds, b);
    const int i = bonds.first(b);
    const int j = bonds.second(b);
    add_row3(particles.force, i, r.force_on_first);
    add_row3(particles.force, j, -r.force_on_first);
    add_row3(particles.torque, i, r.torque_on_first);
    add_row3(particles.torque, j, r.torque_on_second);
    pass.strain_energy += r.energy;
    pass.sum_force_norm += r.force_on_first.norm();
  }
  return pass;
}

double bond_strain_energy(const Particles& particles, const Bonds& bonds) {
  double energy = 0;
  for (int b = 0; b < bonds.size(); ++b) energy += evaluate(particles, bonds, b).energy;
  return energy;
}

namespace {

// Half-bond types are merged when every parameter agrees to about 2^-40 (1e-12) relative: the
// normals and levers of a regular lattice, computed from positions, differ only in their last
// bits, and merging them is what lets a lattice stream a type index instead of its parameters.
// Normal components are quantized absolutely (they lie in [-1, 1] and may be noise around 0),
// the others relative to their own magnitude.
constexpr int kMergeBits = 40;

std::int64_t quantize_absolute(double x) {
  return std::llround(std::ldexp(x, kMergeBits));
}

std::int64_t quantize_relative(double x) {
  int exponent = 0;
  const double mantissa = std::frexp(x, &exponent);
  return std::llround(std::ldexp(mantissa, kMergeBits)) * 4096 + exponent;
}

using TypeKey = std::array<std::int64_t, 9>;
using DirectionKey = std::array<std::int64_t, 3>;

template <std::size_t N>
struct KeyHash {
  std::size_t operator()(const std::array<std::int64_t, N>& key) const {
    std::uint64_t h = 1469598103934665603ull;
    for (std::int64_t k : key) {
      h ^= static_cast<std::uint64_t>(k) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return static_cast<std::size_t>(h);
  }
};

TypeKey key_of(const HalfBondType& h) {
  return {quantize_absolute(h.normal[0]),      quantize_absolute(h.normal[1]),
          quantize_absolute(h.normal[2]),      quantize_relative(h.lever_own),
          quantize_relative(h.lever_other),    quantize_relative(h.shear_stiffness),
          quantize_relative(h.normal_excess),  quantize_relative(h.bending_stiffness),
          quantize_relative(h.twisting_excess)};
}

DirectionKey direction_of(const HalfBondType& h) {
  return {quantize_absolute(h.normal[0]), quantize_absolute(h.normal[1]),
          quantize_absolute(h.normal[2])};
}

}  // namespace

GatherBonds::GatherBonds(const Bonds& bonds, const std::vector<int>& order) {
  const int n = static_cast<int>(order.size());
  check_permutation(order, n);
  particles_ = n;
  padded_ = (n + lanes::kCount - 1) / lanes::kCount * lanes::kCount;
  std::vector<int> kernel_index(n);
  for (int k = 0; k < n; ++k) kernel_index[order[k]] = k;

  // Both ends of every bond, grouped by their own particle (CSR).
  const int m = bonds.size();
  std::vector<int> offset(n + 1, 0);
  for (int b = 0; b < m; ++b) {
    const int i = bonds.first(b), j = bonds.second(b);
    if (!(i >= 0 && i < n && j >= 0 && j < n && i != j)) {
      throw Error(
          fmt::format("bond {} joins particles {} and {}: not two distinct particles of "
                      "the {} in the model",
                      b, i, j, n));
    }
    ++offset[kernel_index[i] + 1];
    ++offset[kernel_index[j] + 1];
  }
  std::partial_sum(offset.begin(), offset.end(), offset.begin());
  std::vector<int> fill(offset.begin(), offset.end() - 1);
  std::vector<std::int32_t> entry_other(2 * static_cast<std::size_t>(m));
  std::vector<std::int32_t> entry_type(2 * static_cast<std::size_t>(m));

  types_.assign(1, HalfBondType{});
  std::unordered_map<TypeKey, std::int32_t, KeyHash<9>> type_index;
  auto type_of = [&](const HalfBondType& h) {
    const auto [it, inserted] =
        type_index.try_emplace(key_of(h), static_cast<std::int32_t>(types_.size()));
    if (inserted) types_.push_back(h);
    return it->second;
  };
  for (int b = 0; b < m; ++b) {
    const int i = kernel_index[bonds.first(b)], j = kernel_index[bonds.second(b)];
    HalfBondType h;
    h.shear_stiffness = bonds.shear_stiffness(b);
    h.normal_excess = bonds.normal_stiffness(b) - bonds.shear_stiffness(b);
    h.bending_stiffness = bonds.bending_stiffness(b);
    h.twisting_excess = bonds.twisting_stiffness(b) - bonds.bending_stiffness(b);
    for (int c = 0; c < 3; ++c) h.normal[c] = bonds.normal(b, c);
    h.lever_own = bonds.lever_first(b);
    h.lever_other = bonds.lever_second(b);
    entry_other[fill[i]] = j;
    entry_type[fill[i]++] = type_of(h);
    for (double& x : h.normal) x = -x;
    std::swap(h.lever_own, h.lever_other);
    entry_other[fill[j]] = i;
    entry_type[fill[j]++] = type_of(h);
  }

  // Lattice slots: one slot per bond direction, if the directions are few and unique per particle.
  std::unordered_map<DirectionKey, int, KeyHash<3>> direction_index;
  std::vector<int> type_direction(types_.size(), -1);
  constexpr int kMaxDirections = 16;
  lattice_slots_ = true;
  for (std::size_t t = 1; t < types_.size() && lattice_slots_; ++t) {
    const auto [it, inserted] = direction_index.try_emplace(
        direction_of(types_[t]), static_cast<int>(direction_index.size()));
    type_direction[t] = it->second;
    if (direction_index.size() > kMaxDirections) lattice_slots_ = false;
  }
  if (lattice_slots_) {
    // Number the directions by angle, so that the slot order does not depend on the bond order.
    std::vector<std::pair<DirectionKey, int>> directions(direction_index.begin(),
                                                         direction_index.end());
    auto angle = [](const DirectionKey& d) {
      return std::pair(std::atan2(static_cast<double>(d[1]), static_cast<double>(d[0])), d[2]);
    };
    std::sort(directions.begin(), directions.end(),
              [&](const auto& a, const auto& b) { return angle(a.first) < angle(b.first); });
    std::vector<int> slot_of_direction(directions.size());
    for (std::size_t s = 0; s < directions.size(); ++s)
      slot_of_direction[directions[s].second] = static_cast<int>(s);
    for (int& d : type_direction) d = d < 0 ? d : slot_of_direction[d];
    width_ = static_cast<int>(directions.size());
    for (int k = 0; k < n && lattice_slots_; ++k) {
      unsigned used = 0;
      for (int e = offset[k]; e < offset[k + 1]; ++e) {
        const unsigned bit = 1u << type_direction[entry_type[e]];
        if (used & bit) lattice_slots_ = false;
        used |= bit;
      }
    }
  }
  if (!lattice_slots_) {
    width_ = 0;
    for (int k = 0; k < n; ++k) width_ = std::max(width_, offset[k + 1] - offset[k]);
  }

  const std::size_t cells = static_cast<std::size_t>(width_) * padded_;
  neighbour_.resize(cells);
  type_.assign(cells, 0);
  for (int s = 0; s < width_; ++s)
    std::iota(neighbour_.begin() + static_cast<std::ptrdiff_t>(s) * padded_,
              neighbour_.begin() + static_cast<std::ptrdiff_t>(s + 1) * padded_, 0);
  std::vector<int> entries;
  for (int k = 0; k < n; ++k) {
    entries.resize(offset[k + 1] - offset[k]);
    std::iota(entries.begin(), entries.end(), offset[k]);
    if (!lattice_slots_) {
      std::sort(entries.begin(), entries.end(),
                [&](int a, int b) { return entry_other[a] < entry_other[b]; });
    }
    for (std::size_t r = 0; r < entries.size(); ++r) {
      const int e = entries[r];
      const int slot = lattice_slots_ ? type_direction[entry_type[e]] : static_cast<int>(r);
      const std::size_t cell = static_cast<std::size_t>(slot) * padded_ + k;
      neighbour_[cell] = entry_other[e];
      type_[cell] = entry_type[e];
    }
  }
}

std::size_t GatherBonds::bytes() const {
  return neighbour_.size() * sizeof(std::int32_t) + type_.size() * sizeof(std::int32_t) +
         types_.size() * sizeof(HalfBondType);
}

}  // namespace plydem
