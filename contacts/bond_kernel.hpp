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
///
/// Breaking (core/bond_failure.hpp). A GatherBonds built with breaking on also keeps, per half-bond
/// type, what the failure law needs (HalfBondFailure), and gather_half_bonds decides, at every
/// cycle, whether each bond breaks or softens, from the deformation it has just computed for the
/// force. Both ends of a bond decide alike because they compute the same numbers (see "Both ends
/// alike" at gather_half_bonds in contacts/half_bond.hpp), so each particle clears its own slot and
/// no thread writes another's memory. The reference loop decides through the same scalar functions
/// (bond_deformation, update_bond_damage).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <span>
#include <vector>

#include "contacts/half_bond.hpp"
#include "core/bond_failure.hpp"
#include "core/lane_ops.hpp"
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
/// implementation: one pass over the bonds, each adding to both of its particles. A broken bond
/// (Bonds::is_broken) carries nothing.
BondPass compute_bond_forces(Particles& particles, const Bonds& bonds);

/// compute_bond_forces over the listed bonds only (`bonds`, increasing), after zeroing the force
/// and torque of the listed particles only (`particles`, every end of a listed bond among them):
/// each particle's sum runs over its listed bonds in the whole pass's order, so a particle all of
/// whose bonds are listed gets the whole pass's bits (an MPI rank's own particles:
/// solvers/rank_exchange.hpp). With `each` (two per listed bond), also each listed bond's energy
/// and |F| there (zeros for a broken bond).
BondPass compute_listed_bond_forces(Particles& particles, const Bonds& bonds,
                                    std::span<const int> listed_bonds,
                                    std::span<const int> listed_particles,
                                    std::span<double> each = {});

/// The bonds' strain energy at the current state [J], without touching forces (broken bonds hold
/// none).
double bond_strain_energy(const Particles& particles, const Bonds& bonds);

/// The stress each particle carries at the current state [Pa], the site stress of failure at the
/// material point (issue 32): the virial of its bonds over the material volume it stands for,
///   sigma_p = (1 / V_p) sum over p's bonds of 1/2 sym(F (x) L),
/// F the bond's force on its first particle and L = length n the branch vector from the first to
/// the second (the same product seen from either end), each particle owning half of each of its
/// bonds, so that a uniform state is measured exactly. Bonds act through the reference loop's law
/// (compute_bond_forces); broken bonds carry nothing; a particle of zero volume gets zero.
/// `free_offsets` (one per bond, or empty: none) is each bond's free relative displacement: the
/// u_j - u_i at which it carries no force (an eigen displacement, such as the affine displacement
/// of a plastic strain: solvers/plastic_shear.hpp); a bond's force is then that of u_j - offset.
std::vector<Eigen::Matrix3d> particle_stresses(const Particles& particles, const Bonds& bonds,
                                               std::span<const Eigen::Vector3d> free_offsets = {});

/// Bond b's deformation at the particles' current state, for the reference loop. The lever term
/// (s_i theta_i + s_j theta_j) x n is written as (sigma (theta_i + theta_j) + delta (theta_j -
/// theta_i)) x n with sigma = (s_i + s_j) / 2 and delta = (s_j - s_i) / 2, the form the fused
/// kernel computes from either end alike (gather_half_bonds). With `du_out` and `dtheta_out`, also
/// writes du and dtheta there.
BondDeformation bond_deformation(const Particles& particles, const Bonds& bonds, int b,
                                 double* du_out = nullptr, double* dtheta_out = nullptr);

/// SIMD lanes: GCC vector extensions, which the compiler lowers to the instruction set of the
/// function being compiled (one AVX-512 register, two AVX2 registers, four SSE2 registers). Values
/// are passed by reference only, so no function boundary depends on the vector ABI.
// GCC 12 lowers a 64-byte vector to narrower registers piece by piece for instruction sets without
// AVX-512 and then warns that the pieces of a freshly built vector "may be used uninitialized".
#if defined(__GNUC__) && !defined(__clang__)  // Clang has no such warning
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace lanes {

inline constexpr int kCount = 8;
using Doubles = double __attribute__((vector_size(kCount * sizeof(double))));
using Mask = std::int64_t __attribute__((vector_size(kCount * sizeof(double))));

// Loads and stores through vector types that may alias double: one vector move each, straight
// to or from a register (through std::memcpy, GCC 12 split some of the kernel's vectors into
// 16-byte pieces on the stack and rebuilt them).
using AlignedDoubles [[gnu::may_alias]] =
    double __attribute__((vector_size(kCount * sizeof(double))));
using UnalignedDoubles [[gnu::may_alias, gnu::aligned(8)]] =
    double __attribute__((vector_size(kCount * sizeof(double))));
[[gnu::always_inline]] inline void load(const double* p, Doubles& v) {
  v = *reinterpret_cast<const AlignedDoubles*>(__builtin_assume_aligned(p, 64));
}
[[gnu::always_inline]] inline void store(double* p, const Doubles& v) {
  *reinterpret_cast<AlignedDoubles*>(__builtin_assume_aligned(p, 64)) = v;
}
[[gnu::always_inline]] inline void load_unaligned(const double* p, Doubles& v) {
  v = *reinterpret_cast<const UnalignedDoubles*>(p);
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
/// Whether any lane of a comparison's result is set.
[[gnu::always_inline]] inline bool any(const Mask& m) {
  std::int64_t a = 0;
  for (int l = 0; l < kCount; ++l) a |= m[l];
  return a != 0;
}
/// |v|, lane by lane (the sign bit cleared).
[[gnu::always_inline]] inline void abs(const Doubles& v, Doubles& out) {
  out = (Doubles)((Mask)v & ~(Mask{} + std::numeric_limits<std::int64_t>::min()));
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

/// Eight particles in the lanes of a vector (core/lane_ops.hpp). fmadd is the vector's a * b + c,
/// which GCC contracts into one vfmadd per vector in the kernel's AVX2 and AVX-512 clones (the host
/// kernel is compiled with GCC's default contraction); c passes through __builtin_assoc_barrier, so
/// that where c is itself a product (fmadd(a, b, x * y), the shared code's pattern) only a * b can
/// be fused with the sum, as the scalar fmadd does, and x * y stays a rounded product.
/// test_cuda_backend checks that this gives the device's bits. GCC 12 fuses them here from -O2 on
/// (the sanitizer tree, built at -O1, compiles solvers/cpu_backend.cpp at -O2: CMakeLists.txt); an
/// unoptimized build (-O0) takes the lane-by-lane form below, exact at any level. Written lane by
/// lane with the scalar builtin instead, GCC kept much of the step in scalar registers and the
/// Table 2 coupon ran at a third of this speed. The baseline x86-64 clone (processors without FMA)
/// fuses nothing: there the host kernel's last bits differ from the device's. Every other operation
/// is the vector's own, lane by lane. The functions take and return vectors by value, which would
/// change the ABI of a call between instruction sets (GCC's -Wpsabi, off in the build), but they
/// are always inlined: no call remains.
template <>
struct LaneOps<lanes::Doubles> {
  using Doubles = lanes::Doubles;
  using Mask = lanes::Mask;
  [[gnu::always_inline]] static Doubles fmadd(const Doubles& a, const Doubles& b,
                                              const Doubles& c) {
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12 && defined(__OPTIMIZE__)
    return a * b + __builtin_assoc_barrier(c);
#else
    Doubles r;
    for (int l = 0; l < lanes::kCount; ++l) r[l] = __builtin_fma(a[l], b[l], c[l]);
    return r;
#endif
  }
  [[gnu::always_inline]] static Doubles fmadd(double a, const Doubles& b, const Doubles& c) {
    return fmadd(a - Doubles{}, b, c);  // a in every lane (exact, -0 included)
  }
  [[gnu::always_inline]] static Doubles select(const Mask& m, const Doubles& a, const Doubles& b) {
    return (Doubles)(((Mask)a & m) | ((Mask)b & ~m));  // bitwise: no branches
  }
  [[gnu::always_inline]] static Doubles keep(const Doubles& x, const Mask& m) {
    return (Doubles)((Mask)x & m);
  }
  [[gnu::always_inline]] static Doubles keep_unless(const Doubles& x, const Mask& m) {
    return (Doubles)((Mask)x & ~m);
  }
  [[gnu::always_inline]] static Doubles abs(const Doubles& x) {
    Doubles r;
    lanes::abs(x, r);
    return r;
  }
  [[gnu::always_inline]] static Doubles sqrt(const Doubles& x) {
    Doubles r;
    for (int l = 0; l < lanes::kCount; ++l) r[l] = __builtin_sqrt(x[l]);
    return r;
  }
  /// |magnitude| with the sign bit of v, built from bits (exact; no per-lane branch), and +0 where
  /// v is zero.
  [[gnu::always_inline]] static Doubles signed_like(const Doubles& magnitude, const Doubles& v) {
    const Mask sign_bit = Mask{} + std::numeric_limits<std::int64_t>::min();
    const Doubles with_sign = (Doubles)((Mask)magnitude | ((Mask)v & sign_bit));
    return v == Doubles{} ? Doubles{} : with_sign;
  }
  [[gnu::always_inline]] static bool any(const Mask& m) {
    return lanes::any(m);
  }
};

/// A HalfBondType with every parameter repeated in all lanes: what a block whose eight particles
/// share the type of a slot loads (plain vector loads; no broadcasts in the loop).
struct alignas(64) HalfBondLanes {
  lanes::Doubles normal[3];
  lanes::Doubles lever_own, lever_other, shear_stiffness, lever_shear, normal_excess,
      bending_stiffness, twisting_excess;
};

/// HalfBondFailure's kernel fields repeated in all lanes (a block whose particles share a type).
struct alignas(64) HalfBondFailureLanes {
  lanes::Doubles lever_mean, lever_half_difference, normal_stiffness, screen_displacement,
      screen_rotation, tension_threshold, shear_threshold, shear_friction, bending_factor,
      twisting_factor, shear_stiffness_squared;
};

/// Where a breaking GatherBonds keeps the bonds' strengths.
enum class StrengthStorage {
  /// Per type where the bonds take at most kMaxTypeStrengths distinct strengths (bond families
  /// with uniform strengths), else per slot.
  kAutomatic,
  kTypes,  ///< in the half-bond types: a bond of its own strength is a type of its own
  kSlots,  ///< tensile strength and cohesion (and the screen's constants) in per-slot arrays
};

/// The most distinct bond strengths StrengthStorage::kAutomatic keeps in the types.
inline constexpr int kMaxTypeStrengths = 64;

/// What a GatherBonds keeps for breaking.
struct GatherBreaking {
  bool enabled = false;
  /// Per-slot damage and kappa, scaling the slot's stiffness: needed when a bond may soften
  /// (ductility > 1) or starts damaged.
  bool softening = false;
  StrengthStorage storage = StrengthStorage::kAutomatic;
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
  /// permutation of the particles, or if a bond refers to a missing particle. Broken bonds
  /// (Bonds::is_broken) get no slot. The two half-bond types of a bond are exact mirror images
  /// (normal negated, levers swapped, the same stiffnesses and strength), so that both ends
  /// compute the same numbers. With `breaking.enabled` the types hold intact stiffnesses
  /// (current / (1 - damage)) and the failure data (HalfBondFailure), and every slot knows its
  /// bond (slot_bond).
  GatherBonds(const Bonds& bonds, const std::vector<int>& order,
              const GatherBreaking& breaking = {});

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

  // --- breaking (a table built with GatherBreaking::enabled) ---
  bool breaking() const { return breaking_; }
  bool softening() const { return softening_; }
  bool slot_strengths() const { return slot_strengths_; }
  const HalfBondFailure& failure(int t) const { return failure_[t]; }
  HalfBondFailure& failure(int t) { return failure_[t]; }
  /// The failure lanes of uniform type u (the same index as uniform_lanes).
  const HalfBondFailureLanes& failure_lanes(int u) const { return failure_uniform_[u]; }
  /// The cell of slot s of kernel particle k in the per-slot arrays: s * padded_count() + k.
  std::size_t cell(int slot, int k) const { return static_cast<std::size_t>(slot) * padded_ + k; }
  /// The model bond of a cell, 2 b for the bond's first end and 2 b + 1 for its second; -1 for a
  /// cell that never held a bond.
  std::int32_t slot_bond(std::size_t cell) const { return slot_bond_[cell]; }
  /// The cells of bond b's first and second ends (-1 if the bond has no slot: it was broken when
  /// the table was built).
  std::array<std::int64_t, 2> bond_cells(int b) const { return bond_cells_[b]; }
  /// Whether a cell still holds its bond.
  bool holds(std::size_t cell) const { return type_[cell] != 0; }
  /// Strengths per slot (slot_strengths()): the screen's alpha, beta and thresholds, and the
  /// tensile strength and cohesion the exact law reads, per cell.
  const double* slot_screen_displacement() const { return slot_alpha_.data(); }
  const double* slot_screen_rotation() const { return slot_beta_.data(); }
  const double* slot_tension_threshold() const { return slot_tension_.data(); }
  const double* slot_shear_threshold() const { return slot_shear_.data(); }
  double slot_tensile_strength(std::size_t cell) const { return slot_tensile_[cell]; }
  /// The per-cell arrays whole (a device backend copies them): slot_bond, the tensile strengths
  /// and cohesions per slot.
  const std::int32_t* slot_bonds() const { return slot_bond_.data(); }
  const double* slot_tensile_strengths() const { return slot_tensile_.data(); }
  const double* slot_cohesions() const { return slot_cohesion_.data(); }
  double slot_cohesion(std::size_t cell) const { return slot_cohesion_[cell]; }
  /// Softening (softening()): per cell, the bond's damage and kappa as this end holds them.
  double* slot_damage() { return slot_damage_.data(); }
  const double* slot_damage() const { return slot_damage_.data(); }
  double* slot_kappa() { return slot_kappa_.data(); }
  const double* slot_kappa() const { return slot_kappa_.data(); }
  /// Empties slot `slot` of kernel particle `own` (type 0, neighbour = own, damage 1) and updates
  /// its block's block_types() and block_runs() for that slot. Touches only `own`'s block, so the
  /// thread that owns the block may call it while others run theirs.
  void clear_slot(int own, int slot);

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
  // Breaking.
  bool breaking_ = false, softening_ = false, slot_strengths_ = false;
  std::vector<HalfBondFailure> failure_;                             // [type]
  std::vector<HalfBondFailureLanes> failure_uniform_;                // [uniform type]
  std::vector<std::int32_t> slot_bond_;                              // [cell]
  std::vector<std::array<std::int64_t, 2>> bond_cells_;              // [model bond]
  lanes::Array slot_alpha_, slot_beta_, slot_tension_, slot_shear_;  // [cell], strengths per slot
  std::vector<double> slot_tensile_, slot_cohesion_;                 // [cell], strengths per slot
  lanes::Array slot_damage_, slot_kappa_;                            // [cell], softening

  // The constructor's steps (bond_kernel.cpp).
  struct Ends;
  std::vector<int> assign_types(const Bonds& bonds, const std::vector<int>& kernel_index,
                                const std::vector<Eigen::Vector3d>& directions, Ends& ends);
  void lay_out_slots(const Ends& ends, const std::vector<Eigen::Vector3d>& directions,
                     std::vector<int>& type_direction);
  void fill_cells(const Ends& ends, const std::vector<int>& type_slot, int bond_count);
  void share_uniform_types();
  void fill_slot_state(const Bonds& bonds);
};

/// Displacements and rotations in kernel order: component c of particle k is `displacement[c][k]`.
struct GatherState {
  const double* displacement[3];
  const double* rotation[3];
};

/// What one thread's breaking pass writes besides forces.
struct BreakingPass {
  std::vector<SlotEvent>* events = nullptr;  ///< this thread's damage steps (first ends only)
  long cycle = 0;
  bool changed = false;  ///< a slot of this pass broke or softened (either end)
};

/// The exact failure law (update_bond_damage) for slot `slot` of kernel particle `k`, at the
/// deformation the kernel computed (du, dtheta and n of that end, as gather_half_bonds has them):
/// updates the slot's damage and kappa (softening), clears the slot if the bond breaks
/// (GatherBonds::clear_slot), and, at the bond's first end, logs the step in `pass`. `u_own` is
/// k's displacement.
void assess_slot(GatherBonds& g, int k, int slot, const double du[3], const double dtheta[3],
                 const double n[3], const double u_own[3], BreakingPass& pass);

/// The second screen of the host's breaking kernel (see HalfBondFailure), for the lanes `near` of
/// one slot, and the exact law where it holds.
template <bool kSoften, bool kSlotStrength>
[[gnu::always_inline]] inline void screen_slot(
    GatherBonds& g, int first, int slot, std::int32_t uniform_type, const lanes::Doubles (&n)[3],
    const HalfBondMotion<lanes::Doubles>& m, const lanes::Doubles (&dt)[3], const lanes::Mask& near,
    const lanes::Doubles (&u_i)[3], BreakingPass& pass) {
  using lanes::Doubles;
  using lanes::Mask;
  using Ops = LaneOps<Doubles>;
  constexpr int kLanes = lanes::kCount;
  Doubles k_n{}, tension{}, shear{}, friction{}, bending{}, twisting{}, shear_stiffness2{};
  if (uniform_type > 0) {
    const HalfBondFailureLanes& f = g.failure_lanes(uniform_type);
    k_n = f.normal_stiffness;
    tension = f.tension_threshold;
    shear = f.shear_threshold;
    friction = f.shear_friction;
    bending = f.bending_factor;
    twisting = f.twisting_factor;
    shear_stiffness2 = f.shear_stiffness_squared;
  } else {
    const std::int32_t* type = g.types(slot) + first;
    for (int l = 0; l < kLanes; ++l) {
      const HalfBondFailure& f = g.failure(type[l]);
      k_n[l] = f.normal_stiffness;
      tension[l] = f.tension_threshold;
      shear[l] = f.shear_threshold;
      friction[l] = f.shear_friction;
      bending[l] = f.bending_factor;
      twisting[l] = f.twisting_factor;
      shear_stiffness2[l] = f.shear_stiffness_squared;
    }
  }
  const std::size_t cell = g.cell(slot, first);
  if constexpr (kSlotStrength) {
    lanes::load(g.slot_tension_threshold() + cell, tension);
    lanes::load(g.slot_shear_threshold() + cell, shear);
  }
  Doubles kappa = Doubles{} + 1.0;
  if constexpr (kSoften) lanes::load(g.slot_kappa() + cell, kappa);
  // The squared norms of du_s = n x du (no cancellation) and dtheta_s, each raised by a slack of
  // 1e-12 |.|^2 that covers the rounding of the scalar law's own du - du_n n.
  constexpr double kSlack = 1e-12;
  const Doubles zero{};
  const Doubles f_n = k_n * m.du_n;
  const Doubles shear2 = Ops::fmadd(
      kSlack, m.du2,
      Ops::fmadd(m.n_cross_du[2], m.n_cross_du[2],
                 Ops::fmadd(m.n_cross_du[1], m.n_cross_du[1], m.n_cross_du[0] * m.n_cross_du[0])));
  const Doubles bend2 = Ops::fmadd(1.0 + kSlack, m.dt2, -(m.dt_n * m.dt_n));
  // Tension: F_n + (4/R) |M_b| >= kappa T_t. Shear: |F_s| + (2/R) |M_t| >= kappa (T_c - tan(phi)
  // F_n).
  const Doubles x = Ops::fmadd(kappa, tension, -f_n);
  const Mask tension_near = (x <= zero) | (bending * bend2 >= x * x);
  const Doubles y =
      Ops::fmadd(kappa, Ops::fmadd(-friction, f_n, shear), -(twisting * Ops::abs(m.dt_n)));
  const Mask shear_near = (y <= zero) | (shear_stiffness2 * shear2 >= y * y);
  const Mask check = near & (tension_near | shear_near);
  if (!lanes::any(check)) return;
  for (int l = 0; l < kLanes; ++l) {
    if (!check[l]) continue;
    const double du_l[3] = {m.du[0][l], m.du[1][l], m.du[2][l]};
    const double dt_l[3] = {dt[0][l], dt[1][l], dt[2][l]};
    const double n_l[3] = {n[0][l], n[1][l], n[2][l]};
    const double u_l[3] = {u_i[0][l], u_i[1][l], u_i[2][l]};
    assess_slot(g, first + l, slot, du_l, dt_l, n_l, u_l, pass);
  }
}

/// The host's bond table seen from one block of lanes::kCount particles (first .. first + 7): the
/// `Slots` of gather_half_bonds (contacts/half_bond.hpp). A slot that no particle of the block
/// uses is skipped; a slot whose eight particles share a type loads its parameters as whole
/// vectors (GatherBonds::uniform_lanes), and one whose other ends are consecutive loads their
/// state as vectors; the rest is gathered lane by lane. An empty lane (type 0) computes a zero
/// force, which adds +0 to sums that are never -0. Breaking: the two screens of HalfBondFailure
/// (screen_measure, then screen_slot) and, where both hold, the exact law (assess_slot).
class BlockSlots {
 public:
  using Lane = lanes::Doubles;
  BlockSlots(GatherBonds& g, int first, const GatherState& s, BreakingPass* pass)
      : g_(g),
        first_(first),
        state_(s),
        pass_(pass),
        block_type_(g.block_types(first / lanes::kCount)),
        block_run_(g.block_runs(first / lanes::kCount)) {}

  [[gnu::always_inline]] int width() const { return g_.width(); }
  [[gnu::always_inline]] bool empty(int slot) const { return block_type_[slot] == 0; }

  [[gnu::always_inline]] void other_state(int slot, Lane (&u_j)[3], Lane (&t_j)[3]) const {
    const std::int32_t run = block_run_[slot];
    if (run >= 0) {  // the other ends are consecutive particles: plain loads
      for (int c = 0; c < 3; ++c) {
        lanes::load_unaligned(state_.displacement[c] + run, u_j[c]);
        lanes::load_unaligned(state_.rotation[c] + run, t_j[c]);
      }
    } else {
      const std::int32_t* other = g_.neighbours(slot) + first_;
      for (int c = 0; c < 3; ++c) {
        lanes::gather(state_.displacement[c], other, u_j[c]);
        lanes::gather(state_.rotation[c], other, t_j[c]);
      }
    }
  }

  template <int kMode>
  [[gnu::always_inline]] void load(int slot, HalfBondLoad<Lane>& h) const {
    const std::int32_t uniform_type = block_type_[slot];
    if (uniform_type > 0) {
      const HalfBondFailureLanes* f =
          breaks_bonds(kMode) ? &g_.failure_lanes(uniform_type) : nullptr;
      load_half_bond<kMode>(g_.uniform_lanes(uniform_type), f, h);
    } else {
      const std::int32_t* type = g_.types(slot) + first_;
      for (int l = 0; l < lanes::kCount; ++l) load_lane<kMode>(g_.type(type[l]), type[l], l, h);
    }
    if constexpr (has_slot_strengths(kMode)) {
      lanes::load(g_.slot_screen_displacement() + g_.cell(slot, first_), h.screen_displacement);
      lanes::load(g_.slot_screen_rotation() + g_.cell(slot, first_), h.screen_rotation);
    }
  }

  [[gnu::always_inline]] void damage(int slot, Lane& d) const {
    lanes::load(g_.slot_damage() + g_.cell(slot, first_), d);
  }

  template <int kMode>
  [[gnu::always_inline]] void assess(int slot, const Lane& measure, const Lane (&n)[3],
                                     const HalfBondMotion<Lane>& m, const Lane (&dt)[3],
                                     const Lane (&u_i)[3]) {
    const lanes::Mask near = measure >= Lane{} + (1.0 - kScreenBound);
    if (__builtin_expect(lanes::any(near), 0)) {
      screen_slot<softens_bonds(kMode), has_slot_strengths(kMode)>(
          g_, first_, slot, block_type_[slot], n, m, dt, near, u_i, *pass_);
    }
  }

 private:
  template <int kMode>
  [[gnu::always_inline]] void load_lane(const HalfBondType& t, std::int32_t type, int l,
                                        HalfBondLoad<Lane>& h) const {
    for (int c = 0; c < 3; ++c) h.normal[c][l] = t.normal[c];
    h.shear_stiffness[l] = t.shear_stiffness;
    h.lever_shear[l] = t.lever_shear;
    h.normal_excess[l] = t.normal_excess;
    h.bending_stiffness[l] = t.bending_stiffness;
    h.twisting_excess[l] = t.twisting_excess;
    if constexpr (breaks_bonds(kMode)) {
      const HalfBondFailure& f = g_.failure(type);
      h.lever_a[l] = f.lever_mean;
      h.lever_b[l] = f.lever_half_difference;
      if constexpr (!has_slot_strengths(kMode)) {
        h.screen_displacement[l] = f.screen_displacement;
        h.screen_rotation[l] = f.screen_rotation;
      }
    } else {
      h.lever_a[l] = t.lever_own;
      h.lever_b[l] = t.lever_other;
    }
  }

  GatherBonds& g_;
  int first_;
  const GatherState& state_;
  BreakingPass* pass_;
  const std::int32_t* block_type_;
  const std::int32_t* block_run_;
};

/// Force and moment on the block of particles first .. first + lanes::kCount - 1 (first a multiple
/// of lanes::kCount) from all their bonds (gather_half_bonds over BlockSlots), added to `force`
/// and `torque`. With kEnergy, also adds half of each bond's strain energy and half its force
/// magnitude (each bond is seen from both ends) to `energy` and `force_norm`. Inlined into the
/// caller, so that it is compiled for the caller's instruction set (the explicit integrator's
/// steps run the same loop through solvers/particle_step.hpp, solvers/cpu_backend.cpp).
template <bool kEnergy>
[[gnu::always_inline]] inline void gather_bond_block(
    const GatherBonds& g, int first, const GatherState& s, lanes::Doubles (&force)[3],
    lanes::Doubles (&torque)[3], lanes::Doubles& energy, lanes::Doubles& force_norm) {
  lanes::Doubles u_i[3], t_i[3];
  for (int c = 0; c < 3; ++c) {
    lanes::load(s.displacement[c] + first, u_i[c]);
    lanes::load(s.rotation[c] + first, t_i[c]);
  }
  // The elastic loop reads the table only (it writes it when bonds break).
  BlockSlots slots(const_cast<GatherBonds&>(g), first, s, nullptr);
  gather_half_bonds<kEnergy, kElasticMode>(slots, u_i, t_i, force, torque, energy, force_norm);
}

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

}  // namespace plydem
