#include "solvers/explicit_integrator.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>

#include "contacts/bond_kernel.hpp"
#include "contacts/particle_ordering.hpp"
#include "core/error.hpp"

// The fused step is compiled for three instruction sets and the best one the processor has is
// picked when the program starts (GCC function multi-versioning): one binary runs everywhere and
// uses AVX-512 where it exists. Everything the step calls is inlined into it.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(PLYDEM_NO_TARGET_CLONES)
#define PLYDEM_TARGET_CLONES [[gnu::target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")]]
#else
#define PLYDEM_TARGET_CLONES
#endif

namespace plydem {

double critical_time_step(const Model& model) {
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  // Row sums of |M^-1/2 K M^-1/2| per degree of freedom (6 per particle).
  Eigen::ArrayXd row_sum = Eigen::ArrayXd::Zero(6 * p.size());
  for (int b = 0; b < bonds.size(); ++b) {
    const Matrix12d k = parallel_bond_stiffness(bond_parameters(bonds, b));
    const int particle[2] = {bonds.first(b), bonds.second(b)};
    double sqrt_mass[12];
    for (int d = 0; d < 12; ++d) {
      const int i = particle[d / 6];
      sqrt_mass[d] = std::sqrt(d % 6 < 3 ? p.mass(i) : p.moment_of_inertia(i));
    }
    for (int r = 0; r < 12; ++r) {
      double sum = 0;
      for (int c = 0; c < 12; ++c) sum += std::abs(k(r, c)) / sqrt_mass[c];
      row_sum(6 * particle[r / 6] + r % 6) += sum / sqrt_mass[r];
    }
  }
  const double lambda_max = row_sum.size() > 0 ? row_sum.maxCoeff() : 0.0;
  require(std::isfinite(lambda_max) && lambda_max > 0,
          "the model has no bond stiffness: no critical time step exists");
  return 2.0 / std::sqrt(lambda_max);
}

void validate(const ExplicitSettings& settings) {
  require(std::isfinite(settings.local_damping) && settings.local_damping >= 0 &&
              settings.local_damping < 1,
          fmt::format("local damping must lie in [0, 1), got {}", settings.local_damping));
  require(
      std::isfinite(settings.safety_factor) && settings.safety_factor > 0 &&
          settings.safety_factor <= 1,
      fmt::format("time-step safety factor must lie in (0, 1], got {}", settings.safety_factor));
  require(std::isfinite(settings.time_step) && settings.time_step >= 0,
          fmt::format("time step must be >= 0 (0 = automatic), got {}", settings.time_step));
}

namespace {

// Central-difference update of one degree of freedom with PFC local damping; returns the
// leapfrog kinetic-energy product m v_old v_new.
inline double advance_dof(double& u, double& v, double force, double inertia, double dt,
                          double alpha) {
  const double damped = force - alpha * std::abs(force) * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0));
  const double v_old = v;
  v += dt * damped / inertia;
  u += dt * v;
  return inertia * v_old * v;
}

// What a prescribed motion does to a particle of its group: per component, a mask (-1 fixed,
// 0 free) and the imposed value.
struct MotionClass {
  std::int64_t fix_velocity[3] = {0, 0, 0};
  std::int64_t fix_angular_velocity[3] = {0, 0, 0};
  double velocity[3] = {0, 0, 0};
  double angular_velocity[3] = {0, 0, 0};
  std::int64_t free = -1;  // no translation fixed: counts in the unbalanced force
};

// The fused kernel's data, in kernel order (particle k is model particle order[k]), padded to
// whole lane blocks. Displacements and rotations are double-buffered: a cycle reads buffer
// `parity` (every particle needs its neighbours' state before the update) and writes the other.
struct FusedState {
  std::vector<int> order;
  std::vector<int> position;  // inverse of order: kernel index of model particle i
  GatherBonds bonds;
  int particles = 0;
  int blocks = 0;
  lanes::Array displacement[2][3], rotation[2][3], velocity[3], angular_velocity[3];
  lanes::Array inverse_mass, inverse_inertia;  // padding particles: 1, and they never move
  std::vector<std::uint8_t> motion;            // class per particle; 0 = free
  std::vector<MotionClass> classes;
  std::vector<double> partial;  // per block: energy, bond force norm, 2 x kinetic, unbalanced
  int parity = 0;               // the buffer holding the current displacements and rotations

  std::size_t bytes() const {
    std::size_t arrays = 0;
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 3; ++c) arrays += displacement[b][c].bytes() + rotation[b][c].bytes();
    for (int c = 0; c < 3; ++c) arrays += velocity[c].bytes() + angular_velocity[c].bytes();
    arrays += inverse_mass.bytes() + inverse_inertia.bytes();
    return arrays + bonds.bytes() + (order.size() + position.size()) * sizeof(int) + motion.size() +
           classes.size() * sizeof(MotionClass) + partial.size() * sizeof(double);
  }
};

constexpr int kPartials = 4;

struct StepArgs {
  FusedState* state = nullptr;
  int parity = 0;
  double dt = 0;
  double alpha = 0;
  // Report cycle only: the model's force and torque columns (model order) and the block sums.
  double* force_out[3] = {nullptr, nullptr, nullptr};
  double* torque_out[3] = {nullptr, nullptr, nullptr};
  double* partial = nullptr;
};

// One degree of freedom of a block: the damped central difference, or the imposed velocity.
// The local damping force alpha |F| sign(v) is built from bits (|F| with the sign of v, zero where
// v is zero), which is exact and avoids per-lane branches.
[[gnu::always_inline]] inline void advance_lanes(const lanes::Doubles& force,
                                                 const lanes::Doubles& dt_over_inertia,
                                                 const lanes::Mask& fixed,
                                                 const lanes::Doubles& imposed, double dt,
                                                 double alpha, lanes::Doubles& u, lanes::Doubles& v,
                                                 lanes::Doubles& v_old) {
  using lanes::Doubles;
  using lanes::Mask;
  const Mask sign_bit = Mask{} + std::numeric_limits<std::int64_t>::min();
  const Doubles magnitude = (Doubles)((Mask)force & ~sign_bit);
  const Doubles push = alpha * magnitude;
  const Doubles signed_push = (Doubles)((Mask)push | ((Mask)v & sign_bit));
  const Doubles damping = v == Doubles{} ? Doubles{} : signed_push;
  v_old = v;
  const Doubles free = v + dt_over_inertia * (force - damping);
  v = (Doubles)(((Mask)imposed & fixed) | ((Mask)free & ~fixed));  // bitwise select: no branches
  u += dt * v;
}

template <bool kReport>
[[gnu::always_inline]] inline void step_range(const StepArgs& a, int begin_block, int end_block) {
  using lanes::Doubles;
  using lanes::Mask;
  constexpr int kLanes = lanes::kCount;
  FusedState& k = *a.state;
  const int in = a.parity, out = 1 - a.parity;
  const GatherState state{
      {k.displacement[in][0].data(), k.displacement[in][1].data(), k.displacement[in][2].data()},
      {k.rotation[in][0].data(), k.rotation[in][1].data(), k.rotation[in][2].data()}};
  // The step writes the other buffer and the velocities, which `state` does not alias.
  double* const next_u[3] = {k.displacement[out][0].data(), k.displacement[out][1].data(),
                             k.displacement[out][2].data()};
  double* const next_t[3] = {k.rotation[out][0].data(), k.rotation[out][1].data(),
                             k.rotation[out][2].data()};
  double* const vel[3] = {k.velocity[0].data(), k.velocity[1].data(), k.velocity[2].data()};
  double* const ang[3] = {k.angular_velocity[0].data(), k.angular_velocity[1].data(),
                          k.angular_velocity[2].data()};
  for (int block = begin_block; block < end_block; ++block) {
    const int first = block * kLanes;
    Doubles force[3] = {}, torque[3] = {};
    Doubles energy{}, bond_force{};
    gather_bond_block<kReport>(k.bonds, first, state, force, torque, energy, bond_force);

    // Prescribed motions of the block's particles (most blocks hold free particles only).
    Mask fix_v[3] = {}, fix_w[3] = {};
    Doubles imposed_v[3] = {}, imposed_w[3] = {};
    Mask counts_free = Mask{} - 1;
    std::uint64_t classes;
    std::memcpy(&classes, k.motion.data() + first, sizeof classes);
    if (classes != 0) {
      for (int l = 0; l < kLanes; ++l) {
        const MotionClass& m = k.classes[k.motion[first + l]];
        for (int c = 0; c < 3; ++c) {
          fix_v[c][l] = m.fix_velocity[c];
          fix_w[c][l] = m.fix_angular_velocity[c];
          imposed_v[c][l] = m.velocity[c];
          imposed_w[c][l] = m.angular_velocity[c];
        }
        counts_free[l] = m.free;
      }
    }
    Doubles inverse_mass, inverse_inertia;
    lanes::load(k.inverse_mass.data() + first, inverse_mass);
    lanes::load(k.inverse_inertia.data() + first, inverse_inertia);
    const Doubles dt_over_mass = a.dt * inverse_mass;
    const Doubles dt_over_inertia = a.dt * inverse_inertia;
    Doubles kinetic{};
    for (int c = 0; c < 3; ++c) {
      Doubles u, v, v_old;
      lanes::load(state.displacement[c] + first, u);
      lanes::load(vel[c] + first, v);
      advance_lanes(force[c], dt_over_mass, fix_v[c], imposed_v[c], a.dt, a.alpha, u, v, v_old);
      lanes::store(next_u[c] + first, u);
      lanes::store(vel[c] + first, v);
      if constexpr (kReport) kinetic += (Doubles)((Mask)(v_old / inverse_mass * v) & ~fix_v[c]);

      lanes::load(state.rotation[c] + first, u);
      lanes::load(ang[c] + first, v);
      advance_lanes(torque[c], dt_over_inertia, fix_w[c], imposed_w[c], a.dt, a.alpha, u, v, v_old);
      lanes::store(next_t[c] + first, u);
      lanes::store(ang[c] + first, v);
      if constexpr (kReport) kinetic += (Doubles)((Mask)(v_old / inverse_inertia * v) & ~fix_w[c]);
    }
    if constexpr (kReport) {
      const Doubles f2 = force[0] * force[0] + force[1] * force[1] + force[2] * force[2];
      double unbalanced = 0;
      for (int l = 0; l < kLanes; ++l) {
        if (counts_free[l]) unbalanced += __builtin_sqrt(f2[l]);
        if (first + l < k.particles) {
          const int i = k.order[first + l];
          for (int c = 0; c < 3; ++c) {
            a.force_out[c][i] = force[c][l];
            a.torque_out[c][i] = torque[c][l];
          }
        }
      }
      double* partial = a.partial + static_cast<std::size_t>(block) * kPartials;
      partial[0] = lanes::sum(energy);
      partial[1] = lanes::sum(bond_force);
      partial[2] = lanes::sum(kinetic);
      partial[3] = unbalanced;
    }
  }
}

PLYDEM_TARGET_CLONES void step_blocks(const StepArgs& a, bool report, int begin_block,
                                      int end_block) {
  if (report) {
    step_range<true>(a, begin_block, end_block);
  } else {
    step_range<false>(a, begin_block, end_block);
  }
}

// Below this many blocks per thread a cycle is too short to share.
constexpr int kMinBlocksPerThread = 32;

}  // namespace

struct ExplicitIntegrator::Fused {
  FusedState state;
};

ExplicitIntegrator::ExplicitIntegrator(Model& model, const ExplicitSettings& settings)
    : model_(model), settings_(settings) {
  validate(settings);
  model.check_consistency();
  const double critical = critical_time_step(model);
  if (settings.time_step > 0) {
    require(settings.time_step <= critical,
            fmt::format("time step {:.3e} s exceeds the critical time step {:.3e} s: the explicit "
                        "scheme would be unstable",
                        settings.time_step, critical));
    time_step_ = settings.time_step;
  } else {
    time_step_ = settings.safety_factor * critical;
  }
  if (settings.kernel == ExplicitKernel::kFused) {
    fused_ = std::make_unique<Fused>();
    FusedState& k = fused_->state;
    const Particles& p = model.particles;
    k.order = kernel_order(model, settings.particle_order);
    k.position.assign(k.order.size(), 0);
    for (std::size_t i = 0; i < k.order.size(); ++i) k.position[k.order[i]] = static_cast<int>(i);
    k.bonds = GatherBonds(model.bonds, k.order);
    k.particles = p.size();
    const int padded = k.bonds.padded_count();
    k.blocks = padded / lanes::kCount;
    for (int b = 0; b < 2; ++b) {
      for (int c = 0; c < 3; ++c) {
        k.displacement[b][c] = lanes::Array(padded);
        k.rotation[b][c] = lanes::Array(padded);
      }
    }
    for (int c = 0; c < 3; ++c) {
      k.velocity[c] = lanes::Array(padded);
      k.angular_velocity[c] = lanes::Array(padded);
    }
    k.inverse_mass = lanes::Array(padded);
    k.inverse_inertia = lanes::Array(padded);
    for (int i = 0; i < padded; ++i) {
      const bool real = i < k.particles;
      k.inverse_mass[i] = real ? 1.0 / p.mass(k.order[i]) : 1.0;
      k.inverse_inertia[i] = real ? 1.0 / p.moment_of_inertia(k.order[i]) : 1.0;
    }
    k.motion.assign(padded, 0);
    k.partial.assign(static_cast<std::size_t>(k.blocks) * kPartials, 0.0);
  }
  set_prescribed_motions({});
}

ExplicitIntegrator::~ExplicitIntegrator() = default;
ExplicitIntegrator::ExplicitIntegrator(ExplicitIntegrator&&) noexcept = default;

void ExplicitIntegrator::set_prescribed_motions(const std::vector<PrescribedMotion>& motions) {
  const Particles& p = model_.particles;
  const int n = p.size();
  fixed_velocity_.setConstant(n, 3, false);
  fixed_angular_velocity_.setConstant(n, 3, false);
  prescribed_velocity_.setZero(n, 3);
  prescribed_angular_velocity_.setZero(n, 3);
  for (const PrescribedMotion& m : motions) {
    require(m.velocity.allFinite() && m.angular_velocity.allFinite(),
            "a prescribed velocity is not finite");
    for (int i = 0; i < n; ++i) {
      if (p.group(i) != static_cast<int>(m.group)) continue;
      for (int c = 0; c < 3; ++c) {
        if (m.fix_velocity[c]) {
          fixed_velocity_(i, c) = true;
          prescribed_velocity_(i, c) = m.velocity(c);
        }
        if (m.fix_angular_velocity[c]) {
          fixed_angular_velocity_(i, c) = true;
          prescribed_angular_velocity_(i, c) = m.angular_velocity(c);
        }
      }
    }
  }
  free_particles_ = 0;
  for (int i = 0; i < n; ++i) free_particles_ += fixed_velocity_.row(i).any() ? 0 : 1;
  if (!fused_) return;

  // The same motions as classes: one per group that a motion names.
  FusedState& k = fused_->state;
  k.classes.assign(1, MotionClass{});
  std::map<int, int> class_of_group;
  for (const PrescribedMotion& m : motions) {
    const auto [it, inserted] =
        class_of_group.try_emplace(static_cast<int>(m.group), static_cast<int>(k.classes.size()));
    if (inserted) k.classes.emplace_back();
    MotionClass& cls = k.classes[it->second];
    for (int c = 0; c < 3; ++c) {
      if (m.fix_velocity[c]) {
        cls.fix_velocity[c] = -1;
        cls.velocity[c] = m.velocity(c);
        cls.free = 0;
      }
      if (m.fix_angular_velocity[c]) {
        cls.fix_angular_velocity[c] = -1;
        cls.angular_velocity[c] = m.angular_velocity(c);
      }
    }
  }
  require(k.classes.size() <= 256, "more than 255 boundary groups have prescribed motions");
  for (int i = 0; i < k.particles; ++i) {
    const auto it = class_of_group.find(p.group(k.order[i]));
    k.motion[i] = static_cast<std::uint8_t>(it == class_of_group.end() ? 0 : it->second);
  }
}

std::string_view to_string(RunStop stop) {
  switch (stop) {
    case RunStop::kQuasiStatic:
      return "quasi-static";
    case RunStop::kCycleLimit:
      return "cycle limit";
    case RunStop::kTimeLimit:
      return "time limit";
    case RunStop::kHook:
      return "hook";
  }
  return "?";
}

void RunControl::validate() const {
  require(check_interval >= 1,
          fmt::format("the check interval must be at least one cycle, got {}", check_interval));
  require(max_cycles >= 0,
          fmt::format("max cycles must be >= 0 (0 = no limit), got {}", max_cycles));
  require(std::isfinite(tolerance) && tolerance >= 0,
          fmt::format("the quasi-static tolerance must be >= 0 (0 = off), got {}", tolerance));
  require(std::isfinite(time_limit_seconds) && time_limit_seconds >= 0,
          fmt::format("the time limit must be >= 0 s (0 = none), got {}", time_limit_seconds));
  require(std::isfinite(progress_seconds) && progress_seconds >= 0,
          fmt::format("the progress interval must be >= 0 s, got {}", progress_seconds));
  require(max_cycles > 0 || tolerance > 0 || time_limit_seconds > 0,
          "a run needs a stop condition: max cycles, a quasi-static tolerance or a time limit");
}

CycleReport ExplicitIntegrator::cycle() {
  return advance(1);
}

CycleReport ExplicitIntegrator::advance(long cycles) {
  if (!(cycles >= 1)) throw Error(fmt::format("cannot advance {} cycles: at least one", cycles));
  RunControl control;
  control.check_interval = cycles;
  control.max_cycles = cycles;
  return run(control).last;
}

void ExplicitIntegrator::load_kernel() {
  if (!fused_) return;
  FusedState& k = fused_->state;
  const Particles& p = model_.particles;
  k.parity = 0;
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < k.particles; ++i) {
      const int m = k.order[i];
      k.displacement[0][c][i] = p.displacement(m, c);
      k.rotation[0][c][i] = p.rotation(m, c);
      k.velocity[c][i] = p.velocity(m, c);
      k.angular_velocity[c][i] = p.angular_velocity(m, c);
    }
  }
}

void ExplicitIntegrator::store_kernel() {
  if (!fused_) return;
  const FusedState& k = fused_->state;
  Particles& p = model_.particles;
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < k.particles; ++i) {
      const int m = k.order[i];
      p.displacement(m, c) = k.displacement[k.parity][c][i];
      p.rotation(m, c) = k.rotation[k.parity][c][i];
      p.velocity(m, c) = k.velocity[c][i];
      p.angular_velocity(m, c) = k.angular_velocity[c][i];
    }
  }
}

CycleReport ExplicitIntegrator::step(long cycles) {
  if (!fused_) {
    CycleReport report;
    for (long c = 0; c < cycles; ++c) {
      if (c + 1 == cycles) {
        previous_displacement_ = model_.particles.displacement;
        previous_rotation_ = model_.particles.rotation;
      }
      report = reference_cycle();
    }
    return report;
  }
  FusedState& k = fused_->state;
  Particles& p = model_.particles;
  StepArgs args;
  args.state = &k;
  args.dt = time_step_;
  args.alpha = settings_.local_damping;
  for (int c = 0; c < 3; ++c) {
    args.force_out[c] = p.force.col(c).data();
    args.torque_out[c] = p.torque.col(c).data();
  }
  args.partial = k.partial.data();
  const int blocks = k.blocks;
  const int first_parity = k.parity;
#pragma omp parallel if (blocks >= 2 * kMinBlocksPerThread)
  {
    const long threads = omp_get_num_threads();
    const long thread = omp_get_thread_num();
    const int begin = static_cast<int>(blocks * thread / threads);
    const int end = static_cast<int>(blocks * (thread + 1) / threads);
    StepArgs mine = args;
    for (long s = 0; s < cycles; ++s) {
      mine.parity = static_cast<int>((first_parity + s) & 1);
      step_blocks(mine, s + 1 == cycles, begin, end);
#pragma omp barrier
    }
  }
  k.parity = static_cast<int>((first_parity + cycles) & 1);
  // Block sums in block order: the report does not depend on the number of threads.
  double sums[kPartials] = {0, 0, 0, 0};
  for (int b = 0; b < blocks; ++b)
    for (int q = 0; q < kPartials; ++q)
      sums[q] += k.partial[static_cast<std::size_t>(b) * kPartials + q];
  CycleReport report;
  report.strain_energy = sums[0];
  report.kinetic_energy = 0.5 * sums[2];
  const double mean_bond_force = sums[1] / std::max(1, model_.bonds.size());
  report.unbalanced_force_ratio =
      mean_bond_force > 0 ? sums[3] / std::max(1, free_particles_) / mean_bond_force : 0.0;
  for (long c = 0; c < cycles; ++c) time_ += time_step_;
  cycles_ += cycles;
  return report;
}

RunReport ExplicitIntegrator::run(const RunControl& control) {
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point from, Clock::time_point to) {
    return std::chrono::duration<double>(to - from).count();
  };
  require(!running_, "run() was called from one of its own hooks");
  control.validate();
  const Clock::time_point start = Clock::now();
  RunReport report;
  running_ = true;
  load_kernel();
  // The model gets the state back however the run ends (an exception from a hook included).
  struct Finish {
    ExplicitIntegrator& integrator;
    RunReport& report;
    Clock::time_point start;
    ~Finish() {
      const Clock::time_point t = Clock::now();
      integrator.store_kernel();
      integrator.running_ = false;
      const Clock::time_point end = Clock::now();
      report.transfer_seconds += std::chrono::duration<double>(end - t).count();
      report.wall_seconds = std::chrono::duration<double>(end - start).count();
    }
  } finish{*this, report, start};
  report.transfer_seconds = seconds(start, Clock::now());

  Clock::time_point last_progress = start;
  long previous_check_cycles = 0;
  double previous_ratio = 0;
  while (true) {
    long chunk = control.check_interval;
    if (control.max_cycles > 0) chunk = std::min(chunk, control.max_cycles - report.cycles);
    const Clock::time_point kernel_start = Clock::now();
    report.last = step(chunk);
    const Clock::time_point check_start = Clock::now();
    report.kernel_seconds += seconds(kernel_start, check_start);
    report.cycles += chunk;
    ++report.checks;

    RunCheck check;
    check.cycles = cycles_;
    check.run_cycles = report.cycles;
    check.report = report.last;
    check.elapsed_seconds = seconds(start, check_start);
    const double ratio = report.last.unbalanced_force_ratio;
    const double per_cycle =
        (report.kernel_seconds + report.check_seconds) / static_cast<double>(report.cycles);
    auto estimate = [&](double left) {
      if (left >= 0 && (check.seconds_left < 0 || left < check.seconds_left))
        check.seconds_left = left;
    };
    if (control.max_cycles > 0)
      estimate(static_cast<double>(control.max_cycles - report.cycles) * per_cycle);
    if (control.tolerance > 0 && previous_check_cycles > 0 && ratio < previous_ratio &&
        ratio > control.tolerance) {
      const double decay = std::log(previous_ratio / ratio) /
                           static_cast<double>(report.cycles - previous_check_cycles);
      estimate(std::log(ratio / control.tolerance) / decay * per_cycle);
    }
    if (control.time_limit_seconds > 0)
      estimate(std::max(0.0, control.time_limit_seconds - check.elapsed_seconds));
    previous_check_cycles = report.cycles;
    previous_ratio = ratio;

    const bool go_on = control.on_check ? control.on_check(check) : true;
    if (control.on_progress && seconds(last_progress, Clock::now()) > control.progress_seconds) {
      control.on_progress(check);
      last_progress = Clock::now();
    }
    const Clock::time_point check_end = Clock::now();
    report.check_seconds += seconds(check_start, check_end);
    if (control.tolerance > 0 && ratio <= control.tolerance) {
      report.stop = RunStop::kQuasiStatic;
      break;
    }
    if (control.max_cycles > 0 && report.cycles >= control.max_cycles) {
      report.stop = RunStop::kCycleLimit;
      break;
    }
    if (control.time_limit_seconds > 0 && seconds(start, check_end) >= control.time_limit_seconds) {
      report.stop = RunStop::kTimeLimit;
      break;
    }
    if (!go_on) {
      report.stop = RunStop::kHook;
      break;
    }
  }
  return report;
}

void ExplicitIntegrator::gather(std::span<const int> particles, Particles& into, StateAt at) const {
  const Particles& p = model_.particles;
  require(into.size() == p.size(),
          fmt::format("gather() into {} particles: the model has {}", into.size(), p.size()));
  require(at == StateAt::kCurrent || running_,
          "the state the forces belong to can be gathered during a run only (from a hook)");
  require(at == StateAt::kCurrent || &into != &p,
          "the state the forces belong to cannot be gathered into the model's own particles");
  for (int i : particles)
    if (i < 0 || i >= p.size()) throw Error(fmt::format("gather(): no particle {}", i));
  const bool own = &into == &p;
  const bool from_kernel = fused_ && running_;
  for (int i : particles) {
    for (int c = 0; c < 3; ++c) {
      if (from_kernel) {
        const FusedState& k = fused_->state;
        const int j = k.position[i];
        const int buffer = at == StateAt::kCurrent ? k.parity : 1 - k.parity;
        into.displacement(i, c) = k.displacement[buffer][c][j];
        into.rotation(i, c) = k.rotation[buffer][c][j];
        into.velocity(i, c) = k.velocity[c][j];
        into.angular_velocity(i, c) = k.angular_velocity[c][j];
      } else if (!own) {
        into.displacement(i, c) =
            at == StateAt::kCurrent ? p.displacement(i, c) : previous_displacement_(i, c);
        into.rotation(i, c) = at == StateAt::kCurrent ? p.rotation(i, c) : previous_rotation_(i, c);
        into.velocity(i, c) = p.velocity(i, c);
        into.angular_velocity(i, c) = p.angular_velocity(i, c);
      }
      if (!own) {
        into.force(i, c) = p.force(i, c);
        into.torque(i, c) = p.torque(i, c);
      }
    }
  }
}

void ExplicitIntegrator::drop_bond(int bond) {
  Bonds& bonds = model_.bonds;
  require(bond >= 0 && bond < bonds.size(),
          fmt::format("cannot drop bond {}: the model has {} bonds", bond, bonds.size()));
  if (fused_) {
    const std::vector<int>& position = fused_->state.position;
    fused_->state.bonds.drop_bond(position[bonds.first(bond)], position[bonds.second(bond)]);
  }
  std::vector<int> kept;
  kept.reserve(static_cast<std::size_t>(bonds.size()));
  for (int b = 0; b < bonds.size(); ++b)
    if (b != bond) kept.push_back(b);
  bonds = bonds.select(kept);
}

std::size_t ExplicitIntegrator::kernel_bytes() const {
  return fused_ ? fused_->state.bytes() : 0;
}

CycleReport ExplicitIntegrator::reference_cycle() {
  Particles& p = model_.particles;
  const BondPass pass = compute_bond_forces(p, model_.bonds);
  const double dt = time_step_;
  const double alpha = settings_.local_damping;
  CycleReport report;
  report.strain_energy = pass.strain_energy;
  double kinetic2 = 0;
  double unbalanced = 0;
  const int n = p.size();
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < n; ++i) {
      if (fixed_velocity_(i, c)) {
        p.velocity(i, c) = prescribed_velocity_(i, c);
        p.displacement(i, c) += dt * p.velocity(i, c);
      } else {
        kinetic2 += advance_dof(p.displacement(i, c), p.velocity(i, c), p.force(i, c), p.mass(i),
                                dt, alpha);
      }
      if (fixed_angular_velocity_(i, c)) {
        p.angular_velocity(i, c) = prescribed_angular_velocity_(i, c);
        p.rotation(i, c) += dt * p.angular_velocity(i, c);
      } else {
        kinetic2 += advance_dof(p.rotation(i, c), p.angular_velocity(i, c), p.torque(i, c),
                                p.moment_of_inertia(i), dt, alpha);
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!fixed_velocity_.row(i).any()) unbalanced += p.force.row(i).matrix().norm();
  }
  report.kinetic_energy = 0.5 * kinetic2;
  const double mean_bond_force = pass.sum_force_norm / std::max(1, model_.bonds.size());
  report.unbalanced_force_ratio =
      mean_bond_force > 0 ? unbalanced / std::max(1, free_particles_) / mean_bond_force : 0.0;
  time_ += dt;
  ++cycles_;
  return report;
}

}  // namespace plydem
