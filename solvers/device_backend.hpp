#pragma once
/// \file
/// A device that runs the explicit kernel's cycles in its own memory: the CUDA backend
/// (solvers/cuda_backend.cu, built with -DPLYDEM_CUDA=ON) and its host emulation (one particle
/// after another, the device's code path on a machine without a GPU, so that tests hold it to the
/// host's SIMD kernel). Each keeps a copy of the kernel's arrays (solvers/kernel_arrays.hpp) for a
/// whole run and runs solvers/particle_step.hpp once per particle and cycle.
///
/// The integrator's mirrored backend (solvers/gather_backend.cpp) keeps the host arrays
/// authoritative between runs: it uploads them at the start of every run and downloads the state
/// after every batch of cycles (checks and hooks read the host copy), the bond table included when
/// bonds can break. The copies are written once for every store, over for_each_kernel_array
/// (upload_kernel_arrays and the others below): a store is any array type with upload(from, n,
/// what), download(to, n, what), zero(n, what), data() and size().

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "solvers/backend_kind.hpp"
#include "solvers/kernel_arrays.hpp"
#include "solvers/particle_step.hpp"

namespace plydem {

/// The host arrays a device mirrors, in kernel order, and their sizes.
struct DeviceArrays {
  KernelView view;
  KernelSizes sizes;
};

/// What one batch of cycles did (DeviceBackend::run_cycles).
struct DeviceBatch {
  long cycles = 0;        ///< run; fewer than asked when a cycle took a damage step
  bool reported = false;  ///< the report cycle ran: `sums` hold its report sums
  double sums[kParticlePartials] = {};
  std::vector<SlotEvent> events;  ///< the damage steps of the batch's last cycle (first ends)
};

class DeviceBackend {
 public:
  virtual ~DeviceBackend() = default;
  /// "CUDA device 0: NVIDIA H200 (...)" or "host emulation".
  virtual std::string describe() const = 0;
  /// Bytes the backend needs for `arrays` (an estimate, checked against free memory on upload).
  virtual std::size_t bytes_needed(const DeviceArrays& arrays) const = 0;
  /// Copies everything in, (re)allocating where sizes changed. Throws plydem::Error when the
  /// device has not the memory (naming what was needed and what is free).
  virtual void upload(const DeviceArrays& arrays) = 0;
  /// Copies the prescribed motions in again (after set_prescribed_motions during a run).
  virtual void upload_motions(const DeviceArrays& arrays) = 0;
  /// Up to `cycles` cycles from buffer `parity` (cycle numbers first_cycle, ...); stops after the
  /// first cycle that took a damage step. The last cycle reports when `report_last`.
  virtual DeviceBatch run_cycles(long cycles, int parity, bool report_last, long first_cycle,
                                 double dt, double alpha) = 0;
  /// Copies the state (both buffers, velocities, the last report's forces, the account's sums)
  /// back into `arrays`.
  virtual void download_state(const DeviceArrays& arrays) = 0;
  /// The bond table's types (and, softening, damage and kappa into `arrays`): `type` gets the
  /// width x padded types as the device holds them.
  virtual void download_table(const DeviceArrays& arrays, std::vector<std::int32_t>& type) = 0;
};

/// Copies every array a run of arrays.sizes.mode uses from the host into `own` (a
/// KernelArrays<Store> of the device's), (re)allocating as needed; the scratch arrays are zeroed.
template <class Own>
void upload_kernel_arrays(Own& own, const DeviceArrays& host) {
  for_each_kernel_array(
      [&](const ArrayInfo& info, auto& mine, auto* const& from) {
        if (!uses(info.use, host.sizes.mode)) return;
        const std::size_t n = host.sizes.count(info.extent);
        if (info.flow == ArrayFlow::kScratch || info.flow == ArrayFlow::kReport) {
          mine.zero(n, info.name);
        } else {
          mine.upload(from, n, info.name);
        }
      },
      own, host.view);
}

/// Copies the prescribed motions (ArrayFlow::kMotion) in again.
template <class Own>
void upload_motion_arrays(Own& own, const DeviceArrays& host) {
  for_each_kernel_array(
      [&](const ArrayInfo& info, auto& mine, auto* const& from) {
        if (info.flow == ArrayFlow::kMotion)
          mine.upload(from, host.sizes.count(info.extent), info.name);
      },
      own, host.view);
}

/// Copies the state, the report's forces and the account's sums back (ArrayFlow::kState,
/// kReport) into the host's arrays.
template <class Own>
void download_kernel_state(const Own& own, const DeviceArrays& host) {
  for_each_kernel_array(
      [&](const ArrayInfo& info, const auto& mine, auto* const& to) {
        if (!uses(info.use, host.sizes.mode)) return;
        if (info.flow == ArrayFlow::kState || info.flow == ArrayFlow::kReport)
          mine.download(to, host.sizes.count(info.extent), info.name);
      },
      own, host.view);
}

/// Copies the softening state (ArrayFlow::kSlotState) back into the host's arrays and the table's
/// types (ArrayFlow::kSlotTypes) into `types`.
template <class Own>
void download_kernel_table(const Own& own, const DeviceArrays& host,
                           std::vector<std::int32_t>& types) {
  for_each_kernel_array(
      [&](const ArrayInfo& info, const auto& mine, auto* const& to) {
        if (!uses(info.use, host.sizes.mode)) return;
        const std::size_t n = host.sizes.count(info.extent);
        if (info.flow == ArrayFlow::kSlotState) mine.download(to, n, info.name);
        if constexpr (std::is_same_v<std::remove_cvref_t<decltype(*to)>, std::int32_t>) {
          if (info.flow == ArrayFlow::kSlotTypes) {
            types.resize(n);
            mine.download(types.data(), n, info.name);
          }
        }
      },
      own, host.view);
}

/// Pointers into `own`: the view the device's step reads.
template <class Own>
KernelView kernel_view(Own& own) {
  KernelView view{};
  for_each_kernel_array([](const ArrayInfo&, auto& mine, auto*& to) { to = mine.data(); }, own,
                        view);
  return view;
}

/// The bytes of the arrays a run of sizes.mode uses.
inline std::size_t kernel_array_bytes(const KernelSizes& sizes) {
  std::size_t bytes = 0;
  KernelView view{};
  for_each_kernel_array(
      [&](const ArrayInfo& info, auto* const& pointer) {
        if (uses(info.use, sizes.mode)) bytes += sizes.count(info.extent) * sizeof(*pointer);
      },
      view);
  return bytes;
}

/// to = from[0 .. count) (compiled by the host compiler: nvcc's front end cannot instantiate a
/// vector of SlotEvent's reallocation).
void assign_events(std::vector<SlotEvent>& to, const SlotEvent* from, std::size_t count);

/// The CUDA backend on device 0. Throws plydem::Error when this build has no CUDA backend
/// (configure with -DPLYDEM_CUDA=ON) or no CUDA device can be used (naming why).
std::unique_ptr<DeviceBackend> make_cuda_backend();
/// Whether make_cuda_backend() would succeed; `why` gets the reason when it would not.
bool cuda_available(std::string* why = nullptr);
/// The CUDA device's copy bandwidth [bytes/s]: device-to-device copies of `bytes`, each counted as
/// 2 x bytes moved (read and write), the best of ten. The yardstick bench/gpu_check holds the
/// kernel's streamed bytes against. Throws plydem::Error as make_cuda_backend() does.
double cuda_copy_bandwidth(std::size_t bytes);

/// The bytes one cycle of particle_step must move to and from device memory per particle, if every
/// neighbour's state is read from cache (a lattice in kernel order): its own state read and the
/// next written (2 x 6 doubles), velocities read and written (2 x 6), the inverse mass and inertia,
/// its motion class, and per slot its type and neighbour (2 x 4 bytes); breaking adds the account's
/// two sums (read and written) and, softening, each slot's damage.
inline double streamed_bytes_per_particle(int width, int mode) {
  double bytes = 8.0 * (12 + 12 + 2) + sizeof(MotionIndex) + 8.0 * width;
  if (mode != kElasticMode) bytes += 8.0 * 4;
  if (mode == kSofteningTypes || mode == kSofteningSlots) bytes += 8.0 * width;
  return bytes;
}

/// The host emulation of the device backend.
std::unique_ptr<DeviceBackend> make_emulation_backend();

}  // namespace plydem
