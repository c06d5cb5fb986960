#include "contacts/bond_kernel.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include "contacts/particle_ordering.hpp"
#include "core/error.hpp"

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

// Half-bond types are merged when their parameters agree to about 1e-12 relative: the normals and
// levers of a regular lattice, computed from positions, differ only in their last bits, and merging
// them is what lets a lattice stream a type index instead of its parameters. Normals are merged
// with the first one seen within 1e-12 (a lattice has a few directions; beyond kMaxDirections the
// packing is irregular and normals are kept exactly), the other parameters by rounding them to 40
// significant bits.
constexpr int kMaxDirections = 16;
constexpr double kSameDirection = 1e-12;

std::int64_t quantize_relative(double x) {
  int exponent = 0;
  const double mantissa = std::frexp(x, &exponent);
  return std::llround(std::ldexp(mantissa, 40)) * 4096 + exponent;
}

std::int64_t bits_of(double x) {
  std::int64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

using TypeKey = std::array<std::int64_t, 9>;

struct KeyHash {
  std::size_t operator()(const TypeKey& key) const {
    std::uint64_t h = 1469598103934665603ull;
    for (std::int64_t k : key) {
      h ^= static_cast<std::uint64_t>(k) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return static_cast<std::size_t>(h);
  }
};

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

  // The bonds' directions, both senses, if they are few.
  std::vector<Eigen::Vector3d> directions;
  auto find_direction = [&](const Eigen::Vector3d& normal) {
    for (std::size_t d = 0; d < directions.size(); ++d) {
      if ((directions[d] - normal).cwiseAbs().maxCoeff() < kSameDirection)
        return static_cast<int>(d);
    }
    return -1;
  };
  bool few_directions = true;
  for (int b = 0; b < m && few_directions; ++b) {
    const Eigen::Vector3d normal = bonds.normal.row(b).matrix().transpose();
    for (const Eigen::Vector3d& sensed : {normal, Eigen::Vector3d(-normal)}) {
      if (find_direction(sensed) >= 0) continue;
      if (static_cast<int>(directions.size()) == kMaxDirections) {
        few_directions = false;
        break;
      }
      directions.push_back(sensed);
    }
  }
  if (!few_directions) directions.clear();

  types_.assign(1, HalfBondType{});
  std::vector<int> type_direction(1, -1);
  std::unordered_map<TypeKey, std::int32_t, KeyHash> type_index;
  auto type_of = [&](HalfBondType h) {
    const Eigen::Vector3d normal(h.normal[0], h.normal[1], h.normal[2]);
    const int d = few_directions ? find_direction(normal) : -1;
    if (d >= 0) {
      for (int c = 0; c < 3; ++c) h.normal[c] = directions[d](c);
    }
    h.lever_shear = h.lever_own * h.shear_stiffness;
    const TypeKey key{d >= 0 ? d : bits_of(h.normal[0]),   d >= 0 ? 0 : bits_of(h.normal[1]),
                      d >= 0 ? 0 : bits_of(h.normal[2]),   quantize_relative(h.lever_own),
                      quantize_relative(h.lever_other),    quantize_relative(h.shear_stiffness),
                      quantize_relative(h.normal_excess),  quantize_relative(h.bending_stiffness),
                      quantize_relative(h.twisting_excess)};
    const auto [it, inserted] =
        type_index.try_emplace(key, static_cast<std::int32_t>(types_.size()));
    if (inserted) {
      types_.push_back(h);
      type_direction.push_back(d);
    }
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

  // Lattice slots: one slot per direction, numbered by angle (so that the slot order does not
  // depend on the bond order), if no particle has two bonds along one direction.
  lattice_slots_ = few_directions && !directions.empty();
  if (lattice_slots_) {
    std::vector<int> by_angle(directions.size());
    std::iota(by_angle.begin(), by_angle.end(), 0);
    auto angle = [&](int d) {
      return std::pair(std::atan2(directions[d].y(), directions[d].x()), directions[d].z());
    };
    std::sort(by_angle.begin(), by_angle.end(), [&](int a, int b) { return angle(a) < angle(b); });
    std::vector<int> slot_of_direction(directions.size());
    for (std::size_t s = 0; s < by_angle.size(); ++s)
      slot_of_direction[by_angle[s]] = static_cast<int>(s);
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

  // The types blocks share, repeated across the lanes.
  uniform_.assign(1, HalfBondLanes{});
  std::vector<std::int32_t> uniform_index(types_.size(), 0);
  auto uniform_of = [&](std::int32_t t) {
    if (uniform_index[t] == 0) {
      const HalfBondType& h = types_[t];
      HalfBondLanes v;
      for (int c = 0; c < 3; ++c) lanes::broadcast(h.normal[c], v.normal[c]);
      lanes::broadcast(h.lever_own, v.lever_own);
      lanes::broadcast(h.lever_other, v.lever_other);
      lanes::broadcast(h.shear_stiffness, v.shear_stiffness);
      lanes::broadcast(h.lever_shear, v.lever_shear);
      lanes::broadcast(h.normal_excess, v.normal_excess);
      lanes::broadcast(h.bending_stiffness, v.bending_stiffness);
      lanes::broadcast(h.twisting_excess, v.twisting_excess);
      uniform_index[t] = static_cast<std::int32_t>(uniform_.size());
      uniform_.push_back(v);
    }
    return uniform_index[t];
  };
  const int blocks = padded_ / lanes::kCount;
  block_type_.assign(static_cast<std::size_t>(blocks) * width_, 0);
  block_run_.assign(static_cast<std::size_t>(blocks) * width_, -1);
  for (int b = 0; b < blocks; ++b) {
    for (int s = 0; s < width_; ++s) {
      const std::int32_t* type = types(s) + b * lanes::kCount;
      bool same_type = true;
      for (int l = 1; l < lanes::kCount; ++l) same_type &= type[l] == type[0];
      const std::size_t cell = static_cast<std::size_t>(b) * width_ + s;
      block_type_[cell] = same_type ? (type[0] == 0 ? 0 : uniform_of(type[0])) : -1;
      block_run_[cell] = block_run_of(b, s);
    }
  }
}

std::int32_t GatherBonds::block_run_of(int block, int slot) const {
  const std::int32_t* other = neighbours(slot) + block * lanes::kCount;
  bool consecutive = other[0] + lanes::kCount <= padded_;
  for (int l = 1; l < lanes::kCount; ++l) consecutive &= other[l] == other[0] + l;
  return consecutive ? other[0] : -1;
}

void GatherBonds::drop_bond(int first, int second) {
  if (!(first >= 0 && first < particles_ && second >= 0 && second < particles_ && first != second))
    throw Error(
        fmt::format("cannot drop a bond between kernel particles {} and {}: not two "
                    "distinct particles of the {}",
                    first, second, particles_));
  auto slot_of = [&](int own, int other) {
    for (int s = 0; s < width_; ++s) {
      const std::size_t cell = static_cast<std::size_t>(s) * padded_ + own;
      if (type_[cell] != 0 && neighbour_[cell] == other) return s;
    }
    throw Error(fmt::format("kernel particles {} and {} have no bond to drop", first, second));
  };
  const int slots[2] = {slot_of(first, second), slot_of(second, first)};
  const int ends[2] = {first, second};
  for (int e = 0; e < 2; ++e) {
    const int own = ends[e], s = slots[e];
    const std::size_t cell = static_cast<std::size_t>(s) * padded_ + own;
    type_[cell] = 0;
    neighbour_[cell] = own;
    // The block's slot was uniform or mixed; with one lane now empty it is mixed, or empty if no
    // lane has a bond left (a uniform type needs every lane to hold it).
    const int block = own / lanes::kCount;
    const std::int32_t* type = types(s) + block * lanes::kCount;
    bool empty = true;
    for (int l = 0; l < lanes::kCount; ++l) empty &= type[l] == 0;
    const std::size_t block_cell = static_cast<std::size_t>(block) * width_ + s;
    block_type_[block_cell] = empty ? 0 : -1;
    block_run_[block_cell] = block_run_of(block, s);
  }
}

std::size_t GatherBonds::bytes() const {
  return (neighbour_.size() + type_.size() + block_type_.size() + block_run_.size()) *
             sizeof(std::int32_t) +
         types_.size() * sizeof(HalfBondType) + uniform_.size() * sizeof(HalfBondLanes);
}

}  // namespace plydem
