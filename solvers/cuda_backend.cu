// The CUDA backend of the explicit integrator (solvers/device_backend.hpp): one thread per
// particle runs solvers/particle_step.hpp, the same code the host emulation runs and the same
// half-bond and failure-law templates the host's SIMD kernel runs (contacts/half_bond.hpp), in
// fp64, compiled with -fmad=false so that no multiply-add is fused where the host rounds twice.
//
// Gather form: a thread writes only its own particle's state, velocities, forces and slots, so the
// forces need no atomics and a run is bitwise reproducible. Every array stays on the device for a
// whole batch of cycles; one kernel launch per cycle (a launch is the grid-wide barrier the
// double-buffered state needs). A cycle that takes a damage step sets `stop`, and the kernels of
// the batch's later cycles return at once, so the host sees the state just after that cycle, as
// the host kernel stops there. The report sums are reduced on the device in a fixed order: each
// block of eight particles in lane order (the host kernel's block partials), then a fixed tree over
// the blocks; no atomics on doubles anywhere. The event log's counter is the one atomic (an
// unsigned int); the integrator sorts the log by cycle and bond.
//
// Errors: every CUDA call is checked and a failure is a plydem::Error naming the call; memory is
// estimated and compared with cudaMemGetInfo before anything is allocated.
#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "solvers/device_backend.hpp"
#include "solvers/particle_step.hpp"

namespace plydem {
namespace {

// fmt's headers do not pass nvcc's front end: messages are put together with a stream.
template <class... Parts>
std::string text(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

void check(cudaError_t status, const std::string& what) {
  if (status != cudaSuccess)
    throw Error(text("CUDA backend: ", what, " failed: ", cudaGetErrorString(status), " (",
                     cudaGetErrorName(status), ")"));
}

constexpr int kThreads = 256;  // per block of threads; 8 warps

// Bytes this process holds on the device through DeviceArray (one backend at a time in practice).
std::size_t allocated_bytes = 0;
constexpr int kReduceThreads = 256;

// One device allocation, freed with its owner.
template <class T>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (data_) {
      cudaFree(data_);  // no throw from a destructor
      allocated_bytes -= size_ * sizeof(T);
    }
  }
  void resize(std::size_t n, const char* what) {
    if (n == size_ && data_) return;
    if (data_) {
      check(cudaFree(data_), "cudaFree");
      allocated_bytes -= size_ * sizeof(T);
    }
    data_ = nullptr;
    size_ = 0;
    if (n == 0) return;
    check(cudaMalloc(reinterpret_cast<void**>(&data_), n * sizeof(T)),
          text("cudaMalloc of ", what, " (", n * sizeof(T), " bytes)"));
    size_ = n;
    allocated_bytes += n * sizeof(T);
  }
  void upload(const T* from, std::size_t n, const char* what) {
    resize(n, what);
    if (n) check(cudaMemcpy(data_, from, n * sizeof(T), cudaMemcpyHostToDevice), what);
  }
  void download(T* to, std::size_t n, const char* what) const {
    if (n) check(cudaMemcpy(to, data_, n * sizeof(T), cudaMemcpyDeviceToHost), what);
  }
  void zero(std::size_t n, const char* what) {
    resize(n, what);
    if (n) check(cudaMemset(data_, 0, n * sizeof(T)), what);
  }
  T* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

template <bool kReport, int kMode>
__global__ void step_kernel(ParticleStepView v) {
  // A cycle after one that took a damage step does nothing (stop is the batch's first such cycle
  // + 1; a thread of this cycle may be writing this cycle's number + 1 meanwhile, which is later).
  const int stop = *static_cast<volatile int*>(v.stop);
  if (stop != 0 && stop <= v.batch_cycle) return;
  const long k = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k >= v.padded) return;
  particle_step<kReport, kMode>(v, static_cast<int>(k));
}

// The host kernel's block partials: sums[q * blocks + b] for the eight particles of block b.
__global__ void block_partials_kernel(const double* partial, int padded, double* sums) {
  const int blocks = padded / 8;
  const long b = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (b >= blocks) return;
  for (int q = 0; q < kParticlePartials; ++q)
    sums[static_cast<std::size_t>(q) * blocks + b] =
        block_partial(partial, padded, q, static_cast<int>(b));
}

// One fixed-order tree per report sum (block q of the grid reduces sum q): thread t adds the block
// partials t, t + n, t + 2n, ... in order, then the threads' sums meet in a binary tree.
__global__ void reduce_kernel(const double* sums, int blocks, double* out) {
  __shared__ double part[kReduceThreads];
  const int q = blockIdx.x;
  const double* s = sums + static_cast<std::size_t>(q) * blocks;
  double mine = 0;
  for (int b = threadIdx.x; b < blocks; b += kReduceThreads) mine += s[b];
  part[threadIdx.x] = mine;
  __syncthreads();
  for (int half = kReduceThreads / 2; half > 0; half /= 2) {
    if (static_cast<int>(threadIdx.x) < half) part[threadIdx.x] += part[threadIdx.x + half];
    __syncthreads();
  }
  if (threadIdx.x == 0) out[q] = part[0];
}

template <bool kReport>
void launch_step(int mode, const ParticleStepView& v, int grid) {
  switch (mode) {
    case kBrittleTypes:
      step_kernel<kReport, kBrittleTypes><<<grid, kThreads>>>(v);
      break;
    case kBrittleSlots:
      step_kernel<kReport, kBrittleSlots><<<grid, kThreads>>>(v);
      break;
    case kSofteningTypes:
      step_kernel<kReport, kSofteningTypes><<<grid, kThreads>>>(v);
      break;
    case kSofteningSlots:
      step_kernel<kReport, kSofteningSlots><<<grid, kThreads>>>(v);
      break;
    default:
      step_kernel<kReport, kElasticMode><<<grid, kThreads>>>(v);
  }
}

bool is_breaking(int mode) {
  return mode != kElasticMode;
}
bool has_slot_strengths(int mode) {
  return mode == kBrittleSlots || mode == kSofteningSlots;
}
bool is_softening(int mode) {
  return mode == kSofteningTypes || mode == kSofteningSlots;
}

// The event log's capacity: every bond's first end may log one step per cycle, and a batch stops
// after the first cycle with a step, so one per bond would always do; it is capped (a cycle that
// breaks more bonds at once than this is reported as an error, not dropped).
constexpr std::size_t kMaxEvents = std::size_t{1} << 20;

class CudaBackend final : public DeviceBackend {
 public:
  CudaBackend() {
    check(cudaSetDevice(0), "cudaSetDevice(0)");
    cudaDeviceProp prop{};
    check(cudaGetDeviceProperties(&prop, 0), "cudaGetDeviceProperties");
    name_ = text("CUDA device 0: ", prop.name, " (compute capability ", prop.major, ".", prop.minor,
                 ", ", prop.totalGlobalMem >> 20, " MiB)");
  }

  std::string describe() const override { return name_; }

  std::size_t bytes_needed(const DeviceArrays& a) const override {
    const std::size_t p = static_cast<std::size_t>(a.padded);
    const std::size_t cells = p * static_cast<std::size_t>(a.width);
    // State (2 x 6), velocities (6), inverse masses (2), report forces (6), partials (6), block
    // partials (6 / 8), motion classes (1 byte); the table's neighbours and types.
    std::size_t bytes = p * sizeof(double) * (12 + 6 + 2 + 6 + kParticlePartials) +
                        p * kParticlePartials + p + cells * 2 * sizeof(std::int32_t) +
                        static_cast<std::size_t>(a.type_count) * sizeof(HalfBondType);
    if (is_breaking(a.mode)) {
      bytes += 2 * p * sizeof(double) + cells * sizeof(std::int32_t) +
               static_cast<std::size_t>(a.type_count) * sizeof(HalfBondFailure) +
               event_capacity(a) * sizeof(SlotEvent);
    }
    if (has_slot_strengths(a.mode)) bytes += 4 * cells * sizeof(double);
    if (is_softening(a.mode)) bytes += 2 * cells * sizeof(double);
    return bytes;
  }

  void upload(const DeviceArrays& a) override {
    require(a.padded % 8 == 0, "CUDA backend: the kernel's particles come in blocks of eight");
    const std::size_t needed = bytes_needed(a);
    std::size_t free = 0, total = 0;
    check(cudaMemGetInfo(&free, &total), "cudaMemGetInfo");
    const std::size_t held = allocated_bytes;  // what re-uploading into them frees
    require(needed <= free + held,
            text("CUDA backend: the model needs ", needed * 1e-9, " GB of device memory, ",
                 (free + held) * 1e-9, " GB of the device's ", total * 1e-9, " GB are free"));
    arrays_ = a;
    const std::size_t p = static_cast<std::size_t>(a.padded);
    const std::size_t cells = p * static_cast<std::size_t>(a.width);
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 3; ++c) {
        displacement_[b][c].upload(a.displacement[b][c], p, "displacements");
        rotation_[b][c].upload(a.rotation[b][c], p, "rotations");
      }
    for (int c = 0; c < 3; ++c) {
      velocity_[c].upload(a.velocity[c], p, "velocities");
      angular_velocity_[c].upload(a.angular_velocity[c], p, "angular velocities");
      force_[c].zero(p, "forces");
      torque_[c].zero(p, "torques");
    }
    inverse_mass_.upload(a.inverse_mass, p, "inverse masses");
    inverse_inertia_.upload(a.inverse_inertia, p, "inverse moments of inertia");
    neighbour_.upload(a.neighbour, cells, "the bond table's neighbours");
    type_.upload(a.type, cells, "the bond table's types");
    types_.upload(a.types, static_cast<std::size_t>(a.type_count), "the half-bond types");
    partial_.zero(p * kParticlePartials, "report partials");
    block_sums_.zero(p / 8 * kParticlePartials, "report block sums");
    sums_.zero(kParticlePartials, "report sums");
    stop_.zero(1, "the stop flag");
    event_count_.zero(1, "the event counter");
    if (is_breaking(a.mode)) {
      failure_.upload(a.failure, static_cast<std::size_t>(a.type_count), "the failure data");
      slot_bond_.upload(a.slot_bond, cells, "the slots' bonds");
      work_sum_.upload(a.work_sum, p, "the boundary work sums");
      damping_sum_.upload(a.damping_sum, p, "the damping sums");
      events_.resize(event_capacity(a), "the event log");
    }
    if (has_slot_strengths(a.mode)) {
      slot_alpha_.upload(a.slot_alpha, cells, "the slots' screen constants");
      slot_beta_.upload(a.slot_beta, cells, "the slots' screen constants");
      slot_tensile_.upload(a.slot_tensile, cells, "the slots' tensile strengths");
      slot_cohesion_.upload(a.slot_cohesion, cells, "the slots' cohesions");
    }
    if (is_softening(a.mode)) {
      slot_damage_.upload(a.slot_damage, cells, "the slots' damage");
      slot_kappa_.upload(a.slot_kappa, cells, "the slots' kappa");
    }
    upload_motions(a);
  }

  void upload_motions(const DeviceArrays& a) override {
    motion_.upload(a.motion, static_cast<std::size_t>(a.padded), "the motion classes");
    classes_.upload(a.classes, static_cast<std::size_t>(a.class_count), "the prescribed motions");
  }

  DeviceBatch run_cycles(long cycles, int parity, bool report_last, long first_cycle, double dt,
                         double alpha) override {
    ParticleStepView v;
    v.padded = arrays_.padded;
    v.width = arrays_.width;
    for (int c = 0; c < 3; ++c) {
      v.velocity[c] = velocity_[c].data();
      v.angular_velocity[c] = angular_velocity_[c].data();
      v.force_out[c] = force_[c].data();
      v.torque_out[c] = torque_[c].data();
    }
    v.inverse_mass = inverse_mass_.data();
    v.inverse_inertia = inverse_inertia_.data();
    v.motion = motion_.data();
    v.classes = classes_.data();
    v.neighbour = neighbour_.data();
    v.type = type_.data();
    v.types = types_.data();
    v.dt = dt;
    v.alpha = alpha;
    v.failure = failure_.data();
    v.slot_bond = slot_bond_.data();
    v.slot_alpha = slot_alpha_.data();
    v.slot_beta = slot_beta_.data();
    v.slot_tensile = slot_tensile_.data();
    v.slot_cohesion = slot_cohesion_.data();
    v.slot_damage = slot_damage_.data();
    v.slot_kappa = slot_kappa_.data();
    v.work_sum = work_sum_.data();
    v.damping_sum = damping_sum_.data();
    v.partial = partial_.data();
    v.stop = stop_.data();
    v.events = events_.data();
    v.event_count = event_count_.data();
    v.event_capacity = static_cast<unsigned>(events_.size());
    check(cudaMemset(stop_.data(), 0, sizeof(int)), "cudaMemset of the stop flag");
    check(cudaMemset(event_count_.data(), 0, sizeof(unsigned)), "cudaMemset of the event counter");
    const long grid_blocks = (static_cast<long>(v.padded) + kThreads - 1) / kThreads;
    require(grid_blocks <= 2147483647L, "CUDA backend: too many particles for one grid");
    const int grid = static_cast<int>(grid_blocks);
    // Launches are queued; the stop flag makes the cycles after a damage step return at once. A
    // batch is cut into pieces so that a break found early does not leave many empty launches.
    constexpr long kPiece = 1024;
    DeviceBatch batch;
    long launched = 0;
    int stop = 0;
    while (launched < cycles && stop == 0) {
      const long piece = std::min(kPiece, cycles - launched);
      for (long s = launched; s < launched + piece; ++s) {
        const int in = static_cast<int>((parity + s) & 1), out = 1 - in;
        for (int c = 0; c < 3; ++c) {
          v.displacement_in[c] = displacement_[in][c].data();
          v.rotation_in[c] = rotation_[in][c].data();
          v.displacement_out[c] = displacement_[out][c].data();
          v.rotation_out[c] = rotation_[out][c].data();
        }
        v.cycle = first_cycle + s;
        v.batch_cycle = static_cast<int>(s);
        if (report_last && s + 1 == cycles) {
          launch_step<true>(arrays_.mode, v, grid);
        } else {
          launch_step<false>(arrays_.mode, v, grid);
        }
        check(cudaGetLastError(), "the step kernel's launch");
      }
      launched += piece;
      if (is_breaking(arrays_.mode)) {
        check(cudaMemcpy(&stop, stop_.data(), sizeof(int), cudaMemcpyDeviceToHost),
              "reading the stop flag");
      }
    }
    check(cudaDeviceSynchronize(), "the step kernels");
    batch.cycles = stop != 0 ? stop : cycles;
    batch.reported = report_last && batch.cycles == cycles;
    if (is_breaking(arrays_.mode)) {
      unsigned count = 0;
      check(cudaMemcpy(&count, event_count_.data(), sizeof(unsigned), cudaMemcpyDeviceToHost),
            "reading the event counter");
      require(count <= events_.size(), text("CUDA backend: ", count,
                                            " bonds took a damage step in one cycle, more than the "
                                            "event log's ",
                                            events_.size()));
      std::unique_ptr<SlotEvent[]> events(new SlotEvent[count + 1]);
      events_.download(events.get(), count, "reading the event log");
      assign_events(batch.events, events.get(), count);
    }
    if (batch.reported) {
      const int blocks = v.padded / 8;
      block_partials_kernel<<<(blocks + kThreads - 1) / kThreads, kThreads>>>(
          partial_.data(), v.padded, block_sums_.data());
      check(cudaGetLastError(), "the block partials' launch");
      reduce_kernel<<<kParticlePartials, kReduceThreads>>>(block_sums_.data(), blocks,
                                                           sums_.data());
      check(cudaGetLastError(), "the reduction's launch");
      sums_.download(batch.sums, kParticlePartials, "reading the report sums");
    }
    return batch;
  }

  void download_state(const DeviceArrays& a) override {
    const std::size_t p = static_cast<std::size_t>(a.padded);
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 3; ++c) {
        displacement_[b][c].download(a.displacement[b][c], p, "reading displacements");
        rotation_[b][c].download(a.rotation[b][c], p, "reading rotations");
      }
    for (int c = 0; c < 3; ++c) {
      velocity_[c].download(a.velocity[c], p, "reading velocities");
      angular_velocity_[c].download(a.angular_velocity[c], p, "reading angular velocities");
      force_[c].download(a.force[c], p, "reading forces");
      torque_[c].download(a.torque[c], p, "reading torques");
    }
    if (is_breaking(a.mode)) {
      work_sum_.download(a.work_sum, p, "reading the boundary work sums");
      damping_sum_.download(a.damping_sum, p, "reading the damping sums");
    }
  }

  void download_table(const DeviceArrays& a, std::vector<std::int32_t>& type) override {
    type.resize(type_.size());
    type_.download(type.data(), type.size(), "reading the bond table");
    if (is_softening(a.mode)) {
      slot_damage_.download(a.slot_damage, slot_damage_.size(), "reading the slots' damage");
      slot_kappa_.download(a.slot_kappa, slot_kappa_.size(), "reading the slots' kappa");
    }
  }

 private:
  static std::size_t event_capacity(const DeviceArrays& a) {
    const std::size_t bonds = static_cast<std::size_t>(a.padded) * a.width / 2 + 1;
    return std::min(bonds, kMaxEvents);
  }

  std::string name_;
  DeviceArrays arrays_;
  DeviceArray<double> displacement_[2][3], rotation_[2][3], velocity_[3], angular_velocity_[3];
  DeviceArray<double> force_[3], torque_[3], inverse_mass_, inverse_inertia_, partial_, block_sums_,
      sums_;
  DeviceArray<std::uint8_t> motion_;
  DeviceArray<MotionClass> classes_;
  DeviceArray<std::int32_t> neighbour_, type_, slot_bond_;
  DeviceArray<HalfBondType> types_;
  DeviceArray<HalfBondFailure> failure_;
  DeviceArray<double> slot_alpha_, slot_beta_, slot_tensile_, slot_cohesion_, slot_damage_,
      slot_kappa_, work_sum_, damping_sum_;
  DeviceArray<SlotEvent> events_;
  DeviceArray<int> stop_;
  DeviceArray<unsigned> event_count_;
};

}  // namespace

bool cuda_available(std::string* why) {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess || count == 0) {
    if (why) {
      // Without an NVIDIA driver the runtime says "driver version is insufficient".
      const bool none =
          count == 0 || status == cudaErrorNoDevice || status == cudaErrorInsufficientDriver;
      *why = none ? text("no CUDA device is present (", cudaGetErrorString(status), ")")
                  : text("no CUDA device can be used: ", cudaGetErrorString(status));
    }
    cudaGetLastError();  // clear the error the query left
    return false;
  }
  return true;
}

double cuda_copy_bandwidth(std::size_t bytes) {
  make_cuda_backend();  // throws where no device can be used
  DeviceArray<unsigned char> from, to;
  from.zero(bytes, "the copy test's source");
  to.zero(bytes, "the copy test's destination");
  cudaEvent_t start{}, stop{};
  check(cudaEventCreate(&start), "cudaEventCreate");
  check(cudaEventCreate(&stop), "cudaEventCreate");
  float best = 0;
  for (int k = 0; k < 11; ++k) {  // the first copy warms up
    check(cudaEventRecord(start), "cudaEventRecord");
    check(cudaMemcpy(to.data(), from.data(), bytes, cudaMemcpyDeviceToDevice), "the copy test");
    check(cudaEventRecord(stop), "cudaEventRecord");
    check(cudaEventSynchronize(stop), "cudaEventSynchronize");
    float ms = 0;
    check(cudaEventElapsedTime(&ms, start, stop), "cudaEventElapsedTime");
    if (k > 0 && (best == 0 || ms < best)) best = ms;
  }
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  return 2.0 * static_cast<double>(bytes) / (1e-3 * best);
}

std::unique_ptr<DeviceBackend> make_cuda_backend() {
  std::string why;
  if (!cuda_available(&why)) throw Error("--backend cuda: " + why);
  return std::make_unique<CudaBackend>();
}

}  // namespace plydem
