#pragma once
/// \file
/// The explicit integrator's backend interface: where its fused kernel's cycles run. The host
/// backend (ExplicitBackend::kCpu) is the integrator's own SIMD kernel. A device backend keeps a
/// copy of the kernel's arrays in its own memory for a whole run() and runs
/// solvers/particle_step.hpp once per particle and cycle: on a CUDA device
/// (solvers/cuda_backend.cu, built with -DPLYDEM_CUDA=ON), or on the host, one particle after
/// another (kDeviceEmulation: the device's code path, so that a machine without a GPU tests it
/// against the host kernel).
///
/// The integrator keeps the host arrays authoritative between runs: it uploads them at the start of
/// every run() and downloads them after every batch of cycles (ExplicitIntegrator::run checks and
/// hooks read the host copy), the bond table included when bonds can break.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "solvers/particle_step.hpp"

namespace plydem {

/// Where the explicit integrator's fused kernel runs (ExplicitSettings::backend).
enum class ExplicitBackend {
  kCpu,   ///< the host's SIMD kernel, OpenMP threads
  kCuda,  ///< a CUDA device (a build with -DPLYDEM_CUDA=ON and a device present)
  /// solvers/particle_step.hpp run on the host, one particle at a time: the CUDA kernel's code
  /// path without a device (for tests; slow)
  kDeviceEmulation,
};

/// "cpu", "cuda", "emulation".
const char* to_string(ExplicitBackend backend);
/// Parses "cpu", "cuda" or "emulation"; throws plydem::Error naming the accepted values.
ExplicitBackend parse_backend(const std::string& name);
/// The backends a user chooses from, as the command line's `--backend` and Python's `backend`
/// offer them: "cpu", "cuda". The emulation is the device's code path for tests and
/// plydem_kernel_bench, not offered there.
const std::vector<std::string>& backend_choices();
/// parse_backend for one of backend_choices(); throws plydem::Error naming them for anything else.
ExplicitBackend parse_backend_choice(const std::string& name);

/// The host arrays a device backend mirrors, in kernel order (see ParticleStepView).
struct DeviceArrays {
  int particles = 0;
  int padded = 0;
  int width = 0;
  int type_count = 0;
  int mode = kElasticMode;  ///< KernelMode
  double* displacement[2][3] = {};
  double* rotation[2][3] = {};
  double* velocity[3] = {};
  double* angular_velocity[3] = {};
  const double* inverse_mass = nullptr;
  const double* inverse_inertia = nullptr;
  const std::uint8_t* motion = nullptr;
  const MotionClass* classes = nullptr;
  int class_count = 0;
  const std::int32_t* neighbour = nullptr;
  const std::int32_t* type = nullptr;
  const HalfBondType* types = nullptr;
  // Breaking (mode != kElasticMode).
  const HalfBondFailure* failure = nullptr;
  const std::int32_t* slot_bond = nullptr;
  const double* slot_alpha = nullptr;  // strengths per slot
  const double* slot_beta = nullptr;
  const double* slot_tensile = nullptr;
  const double* slot_cohesion = nullptr;
  double* slot_damage = nullptr;  // softening
  double* slot_kappa = nullptr;
  double* work_sum = nullptr;
  double* damping_sum = nullptr;
  /// The last report cycle's forces and moments, kernel order (downloaded by download_state).
  double* force[3] = {};
  double* torque[3] = {};
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
  double bytes = 8.0 * (12 + 12 + 2) + 1 + 8.0 * width;
  if (mode != kElasticMode) bytes += 8.0 * 4;
  if (mode == kSofteningTypes || mode == kSofteningSlots) bytes += 8.0 * width;
  return bytes;
}

/// The host emulation of the device backend.
std::unique_ptr<DeviceBackend> make_emulation_backend();

}  // namespace plydem
