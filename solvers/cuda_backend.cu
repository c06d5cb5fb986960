// The CUDA backend of the explicit integrator (solvers/device_backend.hpp): one thread per
// particle runs solvers/particle_step.hpp, the same code the host emulation runs and the same
// half-bond and failure-law templates the host's SIMD kernel runs (contacts/half_bond.hpp), in
// fp64. The kernel's multiply-adds are explicit fused ones (core/lane_ops.hpp); -fmad=false keeps
// nvcc from fusing the others (the exact failure law of core/bond_failure_law.hpp, which the host
// evaluates in baseline x86-64 code, where no multiply-add is fused either).
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
    // The kernel's arrays, the block partials (6 / 8 per particle) and the event log.
    std::size_t bytes =
        kernel_array_bytes(a.sizes) + a.sizes.count(ArrayExtent::kPartials) / 8 * sizeof(double);
    if (breaks_bonds(a.sizes.mode)) bytes += event_capacity(a.sizes) * sizeof(SlotEvent);
    return bytes;
  }

  void upload(const DeviceArrays& a) override {
    require(a.sizes.padded % 8 == 0,
            "CUDA backend: the kernel's particles come in blocks of eight");
    const std::size_t needed = bytes_needed(a);
    std::size_t free = 0, total = 0;
    check(cudaMemGetInfo(&free, &total), "cudaMemGetInfo");
    const std::size_t held = allocated_bytes;  // what re-uploading into them frees
    require(needed <= free + held,
            text("CUDA backend: the model needs ", needed * 1e-9, " GB of device memory, ",
                 (free + held) * 1e-9, " GB of the device's ", total * 1e-9, " GB are free"));
    sizes_ = a.sizes;
    upload_kernel_arrays(own_, a);
    block_sums_.zero(a.sizes.count(ArrayExtent::kPartials) / 8, "report block sums");
    sums_.zero(kParticlePartials, "report sums");
    stop_.zero(1, "the stop flag");
    event_count_.zero(1, "the event counter");
    if (breaks_bonds(a.sizes.mode)) events_.resize(event_capacity(a.sizes), "the event log");
  }

  void upload_motions(const DeviceArrays& a) override {
    sizes_.class_count = a.sizes.class_count;
    upload_motion_arrays(own_, a);
  }

  DeviceBatch run_cycles(long cycles, int parity, bool report_last, long first_cycle, double dt,
                         double alpha) override {
    ParticleStepView v;
    v.a = kernel_view(own_);
    v.padded = sizes_.padded;
    v.width = sizes_.width;
    v.dt = dt;
    v.alpha = alpha;
    v.stop = stop_.data();
    v.events = events_.data();
    v.event_count = event_count_.data();
    v.event_capacity = static_cast<unsigned>(events_.size());
    check(cudaMemset(stop_.data(), 0, sizeof(int)), "cudaMemset of the stop flag");
    check(cudaMemset(event_count_.data(), 0, sizeof(unsigned)), "cudaMemset of the event counter");
    const long grid_blocks = (static_cast<long>(v.padded) + kThreads - 1) / kThreads;
    require(grid_blocks <= 2147483647L, "CUDA backend: too many particles for one grid");
    const int grid = static_cast<int>(grid_blocks);
    const bool breaking = breaks_bonds(sizes_.mode);
    // Launches are queued; the stop flag makes the cycles after a damage step return at once. A
    // batch is cut into pieces so that a break found early does not leave many empty launches.
    constexpr long kPiece = 1024;
    DeviceBatch batch;
    long launched = 0;
    int stop = 0;
    while (launched < cycles && stop == 0) {
      const long piece = std::min(kPiece, cycles - launched);
      for (long s = launched; s < launched + piece; ++s) {
        v.parity = static_cast<int>((parity + s) & 1);
        v.cycle = first_cycle + s;
        v.batch_cycle = static_cast<int>(s);
        if (report_last && s + 1 == cycles) {
          launch_step<true>(sizes_.mode, v, grid);
        } else {
          launch_step<false>(sizes_.mode, v, grid);
        }
        check(cudaGetLastError(), "the step kernel's launch");
      }
      launched += piece;
      if (breaking) {
        check(cudaMemcpy(&stop, stop_.data(), sizeof(int), cudaMemcpyDeviceToHost),
              "reading the stop flag");
      }
    }
    check(cudaDeviceSynchronize(), "the step kernels");
    batch.cycles = stop != 0 ? stop : cycles;
    batch.reported = report_last && batch.cycles == cycles;
    if (breaking) read_events(batch);
    if (batch.reported) reduce_report(v, batch);
    return batch;
  }

  void download_state(const DeviceArrays& a) override { download_kernel_state(own_, a); }

  void download_table(const DeviceArrays& a, std::vector<std::int32_t>& type) override {
    download_kernel_table(own_, a, type);
  }

 private:
  static std::size_t event_capacity(const KernelSizes& sizes) {
    return std::min(sizes.count(ArrayExtent::kCells) / 2 + 1, kMaxEvents);
  }

  void read_events(DeviceBatch& batch) const {
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

  // The report sums in the host kernel's order: block partials in lane order, then a fixed tree.
  void reduce_report(const ParticleStepView& v, DeviceBatch& batch) {
    const int blocks = v.padded / 8;
    block_partials_kernel<<<(blocks + kThreads - 1) / kThreads, kThreads>>>(v.a.partial, v.padded,
                                                                            block_sums_.data());
    check(cudaGetLastError(), "the block partials' launch");
    reduce_kernel<<<kParticlePartials, kReduceThreads>>>(block_sums_.data(), blocks, sums_.data());
    check(cudaGetLastError(), "the reduction's launch");
    sums_.download(batch.sums, kParticlePartials, "reading the report sums");
  }

  std::string name_;
  KernelSizes sizes_;
  KernelArrays<DeviceArray> own_;
  DeviceArray<double> block_sums_, sums_;
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
