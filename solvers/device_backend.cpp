#include "solvers/device_backend.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstring>

#include "core/error.hpp"

namespace plydem {

const char* to_string(ExplicitBackend backend) {
  switch (backend) {
    case ExplicitBackend::kCuda:
      return "cuda";
    case ExplicitBackend::kDeviceEmulation:
      return "emulation";
    case ExplicitBackend::kCpu:
      break;
  }
  return "cpu";
}

ExplicitBackend parse_backend(const std::string& name) {
  if (name == "cpu") return ExplicitBackend::kCpu;
  if (name == "cuda") return ExplicitBackend::kCuda;
  if (name == "emulation") return ExplicitBackend::kDeviceEmulation;
  throw Error(fmt::format("unknown backend '{}': cpu, cuda or emulation", name));
}

const std::vector<std::string>& backend_choices() {
  static const std::vector<std::string> choices{to_string(ExplicitBackend::kCpu),
                                                to_string(ExplicitBackend::kCuda)};
  return choices;
}

ExplicitBackend parse_backend_choice(const std::string& name) {
  const std::vector<std::string>& choices = backend_choices();
  if (std::find(choices.begin(), choices.end(), name) == choices.end()) {
    throw Error(fmt::format("unknown backend '{}': {}", name, fmt::join(choices, " or ")));
  }
  return parse_backend(name);
}

void assign_events(std::vector<SlotEvent>& to, const SlotEvent* from, std::size_t count) {
  to.assign(from, from + count);
}

namespace {

// The device's code path on the host: the arrays copied into vectors of its own, each cycle a loop
// of particle_step over the particles, the report sums reduced as the host kernel does (block
// partials in lane order, then in block order).
class EmulationBackend final : public DeviceBackend {
 public:
  std::string describe() const override { return "host emulation of the device kernel"; }

  std::size_t bytes_needed(const DeviceArrays& a) const override {
    const std::size_t p = static_cast<std::size_t>(a.padded);
    return p * sizeof(double) * (12 + 6 + 2 + 2 + 6 + kParticlePartials) +
           p * a.width * 2 * sizeof(std::int32_t);
  }

  void upload(const DeviceArrays& a) override {
    arrays_ = a;
    const std::size_t p = static_cast<std::size_t>(a.padded);
    const std::size_t cells = p * static_cast<std::size_t>(a.width);
    auto copy = [](std::vector<double>& to, const double* from, std::size_t n) {
      to.assign(from, from + n);
    };
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 3; ++c) {
        copy(displacement_[b][c], a.displacement[b][c], p);
        copy(rotation_[b][c], a.rotation[b][c], p);
      }
    for (int c = 0; c < 3; ++c) {
      copy(velocity_[c], a.velocity[c], p);
      copy(angular_velocity_[c], a.angular_velocity[c], p);
      force_[c].assign(p, 0.0);
      torque_[c].assign(p, 0.0);
    }
    copy(inverse_mass_, a.inverse_mass, p);
    copy(inverse_inertia_, a.inverse_inertia, p);
    neighbour_.assign(a.neighbour, a.neighbour + cells);
    type_.assign(a.type, a.type + cells);
    types_.assign(a.types, a.types + a.type_count);
    partial_.assign(p * kParticlePartials, 0.0);
    const bool breaking = a.mode != kElasticMode;
    const bool slots = a.mode == kBrittleSlots || a.mode == kSofteningSlots;
    const bool soften = a.mode == kSofteningTypes || a.mode == kSofteningSlots;
    if (breaking) {
      failure_.assign(a.failure, a.failure + a.type_count);
      slot_bond_.assign(a.slot_bond, a.slot_bond + cells);
      copy(work_sum_, a.work_sum, p);
      copy(damping_sum_, a.damping_sum, p);
    }
    if (slots) {
      copy(slot_alpha_, a.slot_alpha, cells);
      copy(slot_beta_, a.slot_beta, cells);
      copy(slot_tensile_, a.slot_tensile, cells);
      copy(slot_cohesion_, a.slot_cohesion, cells);
    }
    if (soften) {
      copy(slot_damage_, a.slot_damage, cells);
      copy(slot_kappa_, a.slot_kappa, cells);
    }
    upload_motions(a);
  }

  void upload_motions(const DeviceArrays& a) override {
    motion_.assign(a.motion, a.motion + a.padded);
    classes_.assign(a.classes, a.classes + a.class_count);
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
    int stop = 0;
    unsigned count = 0;
    std::vector<SlotEvent> events(static_cast<std::size_t>(slot_bond_.size() / 2 + 1));
    v.stop = &stop;
    v.events = events.data();
    v.event_count = &count;
    v.event_capacity = static_cast<unsigned>(events.size());
    DeviceBatch batch;
    long s = 0;
    for (; s < cycles && stop == 0; ++s) {
      const int in = static_cast<int>((parity + s) & 1), out = 1 - in;
      for (int c = 0; c < 3; ++c) {
        v.displacement_in[c] = displacement_[in][c].data();
        v.rotation_in[c] = rotation_[in][c].data();
        v.displacement_out[c] = displacement_[out][c].data();
        v.rotation_out[c] = rotation_[out][c].data();
      }
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
        for (int b = 0; b < blocks; ++b) sum += block_partial(partial_.data(), v.padded, q, b);
        batch.sums[q] = sum;
      }
    }
    return batch;
  }

  void download_state(const DeviceArrays& a) override {
    const std::size_t bytes = static_cast<std::size_t>(a.padded) * sizeof(double);
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 3; ++c) {
        std::memcpy(a.displacement[b][c], displacement_[b][c].data(), bytes);
        std::memcpy(a.rotation[b][c], rotation_[b][c].data(), bytes);
      }
    for (int c = 0; c < 3; ++c) {
      std::memcpy(a.velocity[c], velocity_[c].data(), bytes);
      std::memcpy(a.angular_velocity[c], angular_velocity_[c].data(), bytes);
      std::memcpy(a.force[c], force_[c].data(), bytes);
      std::memcpy(a.torque[c], torque_[c].data(), bytes);
    }
    if (a.mode != kElasticMode) {
      std::memcpy(a.work_sum, work_sum_.data(), bytes);
      std::memcpy(a.damping_sum, damping_sum_.data(), bytes);
    }
  }

  void download_table(const DeviceArrays& a, std::vector<std::int32_t>& type) override {
    type = type_;
    if (a.mode == kSofteningTypes || a.mode == kSofteningSlots) {
      std::copy(slot_damage_.begin(), slot_damage_.end(), a.slot_damage);
      std::copy(slot_kappa_.begin(), slot_kappa_.end(), a.slot_kappa);
    }
  }

 private:
  void step(const ParticleStepView& v, int k, bool report) const {
    switch (arrays_.mode) {
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

  DeviceArrays arrays_;
  std::vector<double> displacement_[2][3], rotation_[2][3], velocity_[3], angular_velocity_[3];
  std::vector<double> force_[3], torque_[3], inverse_mass_, inverse_inertia_, partial_;
  std::vector<std::uint8_t> motion_;
  std::vector<MotionClass> classes_;
  std::vector<std::int32_t> neighbour_, type_, slot_bond_;
  std::vector<HalfBondType> types_;
  std::vector<HalfBondFailure> failure_;
  std::vector<double> slot_alpha_, slot_beta_, slot_tensile_, slot_cohesion_, slot_damage_,
      slot_kappa_, work_sum_, damping_sum_;
};

}  // namespace

std::unique_ptr<DeviceBackend> make_emulation_backend() {
  return std::make_unique<EmulationBackend>();
}

}  // namespace plydem
