#pragma once
/// \file
/// One cycle of the fused explicit kernel for one particle: what a CUDA thread does
/// (solvers/cuda_backend.cu), written once over plain arrays so that the host can run the very same
/// code (ExplicitBackend::kDeviceEmulation, one particle after another) and tests can hold it to
/// the host's fused kernel bit for bit on a machine without a GPU.
///
/// Particle k sums its own bonds (gather form: no two threads write the same memory, no atomics on
/// the forces), with the half-bond math and the failure law of contacts/half_bond.hpp, the same
/// templates the host's SIMD kernel instantiates with eight lanes; then it advances its degrees of
/// freedom exactly as one lane of the host's step_range does (damped central difference or imposed
/// velocity, the energy account's sums). Every expression is evaluated in the host kernel's order;
/// with no contraction into fused multiply-adds on either side (the host compiles ISO C++, where
/// GCC contracts none; nvcc gets -fmad=false) both compute the same numbers.
///
/// Differences from the host kernel, none of which changes a result:
///  - a slot of type 0 (no bond, or a broken one) is skipped, where the host's eight lanes compute
///    it with zero stiffness: it adds +0 to sums that start at +0 and so are never -0;
///  - the breaking kernels ask the exact law wherever the first screen holds, without the host's
///    second screen, which is a conservative filter of the same decision (HalfBondFailure);
///  - a broken slot is cleared in the type and neighbour tables only: there are no block tables;
///  - report sums are written per particle (ParticleStepView::partial) for the caller to reduce.
///
/// Breaking: a slot whose damage changes sets `*stop` to the cycle's number + 1 (a plain store of
/// the same value by every writer), and the caller runs no further cycle of the batch, as the host
/// kernel stops after such a cycle; the bond's first end appends its SlotEvent to `events`.

#include <cmath>
#include <cstdint>
#include <limits>

#include "contacts/half_bond.hpp"
#include "core/host_device.hpp"

namespace plydem {

/// What a prescribed motion does to a particle of its group: per component, a mask (-1 fixed,
/// 0 free) and the imposed value.
struct MotionClass {
  std::int64_t fix_velocity[3] = {0, 0, 0};
  std::int64_t fix_angular_velocity[3] = {0, 0, 0};
  double velocity[3] = {0, 0, 0};
  double angular_velocity[3] = {0, 0, 0};
  std::int64_t free = -1;  // no translation fixed: counts in the unbalanced force
};

/// The fused step's variants: elastic, or breaking with strengths per type or per slot, brittle or
/// softening.
enum KernelMode : int {
  kElasticMode = 0,
  kBrittleTypes = 1,
  kBrittleSlots = 2,
  kSofteningTypes = 3,
  kSofteningSlots = 4
};

/// The per-particle report sums of one cycle, in the order the host kernel's block partials keep
/// them: strain energy, bond force magnitude, 2 x kinetic energy, unbalanced force, - F . v(n+1/2)
/// (prescribed), damping . v(n+1/2) (free).
inline constexpr int kParticlePartials = 6;

/// The arrays one cycle reads and writes, in kernel order, padded to whole blocks of eight (the
/// padding particles have no bonds, unit inverse masses and never move). Per-slot arrays are
/// [slot * padded + k] (GatherBonds::cell).
struct ParticleStepView {
  int padded = 0;
  int width = 0;
  const double* displacement_in[3] = {};
  const double* rotation_in[3] = {};
  double* displacement_out[3] = {};
  double* rotation_out[3] = {};
  double* velocity[3] = {};
  double* angular_velocity[3] = {};
  const double* inverse_mass = nullptr;
  const double* inverse_inertia = nullptr;
  const std::uint8_t* motion = nullptr;  ///< class per particle; 0 = free
  const MotionClass* classes = nullptr;
  std::int32_t* neighbour = nullptr;  ///< per slot; a broken slot points at its own particle
  std::int32_t* type = nullptr;       ///< per slot; 0 = empty
  const HalfBondType* types = nullptr;
  double dt = 0;
  double alpha = 0;  ///< local damping
  // Breaking.
  const HalfBondFailure* failure = nullptr;  ///< per type
  const std::int32_t* slot_bond = nullptr;   ///< per slot: 2 b (first end) or 2 b + 1
  const double* slot_alpha = nullptr;        ///< per slot: strengths per slot only
  const double* slot_beta = nullptr;
  const double* slot_tensile = nullptr;
  const double* slot_cohesion = nullptr;
  double* slot_damage = nullptr;  ///< per slot: softening only
  double* slot_kappa = nullptr;
  double* work_sum = nullptr;     ///< per particle: - F (v_old + v_new) over prescribed components
  double* damping_sum = nullptr;  ///< per particle: damping (v_old + v_new) over free ones
  long cycle = 0;                 ///< the integrator's cycle number of this pass
  int* stop = nullptr;            ///< 0, or the batch's first cycle with a damage step + 1
  int batch_cycle = 0;            ///< this cycle's index in its batch
  SlotEvent* events = nullptr;    ///< damage steps logged by first ends
  unsigned* event_count = nullptr;
  unsigned event_capacity = 0;
  // Report cycles.
  double* force_out[3] = {};   ///< kernel order
  double* torque_out[3] = {};  ///< kernel order
  double* partial = nullptr;   ///< [q * padded + k], q < kParticlePartials
};

/// Appends a damage step to the event log: an atomic counter on the device (the only atomic of
/// the kernel; the log's order is fixed afterwards, by cycle and bond, as the host's is), a plain
/// one on the host. An overflow is counted and reported by the caller.
PLYDEM_HOST_DEVICE inline void log_event(const ParticleStepView& v, const SlotEvent& e) {
#if defined(__CUDA_ARCH__)
  const unsigned at = atomicAdd(v.event_count, 1u);
#else
  const unsigned at = (*v.event_count)++;
#endif
  if (at < v.event_capacity) v.events[at] = e;
}

/// The exact failure law for slot `slot` of particle `k` (the host's assess_slot).
template <bool kSoften, bool kSlotStrength>
PLYDEM_HOST_DEVICE inline void assess_particle_slot(const ParticleStepView& v, int k, int slot,
                                                    const double (&du)[3], const double (&dt)[3],
                                                    const double (&n)[3],
                                                    const double (&u_own)[3]) {
  const std::size_t cell = static_cast<std::size_t>(slot) * v.padded + k;
  const std::int32_t type = v.type[cell];
  if (type == 0) return;
  const HalfBondFailure& f = v.failure[type];
  BondStrength strength = f.strength;
  if constexpr (kSlotStrength) {
    strength.tensile = v.slot_tensile[cell];
    strength.cohesion = v.slot_cohesion[cell];
  }
  const double damage = kSoften ? v.slot_damage[cell] : 0.0;
  const double kappa = kSoften ? v.slot_kappa[cell] : 1.0;
  const BondStiffness intact{f.normal_stiffness, f.shear_stiffness, f.bending_stiffness,
                             f.twisting_stiffness};
  const BondDamageUpdate u =
      update_bond_damage(deformation_of(du, dt, n), intact, strength, damage, kappa);
  if (!u.changed) return;
  if constexpr (kSoften) {
    v.slot_damage[cell] = u.damage;
    v.slot_kappa[cell] = u.kappa;
  }
  if (u.broken) {  // GatherBonds::clear_slot
    v.type[cell] = 0;
    v.neighbour[cell] = k;
    if constexpr (kSoften) v.slot_damage[cell] = 1.0;
  }
  *v.stop = v.batch_cycle + 1;
  const std::int32_t bond = v.slot_bond[cell];
  if ((bond & 1) == 0)
    log_event(v, damage_event(bond >> 1, v.cycle, u, damage, intact, du, dt, n, u_own));
}

/// One degree of freedom (the host's advance_lanes, one lane): the damped central difference, or
/// the imposed velocity. The damping force alpha |F| sign(v) is zero where v is zero.
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void advance_dof(double force, double dt_over_inertia,
                                                        bool fixed, double imposed, double dt,
                                                        double alpha, double& u, double& v,
                                                        double& v_old, double& damping) {
  const double push = alpha * std::fabs(force);
  damping = v == 0.0 ? 0.0 : std::copysign(push, v);
  v_old = v;
  const double free = v + dt_over_inertia * (force - damping);
  v = fixed ? imposed : free;
  u += dt * v;
}

/// One cycle of particle k (k < padded). kReport: the cycle also writes the forces and the report
/// sums (the last cycle of a chunk).
template <bool kReport, int kMode>
PLYDEM_HOST_DEVICE inline void particle_step(const ParticleStepView& v, int k) {
  constexpr bool kBreaking = kMode != kElasticMode;
  constexpr bool kSoften = kMode == kSofteningTypes || kMode == kSofteningSlots;
  constexpr bool kSlotStrength = kMode == kBrittleSlots || kMode == kSofteningSlots;
  double u_i[3], t_i[3];
  for (int c = 0; c < 3; ++c) {
    u_i[c] = v.displacement_in[c][k];
    t_i[c] = v.rotation_in[c][k];
  }
  double force[3] = {0, 0, 0}, torque[3] = {0, 0, 0};
  double energy = 0, bond_force = 0;
  for (int slot = 0; slot < v.width; ++slot) {
    const std::size_t cell = static_cast<std::size_t>(slot) * v.padded + k;
    const std::int32_t type = v.type[cell];
    if (type == 0) continue;
    const std::int32_t j = v.neighbour[cell];
    const HalfBondType& h = v.types[type];
    double u_j[3], t_j[3], n[3];
    for (int c = 0; c < 3; ++c) {
      u_j[c] = v.displacement_in[c][j];
      t_j[c] = v.rotation_in[c][j];
      n[c] = h.normal[c];
    }
    double k_s = h.shear_stiffness, s_k_s = h.lever_shear, k_n_excess = h.normal_excess,
           k_b = h.bending_stiffness, k_t_excess = h.twisting_excess;
    double dt[3], a[3], force2 = 0;
    HalfBondMotion<double> m;
    if constexpr (kBreaking) {
      const HalfBondFailure& f = v.failure[type];
      if constexpr (kSoften) {
        const double remaining = 1.0 - v.slot_damage[cell];
        k_s = remaining * k_s;
        s_k_s = remaining * s_k_s;
        k_n_excess = remaining * k_n_excess;
        k_b = remaining * k_b;
        k_t_excess = remaining * k_t_excess;
      }
      symmetric_lever_term(f.lever_mean, f.lever_half_difference, t_i, t_j, dt, a);
      half_bond_response<kReport>(n, u_i, u_j, a, dt, k_s, s_k_s, k_n_excess, k_b, k_t_excess,
                                  force, torque, energy, force2, m);
      if constexpr (kReport) bond_force += 0.5 * std::sqrt(force2);
      const double alpha = kSlotStrength ? v.slot_alpha[cell] : f.screen_displacement;
      const double beta = kSlotStrength ? v.slot_beta[cell] : f.screen_rotation;
      double measure;
      screen_measure(alpha, beta, m, measure);
      if (measure >= 1.0 - kScreenBound)
        assess_particle_slot<kSoften, kSlotStrength>(v, k, slot, m.du, dt, n, u_i);
    } else {
      lever_term(h.lever_own, h.lever_other, t_i, t_j, dt, a);
      half_bond_response<kReport>(n, u_i, u_j, a, dt, k_s, s_k_s, k_n_excess, k_b, k_t_excess,
                                  force, torque, energy, force2, m);
      if constexpr (kReport) bond_force += 0.5 * std::sqrt(force2);
    }
  }

  const MotionClass& motion = v.classes[v.motion[k]];
  const bool prescribed = v.motion[k] != 0;
  const double dt_over_mass = v.dt * v.inverse_mass[k];
  const double dt_over_inertia = v.dt * v.inverse_inertia[k];
  double kinetic = 0, damping_sum = 0, work_sum = 0, damping_half = 0, work_half = 0;
  // The account's shares of one component (the host's account_lanes).
  auto account = [&](double f, double damping, double v_old, double v_new, bool fixed) {
    const double both = v_old + v_new;
    if (!fixed) damping_sum += damping * both;
    if (prescribed && fixed) work_sum -= f * both;
    if constexpr (kReport) {
      if (!fixed) damping_half += damping * v_new;
      if (prescribed && fixed) work_half -= f * v_new;
    }
  };
  for (int c = 0; c < 3; ++c) {
    const bool fix_v = motion.fix_velocity[c] != 0, fix_w = motion.fix_angular_velocity[c] != 0;
    double u = v.displacement_in[c][k], vel = v.velocity[c][k], v_old, damping;
    advance_dof(force[c], dt_over_mass, fix_v, motion.velocity[c], v.dt, v.alpha, u, vel, v_old,
                damping);
    v.displacement_out[c][k] = u;
    v.velocity[c][k] = vel;
    if constexpr (kReport) {
      if (!fix_v) kinetic += v_old / v.inverse_mass[k] * vel;
    }
    if constexpr (kBreaking) account(force[c], damping, v_old, vel, fix_v);

    u = v.rotation_in[c][k];
    vel = v.angular_velocity[c][k];
    advance_dof(torque[c], dt_over_inertia, fix_w, motion.angular_velocity[c], v.dt, v.alpha, u,
                vel, v_old, damping);
    v.rotation_out[c][k] = u;
    v.angular_velocity[c][k] = vel;
    if constexpr (kReport) {
      if (!fix_w) kinetic += v_old / v.inverse_inertia[k] * vel;
    }
    if constexpr (kBreaking) account(torque[c], damping, v_old, vel, fix_w);
  }
  if constexpr (kBreaking) {
    v.damping_sum[k] += damping_sum;
    if (prescribed) v.work_sum[k] += work_sum;
  }
  if constexpr (kReport) {
    const double f2 = force[0] * force[0] + force[1] * force[1] + force[2] * force[2];
    for (int c = 0; c < 3; ++c) {
      v.force_out[c][k] = force[c];
      v.torque_out[c][k] = torque[c];
    }
    const std::size_t p = static_cast<std::size_t>(v.padded);
    v.partial[0 * p + k] = energy;
    v.partial[1 * p + k] = bond_force;
    v.partial[2 * p + k] = kinetic;
    v.partial[3 * p + k] = motion.free != 0 ? std::sqrt(f2) : 0.0;
    v.partial[4 * p + k] = work_half;
    v.partial[5 * p + k] = damping_half;
  }
}

/// The host kernel's block partial of report sum q: the eight particles' sums in lane order.
PLYDEM_HOST_DEVICE inline double block_partial(const double* partial, int padded, int q,
                                               int block) {
  const double* p = partial + static_cast<std::size_t>(q) * padded + 8 * block;
  double s = 0;
  for (int l = 0; l < 8; ++l) s += p[l];
  return s;
}

}  // namespace plydem
