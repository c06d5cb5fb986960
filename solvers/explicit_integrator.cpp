#include "solvers/explicit_integrator.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <string_view>

#include "contacts/bond_kernel.hpp"
#include "contacts/particle_ordering.hpp"
#include "core/error.hpp"
#include "solvers/device_backend.hpp"

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
  settings.contact.validate();
  require(settings.backend == ExplicitBackend::kCpu || settings.kernel == ExplicitKernel::kFused,
          fmt::format("the {} backend runs the fused kernel only: the reference kernel runs on the "
                      "host (backend cpu)",
                      to_string(settings.backend)));
  require(settings.strength_storage == StrengthStorage::kAutomatic ||
              settings.strength_storage == StrengthStorage::kTypes ||
              settings.strength_storage == StrengthStorage::kSlots,
          "the strength storage is no StrengthStorage");
}

namespace {

// MotionClass and KernelMode: solvers/particle_step.hpp (the device backends share them).

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
  // Per block: energy, bond force norm, 2 x kinetic, unbalanced, and the account's second halves
  // of the report cycle: - F . v(n+1/2) (prescribed), damping . v(n+1/2) (free).
  std::vector<double> partial;
  int parity = 0;  // the buffer holding the current displacements and rotations
  // Breaking: the contacts' forces and which blocks have any; the account's per-particle sums of
  // - F (v_old + v_new) (prescribed) and damping (v_old + v_new) (free); per thread, its damage
  // steps and a flag.
  lanes::Array contact_force[3], contact_torque[3];
  std::vector<std::uint8_t> contact_block;
  lanes::Array work_sum, damping_sum;
  std::vector<std::vector<SlotEvent>> thread_events;
  std::vector<int> changed_flags;
  // A device backend (ExplicitSettings::backend), its report's forces in kernel order, its last
  // report sums, and the table as it came back.
  std::unique_ptr<DeviceBackend> device;
  lanes::Array device_force[3], device_torque[3];
  double device_sums[kParticlePartials] = {};
  std::vector<std::int32_t> device_types;
  bool motions_changed = false;

  std::size_t bytes() const {
    std::size_t arrays = 0;
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 3; ++c) arrays += displacement[b][c].bytes() + rotation[b][c].bytes();
    for (int c = 0; c < 3; ++c)
      arrays += velocity[c].bytes() + angular_velocity[c].bytes() + contact_force[c].bytes() +
                contact_torque[c].bytes();
    arrays +=
        inverse_mass.bytes() + inverse_inertia.bytes() + work_sum.bytes() + damping_sum.bytes();
    return arrays + bonds.bytes() + (order.size() + position.size()) * sizeof(int) + motion.size() +
           classes.size() * sizeof(MotionClass) + partial.size() * sizeof(double) +
           contact_block.size();
  }
};

constexpr int kPartials = 6;

struct StepArgs {
  FusedState* state = nullptr;
  int mode = kElasticMode;
  BreakingPass* pass = nullptr;
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
                                                 lanes::Doubles& v_old, lanes::Doubles& damping) {
  using lanes::Doubles;
  using lanes::Mask;
  const Mask sign_bit = Mask{} + std::numeric_limits<std::int64_t>::min();
  const Doubles magnitude = (Doubles)((Mask)force & ~sign_bit);
  const Doubles push = alpha * magnitude;
  const Doubles signed_push = (Doubles)((Mask)push | ((Mask)v & sign_bit));
  damping = v == Doubles{} ? Doubles{} : signed_push;
  v_old = v;
  const Doubles free = v + dt_over_inertia * (force - damping);
  v = (Doubles)(((Mask)imposed & fixed) | ((Mask)free & ~fixed));  // bitwise select: no branches
  u += dt * v;
}

// One component's share of the energy account: damping (v_old + v_new) where it is free, and
// - F (v_old + v_new) where it is prescribed (blocks with prescribed particles only), and the
// second halves (v_new alone) on the report cycle.
template <bool kReport>
[[gnu::always_inline]] inline void account_lanes(
    const lanes::Doubles& f, const lanes::Doubles& damping, const lanes::Doubles& v_old,
    const lanes::Doubles& v, const lanes::Mask& fixed, bool prescribed, lanes::Doubles& damping_sum,
    lanes::Doubles& work_sum, lanes::Doubles& damping_half, lanes::Doubles& work_half) {
  using lanes::Doubles;
  using lanes::Mask;
  const Doubles both = v_old + v;
  damping_sum += (Doubles)((Mask)(damping * both) & ~fixed);
  if (prescribed) work_sum -= (Doubles)((Mask)(f * both) & fixed);
  if constexpr (kReport) {
    damping_half += (Doubles)((Mask)(damping * v) & ~fixed);
    if (prescribed) work_half -= (Doubles)((Mask)(f * v) & fixed);
  }
}

// The prescribed motions of a block's particles, lane by lane: which components are fixed, their
// imposed velocities, and which particles count as free. Most blocks hold free particles only.
struct BlockMotions {
  lanes::Mask fix_velocity[3] = {}, fix_angular_velocity[3] = {};
  lanes::Doubles velocity[3] = {}, angular_velocity[3] = {};
  lanes::Mask counts_free = lanes::Mask{} - 1;
};

// Fills `m` for the block starting at particle `first`; returns the block's eight motion classes
// packed in one word (0: all free, and `m` keeps its defaults).
[[gnu::always_inline]] inline std::uint64_t load_block_motions(const FusedState& k, int first,
                                                               BlockMotions& m) {
  std::uint64_t classes;
  std::memcpy(&classes, k.motion.data() + first, sizeof classes);
  if (classes != 0) {
    for (int l = 0; l < lanes::kCount; ++l) {
      const MotionClass& motion = k.classes[k.motion[first + l]];
      for (int c = 0; c < 3; ++c) {
        m.fix_velocity[c][l] = motion.fix_velocity[c];
        m.fix_angular_velocity[c][l] = motion.fix_angular_velocity[c];
        m.velocity[c][l] = motion.velocity[c];
        m.angular_velocity[c][l] = motion.angular_velocity[c];
      }
      m.counts_free[l] = motion.free;
    }
  }
  return classes;
}

template <bool kReport, int kMode>
[[gnu::always_inline]] inline void step_range(const StepArgs& a, int begin_block, int end_block) {
  using lanes::Doubles;
  using lanes::Mask;
  constexpr int kLanes = lanes::kCount;
  constexpr bool kBreaking = kMode != kElasticMode;
  constexpr bool kSoften = kMode == kSofteningTypes || kMode == kSofteningSlots;
  constexpr bool kSlotStrength = kMode == kBrittleSlots || kMode == kSofteningSlots;
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
    if constexpr (kBreaking) {
      gather_breaking_block<kReport, kSoften, kSlotStrength>(k.bonds, first, state, force, torque,
                                                             energy, bond_force, *a.pass);
      if (k.contact_block[block]) {
        for (int c = 0; c < 3; ++c) {
          Doubles f, m;
          lanes::load(k.contact_force[c].data() + first, f);
          lanes::load(k.contact_torque[c].data() + first, m);
          force[c] += f;
          torque[c] += m;
        }
      }
    } else {
      gather_bond_block<kReport>(k.bonds, first, state, force, torque, energy, bond_force);
    }

    BlockMotions motions;
    const std::uint64_t classes = load_block_motions(k, first, motions);
    const Mask(&fix_v)[3] = motions.fix_velocity;
    const Mask(&fix_w)[3] = motions.fix_angular_velocity;
    const Doubles(&imposed_v)[3] = motions.velocity;
    const Doubles(&imposed_w)[3] = motions.angular_velocity;
    const Mask& counts_free = motions.counts_free;
    Doubles inverse_mass, inverse_inertia;
    lanes::load(k.inverse_mass.data() + first, inverse_mass);
    lanes::load(k.inverse_inertia.data() + first, inverse_inertia);
    const Doubles dt_over_mass = a.dt * inverse_mass;
    const Doubles dt_over_inertia = a.dt * inverse_inertia;
    Doubles kinetic{};
    // The account (breaking kernel): sums of damping (v_old + v_new) over free components and of
    // - F (v_old + v_new) over prescribed ones, and the report cycle's second halves.
    Doubles damping_sum{}, work_sum{}, damping_half{}, work_half{};
    for (int c = 0; c < 3; ++c) {
      Doubles u, v, v_old, damping;
      lanes::load(state.displacement[c] + first, u);
      lanes::load(vel[c] + first, v);
      advance_lanes(force[c], dt_over_mass, fix_v[c], imposed_v[c], a.dt, a.alpha, u, v, v_old,
                    damping);
      lanes::store(next_u[c] + first, u);
      lanes::store(vel[c] + first, v);
      if constexpr (kReport) kinetic += (Doubles)((Mask)(v_old / inverse_mass * v) & ~fix_v[c]);
      if constexpr (kBreaking)
        account_lanes<kReport>(force[c], damping, v_old, v, fix_v[c], classes != 0, damping_sum,
                               work_sum, damping_half, work_half);

      lanes::load(state.rotation[c] + first, u);
      lanes::load(ang[c] + first, v);
      advance_lanes(torque[c], dt_over_inertia, fix_w[c], imposed_w[c], a.dt, a.alpha, u, v, v_old,
                    damping);
      lanes::store(next_t[c] + first, u);
      lanes::store(ang[c] + first, v);
      if constexpr (kReport) kinetic += (Doubles)((Mask)(v_old / inverse_inertia * v) & ~fix_w[c]);
      if constexpr (kBreaking)
        account_lanes<kReport>(torque[c], damping, v_old, v, fix_w[c], classes != 0, damping_sum,
                               work_sum, damping_half, work_half);
    }
    if constexpr (kBreaking) {
      Doubles sum;
      lanes::load(k.damping_sum.data() + first, sum);
      sum += damping_sum;
      lanes::store(k.damping_sum.data() + first, sum);
      if (classes != 0) {
        lanes::load(k.work_sum.data() + first, sum);
        sum += work_sum;
        lanes::store(k.work_sum.data() + first, sum);
      }
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
      partial[4] = lanes::sum(work_half);
      partial[5] = lanes::sum(damping_half);
    }
  }
}

template <bool kReport>
[[gnu::always_inline]] inline void step_mode(const StepArgs& a, int begin_block, int end_block) {
  switch (a.mode) {
    case kBrittleTypes:
      step_range<kReport, kBrittleTypes>(a, begin_block, end_block);
      break;
    case kBrittleSlots:
      step_range<kReport, kBrittleSlots>(a, begin_block, end_block);
      break;
    case kSofteningTypes:
      step_range<kReport, kSofteningTypes>(a, begin_block, end_block);
      break;
    case kSofteningSlots:
      step_range<kReport, kSofteningSlots>(a, begin_block, end_block);
      break;
    default:
      step_range<kReport, kElasticMode>(a, begin_block, end_block);
  }
}

PLYDEM_TARGET_CLONES void step_blocks(const StepArgs& a, bool report, int begin_block,
                                      int end_block) {
  if (report) {
    step_mode<true>(a, begin_block, end_block);
  } else {
    step_mode<false>(a, begin_block, end_block);
  }
}

// Below this many blocks per thread a cycle is too short to share.
constexpr int kMinBlocksPerThread = 32;

// The host arrays a device backend mirrors (solvers/device_backend.hpp).
DeviceArrays device_arrays(FusedState& k, int mode) {
  DeviceArrays a;
  GatherBonds& g = k.bonds;
  a.particles = k.particles;
  a.padded = g.padded_count();
  a.width = g.width();
  a.type_count = g.type_count();
  a.mode = mode;
  for (int b = 0; b < 2; ++b)
    for (int c = 0; c < 3; ++c) {
      a.displacement[b][c] = k.displacement[b][c].data();
      a.rotation[b][c] = k.rotation[b][c].data();
    }
  for (int c = 0; c < 3; ++c) {
    a.velocity[c] = k.velocity[c].data();
    a.angular_velocity[c] = k.angular_velocity[c].data();
    a.force[c] = k.device_force[c].data();
    a.torque[c] = k.device_torque[c].data();
  }
  a.inverse_mass = k.inverse_mass.data();
  a.inverse_inertia = k.inverse_inertia.data();
  a.motion = k.motion.data();
  a.classes = k.classes.data();
  a.class_count = static_cast<int>(k.classes.size());
  a.neighbour = g.neighbours(0);
  a.type = g.types(0);
  a.types = &g.type(0);
  if (mode != kElasticMode) {
    a.failure = &g.failure(0);
    a.slot_bond = g.slot_bonds();
    a.work_sum = k.work_sum.data();
    a.damping_sum = k.damping_sum.data();
  }
  if (mode == kBrittleSlots || mode == kSofteningSlots) {
    a.slot_alpha = g.slot_screen_displacement();
    a.slot_beta = g.slot_screen_rotation();
    a.slot_tensile = g.slot_tensile_strengths();
    a.slot_cohesion = g.slot_cohesions();
  }
  if (mode == kSofteningTypes || mode == kSofteningSlots) {
    a.slot_damage = g.slot_damage();
    a.slot_kappa = g.slot_kappa();
  }
  return a;
}

}  // namespace

struct ExplicitIntegrator::Fused {
  FusedState state;
};

ExplicitIntegrator::ExplicitIntegrator(Model& model, const ExplicitSettings& settings)
    : model_(model), settings_(settings) {
  validate(settings);
  model.check_consistency();
  for (int b = 0; b < model.bonds.size(); ++b)
    require(model.bonds.out_of_plane_shear_ratio(b) == 1,
            fmt::format("bond {} carries its out-of-plane shear with a stiffness of its own (k_z / "
                        "k_s = {:.4g}: plies that carry the laminate's transverse shear, "
                        "InterfaceStiffness::transverse_shear), which the explicit kernels do not "
                        "have yet: run this model with the static or events solver, or build it "
                        "without transverse shear in the plies",
                        b, model.bonds.out_of_plane_shear_ratio(b)));
  // The bonds' intact stiffnesses (the arrays hold 1 - damage times them; unknown, 0, for a bond
  // that came broken), and what the model asks of the kernel.
  const Bonds& bonds = model.bonds;
  for (Eigen::ArrayXd& k : intact_) k.setZero(bonds.size());
  kappa_.setOnes(bonds.size());
  bool broken = false, damaged = false, softening = false;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) {
      broken = true;
      continue;
    }
    const double scale = 1.0 / (1.0 - bonds.damage(b));
    intact_[0](b) = scale * bonds.normal_stiffness(b);
    intact_[1](b) = scale * bonds.shear_stiffness(b);
    intact_[2](b) = scale * bonds.bending_stiffness(b);
    intact_[3](b) = scale * bonds.twisting_stiffness(b);
    damaged |= bonds.damage(b) > 0;
    const bool breakable =
        std::isfinite(bonds.tensile_strength(b)) || std::isfinite(bonds.cohesion(b));
    const BondStrength strength = bond_strength(bonds, b);
    softening |= breakable && may_soften(strength);
    kappa_(b) = softening_history(bonds.damage(b), strength);
  }
  breaking_ = bonds.breakable() || broken || settings.energy_account;
  softening_ = breaking_ && (softening || damaged);
  // A damaged or broken bond's contact is as stiff as the intact bond: the time step is theirs.
  double critical = 0;
  if (broken || damaged) {
    Model intact = model;
    intact.bonds.normal_stiffness = intact_[0];
    intact.bonds.shear_stiffness = intact_[1];
    intact.bonds.bending_stiffness = intact_[2];
    intact.bonds.twisting_stiffness = intact_[3];
    critical = critical_time_step(intact);
  } else {
    critical = critical_time_step(model);
  }
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
    k.bonds = GatherBonds(model.bonds, k.order, {breaking_, softening_, settings.strength_storage});
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
    if (settings.backend == ExplicitBackend::kCuda) k.device = make_cuda_backend();
    if (settings.backend == ExplicitBackend::kDeviceEmulation) k.device = make_emulation_backend();
    if (k.device) {
      for (int c = 0; c < 3; ++c) {
        k.device_force[c] = lanes::Array(padded);
        k.device_torque[c] = lanes::Array(padded);
      }
    }
  }
  set_prescribed_motions({});
  if (breaking_) start_breaking();
}

void ExplicitIntegrator::start_breaking() {
  breaking_ = true;
  const int n = model_.particles.size();
  if (fused_) {
    FusedState& k = fused_->state;
    if (!k.bonds.breaking())
      k.bonds = GatherBonds(model_.bonds, k.order, {true, softening_, settings_.strength_storage});
    const int padded = k.bonds.padded_count();
    for (int c = 0; c < 3; ++c) {
      k.contact_force[c] = lanes::Array(padded);
      k.contact_torque[c] = lanes::Array(padded);
    }
    k.contact_block.assign(static_cast<std::size_t>(k.blocks), 0);
    k.work_sum = lanes::Array(padded);
    k.damping_sum = lanes::Array(padded);
  } else {
    work_sum_.setZero(n);
    damping_sum_.setZero(n);
    contact_force_.setZero(n, 3);
    contact_torque_.setZero(n, 3);
  }
  initial_set_ = false;
  make_contacts();
}

void ExplicitIntegrator::make_contacts() {
  if (!settings_.contacts) return;
  require(!fused_ || !fused_->state.device,
          fmt::format("the {} backend has no contacts between unbonded particles yet: a run whose "
                      "bonds can break (or that keeps the energy account) needs contacts off "
                      "(ExplicitSettings::contacts = false), or backend cpu",
                      to_string(settings_.backend)));
  const Particles& p = model_.particles;
  std::vector<int> index(static_cast<std::size_t>(p.size()));
  ContactState s;
  if (fused_) {
    if (!running_) load_kernel();
    FusedState& k = fused_->state;
    index = k.position;
    for (int c = 0; c < 3; ++c) {
      s.displacement[c] = k.displacement[k.parity][c].data();
      s.rotation[c] = k.rotation[k.parity][c].data();
      s.velocity[c] = k.velocity[c].data();
      s.angular_velocity[c] = k.angular_velocity[c].data();
    }
  } else {
    std::iota(index.begin(), index.end(), 0);
    for (int c = 0; c < 3; ++c) {
      s.displacement[c] = p.displacement.col(c).data();
      s.rotation[c] = p.rotation.col(c).data();
      s.velocity[c] = p.velocity.col(c).data();
      s.angular_velocity[c] = p.angular_velocity.col(c).data();
    }
  }
  contacts_ = std::make_unique<UnbondedContacts>(model_, intact_[0], intact_[1], std::move(index),
                                                 settings_.contact, s);
  contact_countdown_ = 0;
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
  k.motions_changed = true;
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
  if (k.device) {
    k.device->upload(device_arrays(k, kernel_mode()));
    k.motions_changed = false;
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
  const double dt = time_step_;
  if (breaking_ && !initial_set_) {
    // The account starts from the energy the state holds before its first cycle.
    Particles now = model_.particles;
    std::vector<int> all(static_cast<std::size_t>(now.size()));
    std::iota(all.begin(), all.end(), 0);
    gather(all, now);
    double kinetic = 0;
    for (int i = 0; i < now.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        if (!fixed_velocity_(i, c))
          kinetic += now.mass(i) * now.velocity(i, c) * now.velocity(i, c);
        if (!fixed_angular_velocity_(i, c))
          kinetic +=
              now.moment_of_inertia(i) * now.angular_velocity(i, c) * now.angular_velocity(i, c);
      }
    initial_energy_ = bond_strain_energy(now, model_.bonds) + 0.5 * kinetic;
    initial_set_ = true;
  }
  released_ += released_pending_;
  released_pending_ = 0;
  if (!fused_) {
    CycleReport report;
    for (long c = 0; c < cycles; ++c) {
      if (contacts_ && contact_countdown_ <= 0) {
        const Particles& p = model_.particles;
        ContactState s;
        for (int q = 0; q < 3; ++q) {
          s.displacement[q] = p.displacement.col(q).data();
          s.rotation[q] = p.rotation.col(q).data();
          s.velocity[q] = p.velocity.col(q).data();
          s.angular_velocity[q] = p.angular_velocity.col(q).data();
        }
        contact_countdown_ = contacts_->check(s, dt);
      }
      const bool last = c + 1 == cycles;
      if (last) {
        previous_displacement_ = model_.particles.displacement;
        previous_rotation_ = model_.particles.rotation;
      }
      if (contacts_) --contact_countdown_;
      report = reference_cycle(last);
    }
    if (breaking_) last_report_ = report;
    return report;
  }
  FusedState& k = fused_->state;
  long remaining = cycles;
  while (remaining > 0) {
    if (contacts_ && contact_countdown_ <= 0) {
      ContactState s;
      for (int c = 0; c < 3; ++c) {
        s.displacement[c] = k.displacement[k.parity][c].data();
        s.rotation[c] = k.rotation[k.parity][c].data();
        s.velocity[c] = k.velocity[c].data();
        s.angular_velocity[c] = k.angular_velocity[c].data();
      }
      contact_countdown_ = contacts_->check(s, dt);
    }
    const long chunk = contacts_ ? std::min(remaining, contact_countdown_) : remaining;
    const long ran = fused_cycles(chunk, chunk == remaining);
    remaining -= ran;
    if (contacts_) contact_countdown_ -= ran;
    for (long c = 0; c < ran; ++c) time_ += dt;
    cycles_ += ran;
    if (breaking_) {
      std::vector<SlotEvent> events;
      for (auto& thread : k.thread_events) {
        events.insert(events.end(), thread.begin(), thread.end());
        thread.clear();
      }
      resolve_events(events, remaining == 0 ? cycles_ - 1 : -1);
    }
  }
  // Block sums in block order: the report does not depend on the number of threads.
  double sums[kPartials] = {0, 0, 0, 0, 0, 0};
  if (k.device) {
    std::copy(k.device_sums, k.device_sums + kPartials, sums);  // reduced on the device
  } else {
    for (int b = 0; b < k.blocks; ++b)
      for (int q = 0; q < kPartials; ++q)
        sums[q] += k.partial[static_cast<std::size_t>(b) * kPartials + q];
  }
  CycleReport report;
  report.strain_energy = sums[0];
  report.kinetic_energy = 0.5 * sums[2];
  const double mean_bond_force = sums[1] / std::max(1, model_.bonds.size());
  report.unbalanced_force_ratio =
      mean_bond_force > 0 ? sums[3] / std::max(1, free_particles_) / mean_bond_force : 0.0;
  if (breaking_) {
    last_report_ = report;
    pending_work_ = 0.5 * dt * sums[4];
    pending_damping_ = 0.5 * dt * sums[5];
  }
  return report;
}

long ExplicitIntegrator::device_cycles(long cycles, bool report_last) {
  FusedState& k = fused_->state;
  const DeviceArrays arrays = device_arrays(k, kernel_mode());
  if (k.motions_changed) {
    k.device->upload_motions(arrays);
    k.motions_changed = false;
  }
  DeviceBatch batch = k.device->run_cycles(cycles, k.parity, report_last, cycles_, time_step_,
                                           settings_.local_damping);
  k.parity = static_cast<int>((k.parity + batch.cycles) & 1);
  k.device->download_state(arrays);
  if (breaking_) {
    // The slots the device emptied are emptied here too (with their blocks' tables).
    k.device->download_table(arrays, k.device_types);
    GatherBonds& g = k.bonds;
    const std::size_t padded = static_cast<std::size_t>(g.padded_count());
    for (std::size_t cell = 0; cell < k.device_types.size(); ++cell)
      if (k.device_types[cell] == 0 && g.holds(cell))
        g.clear_slot(static_cast<int>(cell % padded), static_cast<int>(cell / padded));
    k.thread_events.assign(1, std::move(batch.events));
  }
  if (batch.reported) {
    std::copy(batch.sums, batch.sums + kPartials, k.device_sums);
    Particles& p = model_.particles;
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < k.particles; ++i) {
        p.force(k.order[i], c) = k.device_force[c][i];
        p.torque(k.order[i], c) = k.device_torque[c][i];
      }
  }
  return batch.cycles;
}

int ExplicitIntegrator::kernel_mode() const {
  if (!breaking_) return kElasticMode;
  const bool slots = fused_ && fused_->state.bonds.slot_strengths();
  return (softening_ ? kSofteningTypes : kBrittleTypes) + (slots ? 1 : 0);
}

long ExplicitIntegrator::fused_cycles(long cycles, bool report_last) {
  FusedState& k = fused_->state;
  if (k.device) return device_cycles(cycles, report_last);
  Particles& p = model_.particles;
  StepArgs args;
  args.state = &k;
  args.dt = time_step_;
  args.alpha = settings_.local_damping;
  args.mode = kernel_mode();
  for (int c = 0; c < 3; ++c) {
    args.force_out[c] = p.force.col(c).data();
    args.torque_out[c] = p.torque.col(c).data();
  }
  args.partial = k.partial.data();
  const int blocks = k.blocks;
  const int first_parity = k.parity;
  const bool breaking = breaking_;
  const bool contacts = contacts_ && !contacts_->contacts().empty();
  // Each thread raises its flag for the cycle's parity when a slot of its blocks broke or softened;
  // after the cycle's barrier every thread reads all flags alike, so all stop after the same cycle
  // (its steps are resolved against the next state, and the contacts of its breaks added, before
  // the next cycle). A flag of parity q is written
  // again two cycles later, after every thread has passed the barrier that follows its reads.
  constexpr int kFlagStride = 16;  // one cache line per flag
  const int max_threads = omp_get_max_threads();
  if (breaking) {
    k.thread_events.resize(static_cast<std::size_t>(max_threads));
    for (auto& e : k.thread_events) e.clear();
    k.changed_flags.assign(static_cast<std::size_t>(2 * max_threads * kFlagStride), 0);
  }
  const long start_cycle = cycles_;
  long ran = cycles;
#pragma omp parallel if (blocks >= 2 * kMinBlocksPerThread)
  {
    const long threads = omp_get_num_threads();
    const long thread = omp_get_thread_num();
    const int begin = static_cast<int>(blocks * thread / threads);
    const int end = static_cast<int>(blocks * (thread + 1) / threads);
    StepArgs mine = args;
    BreakingPass pass;
    if (breaking) pass.events = &k.thread_events[static_cast<std::size_t>(thread)];
    mine.pass = &pass;
    for (long s = 0; s < cycles; ++s) {
      mine.parity = static_cast<int>((first_parity + s) & 1);
      const bool report = report_last && s + 1 == cycles;
      if (contacts) {
#pragma omp single
        {
          ContactState state;
          ContactForces out;
          for (int c = 0; c < 3; ++c) {
            state.displacement[c] = k.displacement[mine.parity][c].data();
            state.rotation[c] = k.rotation[mine.parity][c].data();
            state.velocity[c] = k.velocity[c].data();
            state.angular_velocity[c] = k.angular_velocity[c].data();
            out.force[c] = k.contact_force[c].data();
            out.torque[c] = k.contact_torque[c].data();
          }
          for (int i : contacts_->touched()) k.contact_block[i / lanes::kCount] = 0;
          contacts_->apply(state, args.dt, out);
          for (int i : contacts_->touched()) k.contact_block[i / lanes::kCount] = 1;
        }
      }
      pass.cycle = start_cycle + s;
      pass.changed = false;
      step_blocks(mine, report, begin, end);
      const std::size_t flags = static_cast<std::size_t>(s & 1) * max_threads;
      if (breaking) k.changed_flags[(flags + thread) * kFlagStride] = pass.changed ? 1 : 0;
#pragma omp barrier
      if (breaking) {
        bool any = false;
        for (long t = 0; t < threads; ++t) any |= k.changed_flags[(flags + t) * kFlagStride] != 0;
        if (any) {
          if (thread == 0) ran = s + 1;
          break;
        }
      }
    }
  }
  k.parity = static_cast<int>((first_parity + ran) & 1);
  return ran;
}

void ExplicitIntegrator::log_break(int bond, BondState mode, long cycle,
                                   const double* first_displacement) {
  Bonds& bonds = model_.bonds;
  bonds.state(bond) = static_cast<int>(mode);
  bonds.damage(bond) = 1;
  bonds.normal_stiffness(bond) = 0;
  bonds.shear_stiffness(bond) = 0;
  bonds.bending_stiffness(bond) = 0;
  bonds.twisting_stiffness(bond) = 0;
  BondBreak record;
  record.bond = bond;
  record.mode = mode;
  record.at = static_cast<double>(cycle) * time_step_;
  const int i = bonds.first(bond);
  for (int c = 0; c < 3; ++c)
    record.position(c) = model_.particles.reference_position(i, c) +
                         bonds.lever_first(bond) * bonds.normal(bond, c) + first_displacement[c];
  breaks_.push_back(record);
  if (contacts_) {
    contacts_->add_broken_bond(bond);
    contact_countdown_ = 0;  // a break sets particles moving: check the skin at the next cycle
  }
}

void ExplicitIntegrator::resolve_events(std::vector<SlotEvent>& events, long report_cycle) {
  std::sort(events.begin(), events.end(), [](const SlotEvent& a, const SlotEvent& b) {
    return a.cycle != b.cycle ? a.cycle < b.cycle : a.bond < b.bond;
  });
  // The state now is the one after each event's cycle (runs stop after a cycle with steps).
  const Particles& p = model_.particles;
  const Bonds& bonds = model_.bonds;
  auto state = [&](int i, int c, bool rotation) {
    if (!fused_) return rotation ? p.rotation(i, c) : p.displacement(i, c);
    const FusedState& k = fused_->state;
    const int j = k.position[i];
    return rotation ? k.rotation[k.parity][c][j] : k.displacement[k.parity][c][j];
  };
  for (const SlotEvent& e : events) {
    const int b = e.bond, i = bonds.first(b), j = bonds.second(b);
    double n[3], a[3], dtheta[3], du[3];
    for (int c = 0; c < 3; ++c) {
      n[c] = bonds.normal(b, c);
      a[c] = bonds.lever_first(b) * state(i, c, true) + bonds.lever_second(b) * state(j, c, true);
      dtheta[c] = state(j, c, true) - state(i, c, true);
    }
    for (int c = 0; c < 3; ++c) {
      const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      du[c] = (state(j, c, false) - state(i, c, false)) - (a[c1] * n[c2] - a[c2] * n[c1]);
    }
    double product = 0;  // q_n K q_n+1
    for (int c = 0; c < 3; ++c) product += e.force[c] * du[c] + e.moment[c] * dtheta[c];
    double released = 0.5 * (e.damage_after - e.damage_before) * product;
    if (e.broken && contacts_) released -= contacts_->handover(b, contact_state(), time_step_);
    (e.cycle == report_cycle ? released_pending_ : released_) += released;
    if (e.broken) log_break(b, e.mode, e.cycle, e.displacement);
  }
}

ContactState ExplicitIntegrator::contact_state() const {
  ContactState s;
  const Particles& p = model_.particles;
  for (int c = 0; c < 3; ++c) {
    if (fused_) {
      const FusedState& k = fused_->state;
      s.displacement[c] = k.displacement[k.parity][c].data();
      s.rotation[c] = k.rotation[k.parity][c].data();
      s.velocity[c] = k.velocity[c].data();
      s.angular_velocity[c] = k.angular_velocity[c].data();
    } else {
      s.displacement[c] = p.displacement.col(c).data();
      s.rotation[c] = p.rotation.col(c).data();
      s.velocity[c] = p.velocity.col(c).data();
      s.angular_velocity[c] = p.angular_velocity.col(c).data();
    }
  }
  return s;
}

void ExplicitIntegrator::store_bonds() {
  if (!fused_ || !breaking_) return;
  const GatherBonds& g = fused_->state.bonds;
  Bonds& bonds = model_.bonds;
  for (int b = 0; b < bonds.size(); ++b) {
    const std::array<std::int64_t, 2> cells = g.bond_cells(b);
    if (cells[0] < 0) continue;  // broken before the table was built
    const auto first = static_cast<std::size_t>(cells[0]);
    const auto second = static_cast<std::size_t>(cells[1]);
    const bool agree = g.holds(first) == g.holds(second) && g.holds(first) == !bonds.is_broken(b) &&
                       (!g.softening() || (g.slot_damage()[first] == g.slot_damage()[second] &&
                                           g.slot_kappa()[first] == g.slot_kappa()[second]));
    if (!agree) {
      const bool soft = g.softening();
      throw Error(fmt::format(
          "internal error: the two ends of bond {} disagree in the fused kernel (held {} and {}, "
          "damage {:.17g} and {:.17g}, kappa {:.17g} and {:.17g}, model state {})",
          b, g.holds(first), g.holds(second), soft ? g.slot_damage()[first] : 0.0,
          soft ? g.slot_damage()[second] : 0.0, soft ? g.slot_kappa()[first] : 1.0,
          soft ? g.slot_kappa()[second] : 1.0, bonds.state(b)));
    }
    if (!g.softening() || !g.holds(first)) continue;
    const double damage = g.slot_damage()[first];
    bonds.damage(b) = damage;
    kappa_(b) = g.slot_kappa()[first];
    bonds.normal_stiffness(b) = (1.0 - damage) * intact_[0](b);
    bonds.shear_stiffness(b) = (1.0 - damage) * intact_[1](b);
    bonds.bending_stiffness(b) = (1.0 - damage) * intact_[2](b);
    bonds.twisting_stiffness(b) = (1.0 - damage) * intact_[3](b);
  }
}

EnergyAccount ExplicitIntegrator::energy() const {
  EnergyAccount e;
  if (!breaking_) return e;
  e.initial = initial_energy_;
  e.strain_energy = last_report_.strain_energy;
  e.kinetic_energy = last_report_.kinetic_energy;
  const double half_step = 0.5 * time_step_;
  double work = 0, damping = 0;
  if (fused_) {
    const FusedState& k = fused_->state;
    for (int i = 0; i < k.particles; ++i) {
      work += k.work_sum[i];
      damping += k.damping_sum[i];
    }
  } else {
    work = work_sum_.sum();
    damping = damping_sum_.sum();
  }
  e.released = released_;
  e.boundary_work = half_step * work - pending_work_;
  e.damping = half_step * damping - pending_damping_;
  if (contacts_) {
    e.contact_energy = contacts_->stored_energy();
    e.friction = contacts_->friction_dissipation();
  }
  return e;
}

std::array<BondEnd, 2> ExplicitIntegrator::bond_ends(int bond) const {
  const Bonds& bonds = model_.bonds;
  require(bond >= 0 && bond < bonds.size(),
          fmt::format("no bond {}: the model has {} bonds", bond, bonds.size()));
  if (!fused_ || !breaking_) {
    const BondEnd end{!bonds.is_broken(bond), bonds.damage(bond), kappa_(bond)};
    return {end, end};
  }
  const GatherBonds& g = fused_->state.bonds;
  std::array<BondEnd, 2> ends;
  const std::array<std::int64_t, 2> cells = g.bond_cells(bond);
  for (int e = 0; e < 2; ++e) {
    if (cells[e] < 0) {
      ends[e] = {false, 1.0, kappa_(bond)};
      continue;
    }
    const auto cell = static_cast<std::size_t>(cells[e]);
    ends[e].holds = g.holds(cell);
    ends[e].damage = g.softening() ? g.slot_damage()[cell] : (ends[e].holds ? 0.0 : 1.0);
    ends[e].kappa = g.softening() ? g.slot_kappa()[cell] : 1.0;
  }
  return ends;
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
  store_bonds();
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

void ExplicitIntegrator::break_bond(int bond, BondState mode) {
  Bonds& bonds = model_.bonds;
  require(bond >= 0 && bond < bonds.size(),
          fmt::format("cannot break bond {}: the model has {} bonds", bond, bonds.size()));
  require(mode == BondState::kBrokenTension || mode == BondState::kBrokenShear,
          "a bond breaks in tension or in shear");
  require(!bonds.is_broken(bond), fmt::format("bond {} is broken already", bond));
  if (!breaking_) start_breaking();
  if (fused_) {
    GatherBonds& g = fused_->state.bonds;
    const int padded = g.padded_count();
    for (const std::int64_t cell : g.bond_cells(bond)) {
      if (cell < 0 || !g.holds(static_cast<std::size_t>(cell))) continue;
      g.clear_slot(static_cast<int>(cell % padded), static_cast<int>(cell / padded));
    }
    // From a hook: the device holds the run's arrays, and the host copy is current; copy it in.
    FusedState& k = fused_->state;
    if (k.device && running_) k.device->upload(device_arrays(k, kernel_mode()));
  }
  bonds.state(bond) = static_cast<int>(mode);
  bonds.damage(bond) = 1;
  bonds.normal_stiffness(bond) = 0;
  bonds.shear_stiffness(bond) = 0;
  bonds.bending_stiffness(bond) = 0;
  bonds.twisting_stiffness(bond) = 0;
  if (contacts_) {
    contacts_->add_broken_bond(bond);
    contact_countdown_ = 0;
  }
}

std::size_t ExplicitIntegrator::kernel_bytes() const {
  return fused_ ? fused_->state.bytes() : 0;
}

CycleReport ExplicitIntegrator::reference_cycle(bool last) {
  Particles& p = model_.particles;
  Bonds& bonds = model_.bonds;
  const BondPass pass = compute_bond_forces(p, bonds);
  const double dt = time_step_;
  const double alpha = settings_.local_damping;
  if (contacts_ && !contacts_->contacts().empty()) {
    ContactState s;
    ContactForces out;
    for (int c = 0; c < 3; ++c) {
      s.displacement[c] = p.displacement.col(c).data();
      s.rotation[c] = p.rotation.col(c).data();
      s.velocity[c] = p.velocity.col(c).data();
      s.angular_velocity[c] = p.angular_velocity.col(c).data();
      out.force[c] = contact_force_.col(c).data();
      out.torque[c] = contact_torque_.col(c).data();
    }
    contacts_->apply(s, dt, out);
    p.force += contact_force_;
    p.torque += contact_torque_;
  }
  // The failure law at this cycle's state; what it decides acts from the next cycle.
  std::vector<SlotEvent> events;
  if (breaking_) {
    for (int b = 0; b < bonds.size(); ++b) {
      if (bonds.is_broken(b)) continue;
      const BondStrength strength = bond_strength(bonds, b);
      if (!std::isfinite(strength.tensile) && !std::isfinite(strength.cohesion)) continue;
      double du[3], dtheta[3];
      const BondDeformation d = bond_deformation(p, bonds, b, du, dtheta);
      const BondStiffness intact{intact_[0](b), intact_[1](b), intact_[2](b), intact_[3](b)};
      const BondDamageUpdate u =
          update_bond_damage(d, intact, strength, bonds.damage(b), kappa_(b));
      if (!u.changed) continue;
      kappa_(b) = u.kappa;
      const int i = bonds.first(b);
      const double displacement[3] = {p.displacement(i, 0), p.displacement(i, 1),
                                      p.displacement(i, 2)};
      const double n[3] = {bonds.normal(b, 0), bonds.normal(b, 1), bonds.normal(b, 2)};
      events.push_back(
          damage_event(b, cycles_, u, bonds.damage(b), intact, du, dtheta, n, displacement));
      if (!u.broken) {
        bonds.damage(b) = u.damage;
        bonds.normal_stiffness(b) = (1.0 - u.damage) * intact_[0](b);
        bonds.shear_stiffness(b) = (1.0 - u.damage) * intact_[1](b);
        bonds.bending_stiffness(b) = (1.0 - u.damage) * intact_[2](b);
        bonds.twisting_stiffness(b) = (1.0 - u.damage) * intact_[3](b);
      }
    }
  }
  CycleReport report;
  report.strain_energy = pass.strain_energy;
  double kinetic2 = 0, unbalanced = 0, work_half = 0, damping_half = 0;
  const int n = p.size();
  // One component: the imposed velocity, or the damped central difference; with the account's
  // sums (EnergyAccount).
  auto advance = [&](double& u, double& v, double force, double inertia, bool fixed, double imposed,
                     int i) {
    const double v_old = v;
    if (fixed) {
      v = imposed;
      u += dt * v;
      if (breaking_) {
        work_sum_(i) -= force * (v_old + v);
        if (last) work_half -= force * v;
      }
      return;
    }
    const double damping = alpha * std::abs(force) * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0));
    v += dt * (force - damping) / inertia;
    u += dt * v;
    kinetic2 += inertia * v_old * v;
    if (breaking_) {
      damping_sum_(i) += damping * (v_old + v);
      if (last) damping_half += damping * v;
    }
  };
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < n; ++i) {
      advance(p.displacement(i, c), p.velocity(i, c), p.force(i, c), p.mass(i),
              fixed_velocity_(i, c), prescribed_velocity_(i, c), i);
      advance(p.rotation(i, c), p.angular_velocity(i, c), p.torque(i, c), p.moment_of_inertia(i),
              fixed_angular_velocity_(i, c), prescribed_angular_velocity_(i, c), i);
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!fixed_velocity_.row(i).any()) unbalanced += p.force.row(i).matrix().norm();
  }
  report.kinetic_energy = 0.5 * kinetic2;
  const double mean_bond_force = pass.sum_force_norm / std::max(1, model_.bonds.size());
  report.unbalanced_force_ratio =
      mean_bond_force > 0 ? unbalanced / std::max(1, free_particles_) / mean_bond_force : 0.0;
  if (last && breaking_) {
    pending_work_ = 0.5 * dt * work_half;
    pending_damping_ = 0.5 * dt * damping_half;
  }
  if (!events.empty()) resolve_events(events, last ? cycles_ : -1);
  time_ += dt;
  ++cycles_;
  return report;
}

namespace {

// The fields a run changes; every other field of a restored model must equal the integrator's.
constexpr std::string_view kRunFields[] = {
    "displacement",       "velocity",        "rotation",
    "angular_velocity",   "force",           "torque",
    "normal_stiffness",   "shear_stiffness", "bending_stiffness",
    "twisting_stiffness", "damage",          "state"};

}  // namespace

void ExplicitIntegrator::save(CheckpointWriter& out) const {
  out.section("explicit");
  out.boolean(fused_ != nullptr);
  out.f64(time_step_);
  out.f64(time_);
  out.i64(cycles_);
  out.boolean(breaking_);
  out.boolean(softening_);
  Model state = model_;
  std::vector<int> all(static_cast<std::size_t>(state.particles.size()));
  std::iota(all.begin(), all.end(), 0);
  gather(all, state.particles);
  Eigen::ArrayXd kappa = kappa_;
  if (fused_ && breaking_ && fused_->state.bonds.softening()) {
    // What store_bonds() would write back at this point of the run.
    const GatherBonds& g = fused_->state.bonds;
    Bonds& bonds = state.bonds;
    for (int b = 0; b < bonds.size(); ++b) {
      const std::int64_t cell = g.bond_cells(b)[0];
      if (cell < 0 || !g.holds(static_cast<std::size_t>(cell))) continue;
      const double damage = g.slot_damage()[cell];
      bonds.damage(b) = damage;
      kappa(b) = g.slot_kappa()[cell];
      bonds.normal_stiffness(b) = (1.0 - damage) * intact_[0](b);
      bonds.shear_stiffness(b) = (1.0 - damage) * intact_[1](b);
      bonds.bending_stiffness(b) = (1.0 - damage) * intact_[2](b);
      bonds.twisting_stiffness(b) = (1.0 - damage) * intact_[3](b);
    }
  }
  write_model(out, state);
  out.array(kappa);
  write_breaks(out, breaks_);
  out.boolean(initial_set_);
  out.f64(initial_energy_);
  out.f64(last_report_.strain_energy);
  out.f64(last_report_.kinetic_energy);
  out.f64(last_report_.unbalanced_force_ratio);
  out.f64(pending_work_);
  out.f64(pending_damping_);
  out.f64(released_);
  out.f64(released_pending_);
  if (breaking_) {
    // The account's per-particle sums and the last contact forces, in model order.
    const int n = state.particles.size();
    Eigen::ArrayXd work(n), damping(n);
    Vector3Array force(n, 3), torque(n, 3);
    for (int i = 0; i < n; ++i) {
      if (fused_) {
        const FusedState& k = fused_->state;
        const int j = k.position[i];
        work(i) = k.work_sum[j];
        damping(i) = k.damping_sum[j];
        for (int c = 0; c < 3; ++c) {
          force(i, c) = k.contact_force[c][j];
          torque(i, c) = k.contact_torque[c][j];
        }
      } else {
        work(i) = work_sum_(i);
        damping(i) = damping_sum_(i);
        force.row(i) = contact_force_.row(i);
        torque.row(i) = contact_torque_.row(i);
      }
    }
    out.array(work);
    out.array(damping);
    out.array(force);
    out.array(torque);
  }
  out.boolean(contacts_ != nullptr);
  if (contacts_) contacts_->save(out);
  out.i64(contact_countdown_);
}

void ExplicitIntegrator::restore_account(CheckpointReader& in, int n) {
  Eigen::ArrayXd work, damping;
  Vector3Array force, torque;
  in.array(work);
  in.array(damping);
  in.array(force);
  in.array(torque);
  if (work.size() != n || damping.size() != n || force.rows() != n || torque.rows() != n)
    in.corrupt("the energy account has the wrong size");
  if (fused_) {
    FusedState& k = fused_->state;
    for (int i = 0; i < n; ++i) {
      const int j = k.position[i];
      k.work_sum[j] = work(i);
      k.damping_sum[j] = damping(i);
      for (int c = 0; c < 3; ++c) {
        k.contact_force[c][j] = force(i, c);
        k.contact_torque[c][j] = torque(i, c);
      }
    }
  } else {
    work_sum_ = work;
    damping_sum_ = damping;
    contact_force_ = force;
    contact_torque_ = torque;
  }
}

// The fused kernel's slots: the bonds broken since the table was built, the softening histories.
void ExplicitIntegrator::restore_slots(const Bonds& bonds, const Eigen::ArrayXd& kappa) {
  GatherBonds& g = fused_->state.bonds;
  const int padded = g.padded_count();
  for (int b = 0; b < bonds.size(); ++b) {
    for (const std::int64_t cell : g.bond_cells(b)) {
      if (cell < 0) continue;
      const auto c = static_cast<std::size_t>(cell);
      if (bonds.is_broken(b)) {
        if (g.holds(c))
          g.clear_slot(static_cast<int>(cell % padded), static_cast<int>(cell / padded));
      } else if (g.softening()) {
        g.slot_damage()[c] = bonds.damage(b);
        g.slot_kappa()[c] = kappa(b);
      }
    }
  }
}

void ExplicitIntegrator::restore(CheckpointReader& in) {
  require(!running_, "restore() was called during a run");
  const std::string& file = in.file();
  in.section("explicit");
  const bool fused = in.boolean();
  if (fused != (fused_ != nullptr))
    throw Error(fmt::format("checkpoint {} is for another run: kernel is {} there, {} here", file,
                            fused ? "fused" : "reference", fused_ ? "fused" : "reference"));
  const double dt = in.f64();
  if (std::memcmp(&dt, &time_step_, sizeof dt) != 0)
    throw Error(
        fmt::format("checkpoint {} is for another run: time step is {:.17g} s there, "
                    "{:.17g} s here",
                    file, dt, time_step_));
  const double time = in.f64();
  const long cycles = in.i64();
  if (cycles < 0) in.corrupt(fmt::format("{} cycles", cycles));
  const bool breaking = in.boolean();
  const bool softening = in.boolean();
  Model state;
  read_model(in, state);
  check_same_model(model_, state, kRunFields, file);
  Eigen::ArrayXd kappa;
  in.array(kappa);
  if (kappa.size() != state.bonds.size()) in.corrupt("the softening history has the wrong size");
  std::vector<BondBreak> breaks = read_breaks(in);
  for (const BondBreak& b : breaks)
    if (b.bond < 0 || b.bond >= state.bonds.size())
      in.corrupt(fmt::format("the break log names bond {}", b.bond));
  if (breaking && !breaking_) start_breaking();  // the saved run broke a bond by hand
  if (breaking != breaking_ || softening != softening_)
    throw Error(
        fmt::format("checkpoint {} is for another run: its integrator {} and {}, this one "
                    "{} and {}",
                    file, breaking ? "breaks bonds" : "does not break bonds",
                    softening ? "softens" : "does not soften",
                    breaking_ ? "breaks bonds" : "does not break bonds",
                    softening_ ? "softens" : "does not soften"));
  for (int b = 0; b < state.bonds.size(); ++b)
    if (model_.bonds.is_broken(b) && !state.bonds.is_broken(b))
      throw Error(
          fmt::format("checkpoint {} is for another model: bond {} is intact there and "
                      "broken here",
                      file, b));
  initial_set_ = in.boolean();
  initial_energy_ = in.f64();
  last_report_.strain_energy = in.f64();
  last_report_.kinetic_energy = in.f64();
  last_report_.unbalanced_force_ratio = in.f64();
  pending_work_ = in.f64();
  pending_damping_ = in.f64();
  released_ = in.f64();
  released_pending_ = in.f64();
  if (breaking_) restore_account(in, state.particles.size());
  const bool contacts = in.boolean();
  if (contacts != (contacts_ != nullptr))
    throw Error(fmt::format("checkpoint {} is for another run: contacts are {} there, {} here",
                            file, contacts ? "on" : "off", contacts_ ? "on" : "off"));
  if (contacts_) {
    contacts_->restore(in);
    if (fused_) {
      FusedState& k = fused_->state;
      std::fill(k.contact_block.begin(), k.contact_block.end(), 0);
      for (int i : contacts_->touched()) {
        if (i / lanes::kCount >= k.blocks) in.corrupt("a touched contact is out of range");
        k.contact_block[i / lanes::kCount] = 1;
      }
    }
  }
  contact_countdown_ = in.i64();

  if (fused_ && breaking_) restore_slots(state.bonds, kappa);
  model_.particles = std::move(state.particles);
  model_.bonds = std::move(state.bonds);
  kappa_ = std::move(kappa);
  breaks_ = std::move(breaks);
  time_ = time;
  cycles_ = cycles;
}

}  // namespace plydem
