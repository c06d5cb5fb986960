#include "solvers/device_backend.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstring>

#include "core/error.hpp"

namespace plydem {

namespace {

constexpr ExplicitBackend kBackends[] = {ExplicitBackend::kCpu, ExplicitBackend::kCuda,
                                         ExplicitBackend::kDeviceEmulation,
                                         ExplicitBackend::kReference};

}  // namespace

const char* to_string(ExplicitBackend backend) {
  switch (backend) {
    case ExplicitBackend::kCuda:
      return "cuda";
    case ExplicitBackend::kDeviceEmulation:
      return "emulation";
    case ExplicitBackend::kReference:
      return "reference";
    case ExplicitBackend::kCpu:
      break;
  }
  return "cpu";
}

const char* describe(ExplicitBackend backend) {
  switch (backend) {
    case ExplicitBackend::kCuda:
      return "one CUDA device (a build with -DPLYDEM_CUDA=ON)";
    case ExplicitBackend::kDeviceEmulation:
      return "the CUDA kernel's code run on the host, one particle at a time (for checks; slow)";
    case ExplicitBackend::kReference:
      return "plain loops over the model's arrays, one thread (for checks; slow)";
    case ExplicitBackend::kCpu:
      break;
  }
  return "SIMD kernel, OpenMP threads";
}

const std::vector<std::string>& backend_choices() {
  static const std::vector<std::string> choices = [] {
    std::vector<std::string> names;
    for (ExplicitBackend b : kBackends) names.emplace_back(to_string(b));
    return names;
  }();
  return choices;
}

ExplicitBackend parse_backend(const std::string& name) {
  for (ExplicitBackend b : kBackends)
    if (name == to_string(b)) return b;
  throw Error(fmt::format("unknown backend '{}': {}", name, fmt::join(backend_choices(), ", ")));
}

std::string backend_help(const std::string& quote) {
  std::string help;
  for (std::size_t k = 0; k < std::size(kBackends); ++k) {
    if (k > 0) help += k + 1 == std::size(kBackends) ? " or " : ", ";
    help += fmt::format("{0}{1}{0} ({2})", quote, to_string(kBackends[k]), describe(kBackends[k]));
  }
  return help;
}

ExplicitBackend parse_backend_choice(const std::string& name) {
  return parse_backend(name);
}

bool backend_available(ExplicitBackend backend, std::string* why) {
  if (backend == ExplicitBackend::kCuda) return cuda_available(why);
  return true;
}

void assign_events(std::vector<SlotEvent>& to, const SlotEvent* from, std::size_t count) {
  to.assign(from, from + count);
}

namespace {

// An array of the emulation's own: the store of upload_kernel_arrays and the others.
template <class T>
class HostArray {
 public:
  void upload(const T* from, std::size_t n, const char*) { data_.assign(from, from + n); }
  void download(T* to, std::size_t n, const char*) const {
    std::copy(data_.begin(), data_.begin() + static_cast<std::ptrdiff_t>(n), to);
  }
  void zero(std::size_t n, const char*) { data_.assign(n, T{}); }
  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  std::size_t size() const { return data_.size(); }

 private:
  std::vector<T> data_;
};

// The device's code path on the host: the arrays copied into arrays of its own, each cycle a loop
// of particle_step over the particles, the report sums reduced as the host kernel does (block
// partials in lane order, then in block order).
class EmulationBackend final : public DeviceBackend {
 public:
  std::string describe() const override { return "host emulation of the device kernel"; }

  std::size_t bytes_needed(const DeviceArrays& a) const override {
    return kernel_array_bytes(a.sizes);
  }

  void upload(const DeviceArrays& a) override {
    sizes_ = a.sizes;
    upload_kernel_arrays(own_, a);
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
    int stop = 0;
    unsigned count = 0;
    std::vector<SlotEvent> events(
        static_cast<std::size_t>(sizes_.count(ArrayExtent::kCells) / 2 + 1));
    v.stop = &stop;
    v.events = events.data();
    v.event_count = &count;
    v.event_capacity = static_cast<unsigned>(events.size());
    DeviceBatch batch;
    long s = 0;
    for (; s < cycles && stop == 0; ++s) {
      v.parity = static_cast<int>((parity + s) & 1);
      v.cycle = first_cycle + s;
      v.batch_cycle = static_cast<int>(s);
      const bool report = report_last && s + 1 == cycles;
      for (int k = 0; k < v.padded; ++k) step(v, k, report);
      batch.reported = report;
    }
    batch.cycles = s;
    require(count <= v.event_capacity, "internal error: the emulated event log overflowed");
    batch.events.assign(events.begin(), events.begin() + count);
    if (batch.reported) {
      const int blocks = v.padded / 8;
      for (int q = 0; q < kParticlePartials; ++q) {
        double sum = 0;
        for (int b = 0; b < blocks; ++b) sum += block_partial(v.a.partial, v.padded, q, b);
        batch.sums[q] = sum;
      }
    }
    return batch;
  }

  void download_state(const DeviceArrays& a) override { download_kernel_state(own_, a); }

  void download_table(const DeviceArrays& a, std::vector<std::int32_t>& type) override {
    download_kernel_table(own_, a, type);
  }

 private:
  void step(const ParticleStepView& v, int k, bool report) const {
    switch (sizes_.mode) {
      case kBrittleTypes:
        report ? particle_step<true, kBrittleTypes>(v, k)
               : particle_step<false, kBrittleTypes>(v, k);
        break;
      case kBrittleSlots:
        report ? particle_step<true, kBrittleSlots>(v, k)
               : particle_step<false, kBrittleSlots>(v, k);
        break;
      case kSofteningTypes:
        report ? particle_step<true, kSofteningTypes>(v, k)
               : particle_step<false, kSofteningTypes>(v, k);
        break;
      case kSofteningSlots:
        report ? particle_step<true, kSofteningSlots>(v, k)
               : particle_step<false, kSofteningSlots>(v, k);
        break;
      default:
        report ? particle_step<true, kElasticMode>(v, k) : particle_step<false, kElasticMode>(v, k);
    }
  }

  KernelSizes sizes_;
  KernelArrays<HostArray> own_;
};

}  // namespace

std::unique_ptr<DeviceBackend> make_emulation_backend() {
  return std::make_unique<EmulationBackend>();
}

}  // namespace plydem
