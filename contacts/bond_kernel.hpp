#pragma once
/// \file
/// The bond-force kernels that advance every model, both applying the parallel bond law
/// (core/parallel_bond.hpp):
///
/// - compute_bond_forces: the simple reference loop over the bond arrays (scatter: each bond adds
///   to its two particles). Tests hold the fast path to it.
/// - GatherBonds + gather_bond_block: the gather form the explicit integrator runs. Every particle
///   sums its own bonds, so no two particles write the same memory (threads need no atomics and
///   a particle's sum never depends on how the particles are split between threads), and a block
///   of kLanes consecutive particles is evaluated together in SIMD lanes. The bonds are stored per
///   particle in a padded, slot-major table (ELL): slot s of particles i .. i+7 are 8 consecutive
///   integers. A bond's parameters (normal, levers, stiffnesses) are not stored per bond but as an
///   index into a table of distinct "half-bond types", so that a regular lattice, whose bonds take
///   a handful of distinct values, streams 8 bytes per bond end instead of 80.
///
/// Free functions over arrays, no virtual call per bond, so that strategies and experiments never
/// see how the kernel is laid out.

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#include "core/model.hpp"
#include "core/parallel_bond.hpp"

namespace plydem {

/// Bond b's parameters, gathered from the bond arrays.
BondParameters bond_parameters(const Bonds& bonds, int b);

/// Totals of one pass over the bonds.
struct BondPass {
  double strain_energy = 0;   ///< sum of bond energies [J]
  double sum_force_norm = 0;  ///< sum over bonds of |F| [N], the scale of the unbalanced force
};

/// Sets particles.force and particles.torque to the bond forces and moments at the current
/// displacements and rotations (external loads are added by the caller afterwards). The reference
/// implementation: one pass over the bonds, each adding to both of its particles.
BondPass compute_bond_forces(Particles& particles, const Bonds& bonds);

/// The bonds' strain energy at the current state [J], without touching forces.
double bond_strain_energy(const Particles& particles, const Bonds& bonds);

/// SIMD lanes: GCC vector extensions, which the compiler lowers to the instruction set of the
/// function being compiled (one AVX-512 register, two AVX2 registers, four SSE2 registers). Values
/// are passed by reference only, so no function boundary depends on the vector ABI.
// GCC 12 lowers a 64-byte vector to narrower registers piece by piece for instruction sets without
// AVX-512 and then warns that the pieces of a freshly built vector "may be used uninitialized".
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace lanes {

inline constexpr int kCount = 8;
using Doubles = double __attribute__((vector_size(kCount * sizeof(double))));
using Mask = std::int64_t __attribute__((vector_size(kCount * sizeof(double))));

[[gnu::always_inline]] inline void load(const double* p, Doubles& v) {
  std::memcpy(&v, __builtin_assume_aligned(p, 64), sizeof v);
}
[[gnu::always_inline]] inline void store(double* p, const Doubles& v) {
  std::memcpy(__builtin_assume_aligned(p, 64), &v, sizeof v);
}
[[gnu::always_inline]] inline void load_unaligned(const double* p, Doubles& v) {
  std::memcpy(&v, p, sizeof v);
}
[[gnu::always_inline]] inline void broadcast(double x, Doubles& v) {
  v = x - Doubles{};  // exact for every x (unlike x + 0, which turns -0 into +0): one broadcast
}
/// v[l] = base[index[l]].
[[gnu::always_inline]] inline void gather(const double* base, const std::int32_t* index,
                                          Doubles& v) {
  static_assert(kCount == 8);
  v = Doubles{base[index[0]], base[index[1]], base[index[2]], base[index[3]],
              base[index[4]], base[index[5]], base[index[6]], base[index[7]]};
}
/// Sum of the lanes, in lane order.
[[gnu::always_inline]] inline double sum(const Doubles& v) {
  double s = 0;
  for (int l = 0; l < kCount; ++l) s += v[l];
  return s;
}

/// A 64-byte aligned, zero-initialized array of doubles whose size is a whole number of lanes.
class Array {
 public:
  Array() = default;
  /// Room for at least `size` values, rounded up to whole lanes.
  explicit Array(std::size_t size)
      : size_((size + kCount - 1) / kCount * kCount),
        data_(static_cast<double*>(
            std::aligned_alloc(64, std::max<std::size_t>(size_, kCount) * sizeof(double)))) {
    if (!data_) throw std::bad_alloc();
    std::memset(data_.get(), 0, size_ * sizeof(double));
  }
  double* data() { return data_.get(); }
  const double* data() const { return data_.get(); }
  double& operator[](std::size_t i) { return data_[i]; }
  double operator[](std::size_t i) const { return data_[i]; }
  std::size_t size() const { return size_; }
  std::size_t bytes() const { return size_ * sizeof(double); }

 private:
  struct Free {
    void operator()(double* p) const { std::free(p); }
  };
  std::size_t size_ = 0;
  std::unique_ptr<double[], Free> data_;
};

}  // namespace lanes

/// One bond as seen from one of its particles ("own"), toward the other: the parameters of the
/// gather form. With the normal pointing from own to other, the force and moment on own are those
/// parallel_bond_response gives the first particle (it is symmetric under swapping the two ends,
/// which flips n, du and dtheta), written as
///   F = k_s du + (k_n - k_s)(n.du) n,   M_own = s_own n x F + k_b dtheta + (k_t - k_b)(n.dtheta)
///   n.
struct HalfBondType {
  double normal[3] = {0, 0, 0};  ///< unit, own -> other
  double lever_own = 0;          ///< [m]
  double lever_other = 0;        ///< [m]
  double shear_stiffness = 0;    ///< k_s [N/m]
  double lever_shear = 0;        ///< s_own k_s [N]
  double normal_excess = 0;      ///< k_n - k_s [N/m]
  double bending_stiffness = 0;  ///< k_b [N m/rad]
  double twisting_excess = 0;    ///< k_t - k_b [N m/rad]
};

/// A HalfBondType with every parameter repeated in all lanes: what a block whose eight particles
/// share the type of a slot loads (plain vector loads; no broadcasts in the loop).
struct alignas(64) HalfBondLanes {
  lanes::Doubles normal[3];
  lanes::Doubles lever_own, lever_other, shear_stiffness, lever_shear, normal_excess,
      bending_stiffness, twisting_excess;
};

/// The bonds in gather form for particles numbered in "kernel order" (see the constructor),
/// padded to whole blocks of lanes::kCount particles. Slot s of kernel particle k holds the other
/// end `neighbours(s)[k]` (a kernel index) and the half-bond type `types(s)[k]`; type 0 is the
/// empty slot (all zero: no force), whose neighbour is the particle itself.
///
/// Slots follow directions where the packing is a lattice: when the bonds point along at most
/// 16 distinct directions and no particle has two bonds along one, slot s is direction s for
/// every particle, so the 8 particles of a block mostly share the type of each slot and the kernel
/// loads its parameters once for all 8. Otherwise slots are filled in order of the other end's
/// index and the width is the largest number of bonds of one particle.
class GatherBonds {
 public:
  GatherBonds() = default;
  /// `order[k]` = model index of kernel particle k; throws plydem::Error unless it is a
  /// permutation of the particles, or if a bond refers to a missing particle.
  GatherBonds(const Bonds& bonds, const std::vector<int>& order);

  int particle_count() const { return particles_; }
  /// Particles rounded up to whole lane blocks; the padding particles have no bonds.
  int padded_count() const { return padded_; }
  int width() const { return width_; }
  bool lattice_slots() const { return lattice_slots_; }
  const std::int32_t* neighbours(int slot) const {
    return neighbour_.data() + static_cast<std::size_t>(slot) * padded_;
  }
  const std::int32_t* types(int slot) const {
    return type_.data() + static_cast<std::size_t>(slot) * padded_;
  }
  const HalfBondType& type(int t) const { return types_[t]; }
  /// Per slot of block b (particles 8b .. 8b+7): 0 if none of the eight has a bond in the slot, -1
  /// if their types differ, else u > 0: they all have the type uniform_lanes(u).
  const std::int32_t* block_types(int b) const {
    return block_type_.data() + static_cast<std::size_t>(b) * width_;
  }
  const HalfBondLanes& uniform_lanes(int u) const { return uniform_[u]; }
  /// Per slot of block b: k if the eight other ends are the consecutive particles k .. k+7 (the
  /// kernel then loads them as one vector instead of gathering), else -1.
  const std::int32_t* block_runs(int b) const {
    return block_run_.data() + static_cast<std::size_t>(b) * width_;
  }
  int type_count() const { return static_cast<int>(types_.size()); }
  /// Bytes held by the lists and the type table.
  std::size_t bytes() const;

  /// Removes the bond between kernel particles `first` and `second` without rebuilding the
  /// table: its slot at both ends becomes the empty slot (type 0, neighbour = the particle
  /// itself), as LAMMPS keeps a broken bond's slot with bond type 0, and the two blocks'
  /// block_types() and block_runs() of that slot are updated (a uniform slot turns mixed, or empty
  /// when no particle of the block has a bond in it). The forces are then those of a table built
  /// without the bond. Throws plydem::Error if the two particles have no bond.
  void drop_bond(int first, int second);

 private:
  // block_runs() of one block and slot, from the neighbours.
  std::int32_t block_run_of(int block, int slot) const;

  int particles_ = 0;
  int padded_ = 0;
  int width_ = 0;
  bool lattice_slots_ = false;
  std::vector<std::int32_t> neighbour_;   // [slot * padded + particle]
  std::vector<std::int32_t> type_;        // [slot * padded + particle]
  std::vector<HalfBondType> types_;       // [0] = empty slot
  std::vector<std::int32_t> block_type_;  // [block * width + slot]
  std::vector<HalfBondLanes> uniform_;    // [0] unused
  std::vector<std::int32_t> block_run_;   // [block * width + slot]
};

/// Displacements and rotations in kernel order: component c of particle k is `displacement[c][k]`.
struct GatherState {
  const double* displacement[3];
  const double* rotation[3];
};

/// Force and moment on the block of particles first .. first + lanes::kCount - 1 (first a multiple
/// of lanes::kCount) from all their bonds, added to `force` and `torque`. With kEnergy, also adds
/// half of each bond's strain energy and half its force magnitude (each bond is seen from both
/// ends) to `energy` and `force_norm`. Inlined into the caller, so that it is compiled for the
/// caller's instruction set (see solvers/explicit_integrator.cpp).
template <bool kEnergy>
[[gnu::always_inline]] inline void gather_bond_block(
    const GatherBonds& g, int first, const GatherState& s, lanes::Doubles (&force)[3],
    lanes::Doubles (&torque)[3], lanes::Doubles& energy, lanes::Doubles& force_norm) {
  using lanes::Doubles;
  constexpr int kLanes = lanes::kCount;
  Doubles u_i[3], t_i[3];
  for (int c = 0; c < 3; ++c) {
    lanes::load(s.displacement[c] + first, u_i[c]);
    lanes::load(s.rotation[c] + first, t_i[c]);
  }
  const int block = first / kLanes;
  const std::int32_t* block_type = g.block_types(block);
  const std::int32_t* block_run = g.block_runs(block);
  for (int slot = 0; slot < g.width(); ++slot) {
    const std::int32_t uniform_type = block_type[slot];
    if (uniform_type == 0) continue;  // no particle of the block has a bond in this slot

    Doubles u_j[3], t_j[3];
    const std::int32_t run = block_run[slot];
    if (run >= 0) {  // the other ends are consecutive particles: plain loads
      for (int c = 0; c < 3; ++c) {
        lanes::load_unaligned(s.displacement[c] + run, u_j[c]);
        lanes::load_unaligned(s.rotation[c] + run, t_j[c]);
      }
    } else {
      const std::int32_t* other = g.neighbours(slot) + first;
      for (int c = 0; c < 3; ++c) {
        lanes::gather(s.displacement[c], other, u_j[c]);
        lanes::gather(s.rotation[c], other, t_j[c]);
      }
    }
    Doubles n[3] = {}, s_own{}, s_other{}, k_s{}, s_k_s{}, k_n_excess{}, k_b{}, k_t_excess{};
    if (uniform_type > 0) {
      const HalfBondLanes& h = g.uniform_lanes(uniform_type);
      for (int c = 0; c < 3; ++c) n[c] = h.normal[c];
      s_own = h.lever_own;
      s_other = h.lever_other;
      k_s = h.shear_stiffness;
      s_k_s = h.lever_shear;
      k_n_excess = h.normal_excess;
      k_b = h.bending_stiffness;
      k_t_excess = h.twisting_excess;
    } else {
      const std::int32_t* type = g.types(slot) + first;
      for (int l = 0; l < kLanes; ++l) {
        const HalfBondType& h = g.type(type[l]);
        for (int c = 0; c < 3; ++c) n[c][l] = h.normal[c];
        s_own[l] = h.lever_own;
        s_other[l] = h.lever_other;
        k_s[l] = h.shear_stiffness;
        s_k_s[l] = h.lever_shear;
        k_n_excess[l] = h.normal_excess;
        k_b[l] = h.bending_stiffness;
        k_t_excess[l] = h.twisting_excess;
      }
    }
    // du = (u_j - u_i) - (s_i theta_i + s_j theta_j) x n  (core/parallel_bond.hpp)
    Doubles a[3], du[3];
    for (int c = 0; c < 3; ++c) a[c] = s_own * t_i[c] + s_other * t_j[c];
    du[0] = (u_j[0] - u_i[0]) - (a[1] * n[2] - a[2] * n[1]);
    du[1] = (u_j[1] - u_i[1]) - (a[2] * n[0] - a[0] * n[2]);
    du[2] = (u_j[2] - u_i[2]) - (a[0] * n[1] - a[1] * n[0]);
    const Doubles du_n = n[0] * du[0] + n[1] * du[1] + n[2] * du[2];
    const Doubles normal_part = k_n_excess * du_n;
    // F = k_s du + (k_n - k_s) du_n n, accumulated term by term; n x F = k_s (n x du).
    for (int c = 0; c < 3; ++c) {
      force[c] += k_s * du[c];
      force[c] += normal_part * n[c];
    }
    const Doubles n_cross_du[3] = {n[1] * du[2] - n[2] * du[1], n[2] * du[0] - n[0] * du[2],
                                   n[0] * du[1] - n[1] * du[0]};
    Doubles dt[3];
    for (int c = 0; c < 3; ++c) dt[c] = t_j[c] - t_i[c];
    const Doubles dt_n = n[0] * dt[0] + n[1] * dt[1] + n[2] * dt[2];
    const Doubles twist_part = k_t_excess * dt_n;
    // M_own = s_own n x F + k_b dtheta + (k_t - k_b) dtheta_n n.
    for (int c = 0; c < 3; ++c) {
      torque[c] += s_k_s * n_cross_du[c];
      torque[c] += k_b * dt[c];
      torque[c] += twist_part * n[c];
    }
    if constexpr (kEnergy) {
      const Doubles du2 = du[0] * du[0] + du[1] * du[1] + du[2] * du[2];
      const Doubles dt2 = dt[0] * dt[0] + dt[1] * dt[1] + dt[2] * dt[2];
      // E = 1/2 (k_s |du|^2 + (k_n - k_s) du_n^2 + k_b |dtheta|^2 + (k_t - k_b) dtheta_n^2),
      // half of it per end.
      energy += 0.25 * (k_s * du2 + normal_part * du_n + k_b * dt2 + twist_part * dt_n);
      // |F|^2 = k_s^2 |du|^2 + (k_n^2 - k_s^2) du_n^2, from scalars only: no product
      // shared with the force above, so that report cycles compute the forces with the very same
      // instructions as the others (cycle() and advance(n) agree to the bit).
      const Doubles f2 = k_s * k_s * du2 + normal_part * (2.0 * k_s * du_n + normal_part);
      for (int l = 0; l < kLanes; ++l) force_norm[l] += 0.5 * __builtin_sqrt(f2[l]);
    }
  }
}

#pragma GCC diagnostic pop

}  // namespace plydem
