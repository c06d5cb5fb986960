#pragma once
/// \file
/// The explicit kernel's arrays, listed once. A backend holds them in kernel order (particle k is
/// model particle order[k]), padded to whole blocks of eight particles, in a store of its own:
/// the host's fused state keeps them in its own arrays and the bond table (solvers/
/// gather_backend.cpp) and hands the step a view of pointers (KernelView), the host emulation of
/// the device keeps std::vectors (solvers/device_backend.cpp), the CUDA backend device
/// allocations (solvers/cuda_backend.cu). for_each_kernel_array walks the list with what each
/// array is (its size, when a run needs it, when it moves between host and device), so that
/// allocating, uploading, downloading and counting bytes are each written once, for every store.
///
/// No Eigen and no vector extension here: nvcc compiles this header.

#include <cstddef>
#include <cstdint>

#include "contacts/half_bond.hpp"

namespace plydem {

/// A particle's motion class (KernelArrays::motion): 0 free, else an index into the classes. A
/// grip whose particles move each at its own velocity (a uniform strain) has a class per particle.
using MotionIndex = std::uint16_t;

/// What a prescribed motion does to a particle of its group (or to the one particle it names):
/// per component, a mask (-1 fixed, 0 free) and the imposed value.
struct MotionClass {
  std::int64_t fix_velocity[3] = {0, 0, 0};
  std::int64_t fix_angular_velocity[3] = {0, 0, 0};
  double velocity[3] = {0, 0, 0};
  double angular_velocity[3] = {0, 0, 0};
  std::int64_t free = -1;  // no translation fixed: counts in the unbalanced force
};

/// The report sums of one cycle, per particle (the device) or per block of eight (the host), in
/// this order: strain energy, bond force magnitude, 2 x kinetic energy, unbalanced force,
/// - F . v(n+1/2) (prescribed), damping . v(n+1/2) (free).
inline constexpr int kParticlePartials = 6;

/// How many elements an array has.
enum class ArrayExtent {
  kParticles,  ///< padded particles
  kCells,      ///< slots x padded particles (slot-major: [slot * padded + k])
  kTypes,      ///< half-bond types
  kClasses,    ///< motion classes
  kPartials,   ///< kParticlePartials x padded particles
};

/// When a run needs an array.
enum class ArrayUse { kAlways, kBreaking, kSlotStrengths, kSoftening };

/// How an array moves between the host's copy and a device's around a batch of cycles. Every
/// array a run uses is uploaded at the start of a run.
enum class ArrayFlow {
  kInput,      ///< read only
  kMotion,     ///< read only, uploaded again when the prescribed motions change
  kState,      ///< read and written: downloaded after every batch
  kReport,     ///< written by a report cycle: downloaded after every batch
  kSlotTypes,  ///< the table's types, emptied by breaks: downloaded beside the host's table
  kSlotState,  ///< softening state, written by breaking cycles: downloaded after breaking batches
  kScratch,    ///< the backend's own (report partials): neither uploaded nor downloaded
};

struct ArrayInfo {
  const char* name;  ///< in messages ("cudaMalloc of the displacements failed")
  ArrayExtent extent;
  ArrayUse use;
  ArrayFlow flow;
};

/// Whether a run of KernelMode `mode` uses an array of `use`.
constexpr bool uses(ArrayUse use, int mode) {
  switch (use) {
    case ArrayUse::kBreaking:
      return breaks_bonds(mode);
    case ArrayUse::kSlotStrengths:
      return has_slot_strengths(mode);
    case ArrayUse::kSoftening:
      return softens_bonds(mode);
    case ArrayUse::kAlways:
      break;
  }
  return true;
}

/// The sizes that fix every array's length.
struct KernelSizes {
  int particles = 0;  ///< real particles
  int padded = 0;     ///< particles rounded up to whole blocks of eight
  int width = 0;      ///< slots per particle
  int type_count = 0;
  int class_count = 0;
  int mode = kElasticMode;  ///< KernelMode

  std::size_t count(ArrayExtent extent) const {
    const std::size_t p = static_cast<std::size_t>(padded);
    switch (extent) {
      case ArrayExtent::kCells:
        return p * static_cast<std::size_t>(width);
      case ArrayExtent::kTypes:
        return static_cast<std::size_t>(type_count);
      case ArrayExtent::kClasses:
        return static_cast<std::size_t>(class_count);
      case ArrayExtent::kPartials:
        return p * kParticlePartials;
      case ArrayExtent::kParticles:
        break;
    }
    return p;
  }
};

/// The arrays, each a Store<T> (a pointer, a vector, a device allocation). Displacements and
/// rotations are double-buffered: a cycle reads buffer `parity` (every particle needs its
/// neighbours' state before the update) and writes the other. Add an array here and in
/// for_each_kernel_array below, and every backend has it.
template <template <class> class Store>
struct KernelArrays {
  Store<double> displacement[2][3], rotation[2][3];
  Store<double> velocity[3], angular_velocity[3];
  Store<double> inverse_mass, inverse_inertia;  ///< padding particles: 1, and they never move
  Store<MotionIndex> motion;                    ///< class per particle; 0 = free
  Store<MotionClass> classes;
  Store<std::int32_t> neighbour;  ///< per cell; a broken slot points at its own particle
  Store<std::int32_t> type;       ///< per cell; 0 = empty
  Store<HalfBondType> types;
  // Breaking.
  Store<HalfBondFailure> failure;  ///< per type
  Store<std::int32_t> slot_bond;   ///< per cell: 2 b (the bond's first end) or 2 b + 1
  /// Strengths per slot (StrengthStorage::kSlots): the first screen's constants and the exact
  /// law's strengths, per cell.
  Store<double> slot_alpha, slot_beta, slot_tensile, slot_cohesion;
  Store<double> slot_damage, slot_kappa;  ///< per cell, softening
  /// The energy account, per particle: - F (v_old + v_new) over prescribed components and
  /// damping (v_old + v_new) over free ones.
  Store<double> work_sum, damping_sum;
  // Report cycles.
  Store<double> force[3], torque[3];  ///< the bond (and contact) forces of the report cycle
  Store<double> partial;              ///< [q * padded + k], q < kParticlePartials
};

/// Calls f(info, a.x, b.x, ...) for every array x of the KernelArrays `a, b, ...` (each of any
/// store), always in this order.
template <class F, class... A>
constexpr void for_each_kernel_array(F&& f, A&... a) {
  using E = ArrayExtent;
  using U = ArrayUse;
  using W = ArrayFlow;
  for (int b = 0; b < 2; ++b) {
    for (int c = 0; c < 3; ++c) {
      f(ArrayInfo{"displacements", E::kParticles, U::kAlways, W::kState}, a.displacement[b][c]...);
      f(ArrayInfo{"rotations", E::kParticles, U::kAlways, W::kState}, a.rotation[b][c]...);
    }
  }
  for (int c = 0; c < 3; ++c) {
    f(ArrayInfo{"velocities", E::kParticles, U::kAlways, W::kState}, a.velocity[c]...);
    f(ArrayInfo{"angular velocities", E::kParticles, U::kAlways, W::kState},
      a.angular_velocity[c]...);
  }
  f(ArrayInfo{"inverse masses", E::kParticles, U::kAlways, W::kInput}, a.inverse_mass...);
  f(ArrayInfo{"inverse moments of inertia", E::kParticles, U::kAlways, W::kInput},
    a.inverse_inertia...);
  f(ArrayInfo{"the motion classes", E::kParticles, U::kAlways, W::kMotion}, a.motion...);
  f(ArrayInfo{"the prescribed motions", E::kClasses, U::kAlways, W::kMotion}, a.classes...);
  f(ArrayInfo{"the bond table's neighbours", E::kCells, U::kAlways, W::kInput}, a.neighbour...);
  f(ArrayInfo{"the bond table's types", E::kCells, U::kAlways, W::kSlotTypes}, a.type...);
  f(ArrayInfo{"the half-bond types", E::kTypes, U::kAlways, W::kInput}, a.types...);
  f(ArrayInfo{"the failure data", E::kTypes, U::kBreaking, W::kInput}, a.failure...);
  f(ArrayInfo{"the slots' bonds", E::kCells, U::kBreaking, W::kInput}, a.slot_bond...);
  f(ArrayInfo{"the slots' screen constants", E::kCells, U::kSlotStrengths, W::kInput},
    a.slot_alpha...);
  f(ArrayInfo{"the slots' screen constants", E::kCells, U::kSlotStrengths, W::kInput},
    a.slot_beta...);
  f(ArrayInfo{"the slots' tensile strengths", E::kCells, U::kSlotStrengths, W::kInput},
    a.slot_tensile...);
  f(ArrayInfo{"the slots' cohesions", E::kCells, U::kSlotStrengths, W::kInput}, a.slot_cohesion...);
  f(ArrayInfo{"the slots' damage", E::kCells, U::kSoftening, W::kSlotState}, a.slot_damage...);
  f(ArrayInfo{"the slots' kappa", E::kCells, U::kSoftening, W::kSlotState}, a.slot_kappa...);
  f(ArrayInfo{"the boundary work sums", E::kParticles, U::kBreaking, W::kState}, a.work_sum...);
  f(ArrayInfo{"the damping sums", E::kParticles, U::kBreaking, W::kState}, a.damping_sum...);
  for (int c = 0; c < 3; ++c) {
    f(ArrayInfo{"forces", E::kParticles, U::kAlways, W::kReport}, a.force[c]...);
    f(ArrayInfo{"torques", E::kParticles, U::kAlways, W::kReport}, a.torque[c]...);
  }
  f(ArrayInfo{"report partials", E::kPartials, U::kAlways, W::kScratch}, a.partial...);
}

template <class T>
using Pointer = T*;

/// The arrays as the step reads and writes them: pointers into a backend's store.
using KernelView = KernelArrays<Pointer>;

/// The number of arrays for_each_kernel_array visits.
constexpr int kernel_array_count() {
  int count = 0;
  KernelView v{};
  for_each_kernel_array([&count](const ArrayInfo&, auto&) { ++count; }, v);
  return count;
}
// Every field of KernelArrays is visited once: a field added to the struct but not to the walk
// (which every backend's copies rely on) fails to compile here.
static_assert(sizeof(KernelView) == kernel_array_count() * sizeof(void*),
              "for_each_kernel_array must visit every field of KernelArrays");

}  // namespace plydem
