#pragma once
/// \file
/// One cycle of the explicit kernel for one particle, or for one block of eight particles side by
/// side in SIMD lanes, written once (step_particle) and instantiated by every backend
/// (solvers/explicit_backend.hpp): the host's SIMD kernel with T = lanes::Doubles (solvers/
/// gather_backend.cpp, BlockLayout), the CUDA kernel (solvers/cuda_backend.cu) and its host
/// emulation (solvers/device_backend.cpp) with T = double, one particle per thread
/// (particle_step below, ParticleLayout); the reference backend runs its update (advance_particle)
/// after its own scatter pass over the bonds.
///
/// A particle sums its own bonds (gather form: no two threads write the same memory, no atomics on
/// the forces) with the half-bond math and the failure law of contacts/half_bond.hpp
/// (gather_half_bonds), then advances its degrees of freedom (damped central difference or
/// imposed velocity) and adds its shares of the energy account. Every operation is exactly rounded
/// and every multiply-add an explicit fused one (core/lane_ops.hpp), so that all backends compute
/// the same numbers to the bit whatever the compiler contracts: tests hold the host emulation to
/// the host's SIMD kernel on every machine.
///
/// What a Layout gives the step (T = Layout::Lane): load_state(u, theta) (the buffer the cycle
/// reads), slots() (the bond table, contacts/half_bond.hpp), add_contacts(force, torque)
/// (breaking runs' contact forces), load_motion(LaneMotion&) (returns whether any of its particles
/// has a prescribed motion), load_dynamics(inverse mass, inverse inertia, v, omega),
/// store_state(u, theta, v, omega) (the other buffer), add_account(StepSums, prescribed) and
/// report(ParticleReport) (report cycles), dt() and alpha().
///
/// Breaking (device): a slot whose damage changes sets `*stop` to the cycle's number + 1 (a plain
/// store of the same value by every writer), and the caller runs no further cycle of the batch,
/// as the host kernel stops after such a cycle; the bond's first end appends its SlotEvent to
/// `events`.
///
/// No Eigen and no vector extension here: nvcc compiles this header.

#include <cmath>
#include <cstdint>

#include "contacts/half_bond.hpp"
#include "core/host_device.hpp"
#include "core/lane_ops.hpp"
#include "solvers/kernel_arrays.hpp"

namespace plydem {

/// The prescribed motions of the particles in the lanes: which components are fixed, the imposed
/// velocities, and which particles count as free (no translation fixed).
template <class T>
struct LaneMotion {
  using Mask = typename LaneOps<T>::Mask;
  Mask fix_velocity[3] = {}, fix_angular_velocity[3] = {};
  T velocity[3] = {}, angular_velocity[3] = {};
  Mask counts_free = {};
};

/// What the update adds to the energy account and the report (the account's sums: breaking runs).
template <class T>
struct StepSums {
  T kinetic{};       ///< 2 x leapfrog kinetic energy, free components (report)
  T damping_sum{};   ///< damping (v_old + v_new), free components
  T work_sum{};      ///< - F (v_old + v_new), prescribed components
  T damping_half{};  ///< damping v_new (report)
  T work_half{};     ///< - F v_new (report)
};

/// What a report cycle writes: the forces and the report sums (kParticlePartials' order).
template <class T>
struct ParticleReport {
  const T (&force)[3];
  const T (&torque)[3];
  T partial[kParticlePartials];
};

/// One degree of freedom: the damped central difference, or the imposed velocity. The local
/// damping force alpha |F| sign(v) is zero where v is zero.
template <class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void advance_dof(const T& force, const T& dt_over_inertia,
                                                        const typename LaneOps<T>::Mask& fixed,
                                                        const T& imposed, double dt, double alpha,
                                                        T& u, T& v, T& v_old, T& damping) {
  using Ops = LaneOps<T>;
  damping = Ops::signed_like(alpha * Ops::abs(force), v);
  v_old = v;
  const T free = Ops::fmadd(dt_over_inertia, force - damping, v);
  v = Ops::select(fixed, imposed, free);
  u = Ops::fmadd(dt, v, u);
}

/// One component's share of the energy account: damping (v_old + v_new) where it is free, and
/// - F (v_old + v_new) where it is prescribed, and the second halves (v_new alone) on a report
/// cycle. Products are masked before they are summed. (Branch-free: GCC 12's AVX-512 clone of the
/// host kernel lost the prescribed sums of plain cycles when they were summed under a test of
/// whether any particle of the block is prescribed.)
template <bool kReport, class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void account_dof(const T& f, const T& damping,
                                                        const T& v_old, const T& v,
                                                        const typename LaneOps<T>::Mask& fixed,
                                                        StepSums<T>& s) {
  using Ops = LaneOps<T>;
  const T both = v_old + v;
  s.damping_sum += Ops::keep_unless(damping * both, fixed);
  s.work_sum -= Ops::keep(f * both, fixed);
  if constexpr (kReport) {
    s.damping_half += Ops::keep_unless(damping * v, fixed);
    s.work_half -= Ops::keep(f * v, fixed);
  }
}

/// The update of the particles in the lanes from their forces and moments: every degree of
/// freedom (advance_dof), with the kinetic energy (report) and the account's shares (kAccount).
template <bool kReport, bool kAccount, class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void advance_particle(
    const T (&force)[3], const T (&torque)[3], const LaneMotion<T>& motion, const T& inverse_mass,
    const T& inverse_inertia, double dt, double alpha, T (&u)[3], T (&theta)[3], T (&v)[3],
    T (&omega)[3], StepSums<T>& s) {
  using Ops = LaneOps<T>;
  const T dt_over_mass = dt * inverse_mass;
  const T dt_over_inertia = dt * inverse_inertia;
  for (int c = 0; c < 3; ++c) {
    T v_old, damping;
    advance_dof(force[c], dt_over_mass, motion.fix_velocity[c], motion.velocity[c], dt, alpha, u[c],
                v[c], v_old, damping);
    if constexpr (kReport)
      s.kinetic += Ops::keep_unless(v_old / inverse_mass * v[c], motion.fix_velocity[c]);
    if constexpr (kAccount)
      account_dof<kReport>(force[c], damping, v_old, v[c], motion.fix_velocity[c], s);

    advance_dof(torque[c], dt_over_inertia, motion.fix_angular_velocity[c],
                motion.angular_velocity[c], dt, alpha, theta[c], omega[c], v_old, damping);
    if constexpr (kReport)
      s.kinetic +=
          Ops::keep_unless(v_old / inverse_inertia * omega[c], motion.fix_angular_velocity[c]);
    if constexpr (kAccount)
      account_dof<kReport>(torque[c], damping, v_old, omega[c], motion.fix_angular_velocity[c], s);
  }
}

/// One cycle of the particles of `p` (see the file comment). kReport: the cycle also writes the
/// forces and the report sums (the last cycle of a chunk).
template <bool kReport, int kMode, class Layout>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void step_particle(Layout& p) {
  using T = typename Layout::Lane;
  using Ops = LaneOps<T>;
  constexpr bool kBreaking = breaks_bonds(kMode);
  T u[3], theta[3];
  p.load_state(u, theta);
  T force[3] = {}, torque[3] = {};
  T energy{}, bond_force{};
  {
    auto slots = p.slots();
    gather_half_bonds<kReport, kMode>(slots, u, theta, force, torque, energy, bond_force);
  }
  if constexpr (kBreaking) p.add_contacts(force, torque);
  LaneMotion<T> motion;
  const bool prescribed = p.load_motion(motion);
  T inverse_mass, inverse_inertia, v[3], omega[3];
  p.load_dynamics(inverse_mass, inverse_inertia, v, omega);
  StepSums<T> sums;
  if (prescribed) {
    advance_particle<kReport, kBreaking>(force, torque, motion, inverse_mass, inverse_inertia,
                                         p.dt(), p.alpha(), u, theta, v, omega, sums);
  } else {
    // No particle of `p` prescribed: the same update with its masks known to be clear, which the
    // compiler folds away (the same numbers: a clear mask selects and keeps exactly).
    LaneMotion<T> free;
    free.counts_free = motion.counts_free;
    advance_particle<kReport, kBreaking>(force, torque, free, inverse_mass, inverse_inertia, p.dt(),
                                         p.alpha(), u, theta, v, omega, sums);
  }
  p.store_state(u, theta, v, omega);
  if constexpr (kBreaking) p.add_account(sums, prescribed);
  if constexpr (kReport) {
    const T f2 =
        Ops::fmadd(force[2], force[2], Ops::fmadd(force[1], force[1], force[0] * force[0]));
    ParticleReport<T> r{force, torque, {}};
    r.partial[0] = energy;
    r.partial[1] = bond_force;
    r.partial[2] = sums.kinetic;
    r.partial[3] = Ops::keep(Ops::sqrt(f2), motion.counts_free);
    r.partial[4] = sums.work_half;
    r.partial[5] = sums.damping_half;
    p.report(r);
  }
}

/// What one cycle of the device's kernel reads and writes: the arrays (KernelView, in kernel order,
/// padded to whole blocks of eight: the padding particles have no bonds, unit inverse masses and
/// never move) and the cycle's numbers.
struct ParticleStepView {
  KernelView a;
  int padded = 0;
  int width = 0;
  int parity = 0;  ///< the state buffer the cycle reads; it writes the other
  double dt = 0;
  double alpha = 0;  ///< local damping
  // Breaking.
  long cycle = 0;               ///< the integrator's cycle number of this pass
  int* stop = nullptr;          ///< 0, or the batch's first cycle with a damage step + 1
  int batch_cycle = 0;          ///< this cycle's index in its batch
  SlotEvent* events = nullptr;  ///< damage steps logged by first ends
  unsigned* event_count = nullptr;
  unsigned event_capacity = 0;
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
  const KernelView& a = v.a;
  const std::size_t cell = static_cast<std::size_t>(slot) * v.padded + k;
  const std::int32_t type = a.type[cell];
  if (type == 0) return;
  const HalfBondFailure& f = a.failure[type];
  BondStrength strength = f.strength;
  if constexpr (kSlotStrength) {
    strength.tensile = a.slot_tensile[cell];
    strength.cohesion = a.slot_cohesion[cell];
  }
  const double damage = kSoften ? a.slot_damage[cell] : 0.0;
  const double kappa = kSoften ? a.slot_kappa[cell] : 1.0;
  const BondStiffness intact{f.normal_stiffness, f.shear_stiffness, f.bending_stiffness,
                             f.twisting_stiffness};
  const BondDamageUpdate u =
      update_bond_damage(deformation_of(du, dt, n), intact, strength, damage, kappa);
  if (!u.changed) return;
  if constexpr (kSoften) {
    a.slot_damage[cell] = u.damage;
    a.slot_kappa[cell] = u.kappa;
  }
  if (u.broken) {  // GatherBonds::clear_slot
    a.type[cell] = 0;
    a.neighbour[cell] = k;
    if constexpr (kSoften) a.slot_damage[cell] = 1.0;
  }
  *v.stop = v.batch_cycle + 1;
  const std::int32_t bond = a.slot_bond[cell];
  if ((bond & 1) == 0)
    log_event(v, damage_event(bond >> 1, v.cycle, u, damage, intact, du, dt, n, u_own));
}

/// The device's bond table seen from particle k: the `Slots` of gather_half_bonds. A slot of type
/// 0 (no bond, or a broken one) is skipped, where the host's eight lanes compute it with zero
/// stiffness: that adds +0 to sums that start at +0 and so are never -0. Breaking: the exact law
/// wherever the first screen holds, without the host's second screen, which is a conservative
/// filter of the same decision (HalfBondFailure).
class ParticleSlots {
 public:
  using Lane = double;
  PLYDEM_HOST_DEVICE ParticleSlots(const ParticleStepView& v, int k) : v_(v), k_(k) {}

  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE int width() const { return v_.width; }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE bool empty(int slot) const {
    return v_.a.type[cell(slot)] == 0;
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void other_state(int slot, double (&u_j)[3],
                                                          double (&t_j)[3]) const {
    const std::int32_t j = v_.a.neighbour[cell(slot)];
    for (int c = 0; c < 3; ++c) {
      u_j[c] = v_.a.displacement[v_.parity][c][j];
      t_j[c] = v_.a.rotation[v_.parity][c][j];
    }
  }
  template <int kMode>
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void load(int slot, HalfBondLoad<double>& h) const {
    const std::size_t c = cell(slot);
    const std::int32_t type = v_.a.type[c];
    const HalfBondFailure* f = breaks_bonds(kMode) ? &v_.a.failure[type] : nullptr;
    load_half_bond<kMode>(v_.a.types[type], f, h);
    if constexpr (has_slot_strengths(kMode)) {
      h.screen_displacement = v_.a.slot_alpha[c];
      h.screen_rotation = v_.a.slot_beta[c];
    }
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void damage(int slot, double& d) const {
    d = v_.a.slot_damage[cell(slot)];
  }
  template <int kMode>
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void assess(int slot, double measure, const double (&n)[3],
                                                     const HalfBondMotion<double>& m,
                                                     const double (&dt)[3],
                                                     const double (&u_i)[3]) const {
    if (measure >= 1.0 - kScreenBound)
      assess_particle_slot<softens_bonds(kMode), has_slot_strengths(kMode)>(v_, k_, slot, m.du, dt,
                                                                            n, u_i);
  }

 private:
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE std::size_t cell(int slot) const {
    return static_cast<std::size_t>(slot) * v_.padded + k_;
  }
  const ParticleStepView& v_;
  int k_;
};

/// Particle k of the device's arrays: the Layout of step_particle for one particle. The device has
/// no contacts between unbonded particles (a breaking run there needs them off).
class ParticleLayout {
 public:
  using Lane = double;
  PLYDEM_HOST_DEVICE ParticleLayout(const ParticleStepView& v, int k) : v_(v), k_(k) {}

  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE double dt() const { return v_.dt; }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE double alpha() const { return v_.alpha; }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void load_state(double (&u)[3], double (&t)[3]) const {
    for (int c = 0; c < 3; ++c) {
      u[c] = v_.a.displacement[v_.parity][c][k_];
      t[c] = v_.a.rotation[v_.parity][c][k_];
    }
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE ParticleSlots slots() const {
    return ParticleSlots(v_, k_);
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void add_contacts(double (&)[3], double (&)[3]) const {}
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE bool load_motion(LaneMotion<double>& m) const {
    const MotionClass& motion = v_.a.classes[v_.a.motion[k_]];
    for (int c = 0; c < 3; ++c) {
      m.fix_velocity[c] = motion.fix_velocity[c] != 0;
      m.fix_angular_velocity[c] = motion.fix_angular_velocity[c] != 0;
      m.velocity[c] = motion.velocity[c];
      m.angular_velocity[c] = motion.angular_velocity[c];
    }
    m.counts_free = motion.free != 0;
    return v_.a.motion[k_] != 0;
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void load_dynamics(double& inverse_mass,
                                                            double& inverse_inertia, double (&v)[3],
                                                            double (&omega)[3]) const {
    inverse_mass = v_.a.inverse_mass[k_];
    inverse_inertia = v_.a.inverse_inertia[k_];
    for (int c = 0; c < 3; ++c) {
      v[c] = v_.a.velocity[c][k_];
      omega[c] = v_.a.angular_velocity[c][k_];
    }
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void store_state(const double (&u)[3],
                                                          const double (&t)[3],
                                                          const double (&v)[3],
                                                          const double (&omega)[3]) const {
    const int out = 1 - v_.parity;
    for (int c = 0; c < 3; ++c) {
      v_.a.displacement[out][c][k_] = u[c];
      v_.a.rotation[out][c][k_] = t[c];
      v_.a.velocity[c][k_] = v[c];
      v_.a.angular_velocity[c][k_] = omega[c];
    }
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void add_account(const StepSums<double>& s,
                                                          bool prescribed) const {
    v_.a.damping_sum[k_] += s.damping_sum;
    if (prescribed) v_.a.work_sum[k_] += s.work_sum;
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void report(const ParticleReport<double>& r) const {
    for (int c = 0; c < 3; ++c) {
      v_.a.force[c][k_] = r.force[c];
      v_.a.torque[c][k_] = r.torque[c];
    }
    const std::size_t p = static_cast<std::size_t>(v_.padded);
    for (int q = 0; q < kParticlePartials; ++q) v_.a.partial[q * p + k_] = r.partial[q];
  }

 private:
  const ParticleStepView& v_;
  int k_;
};

/// One cycle of particle k (k < padded) of the device's arrays.
template <bool kReport, int kMode>
PLYDEM_HOST_DEVICE inline void particle_step(const ParticleStepView& v, int k) {
  ParticleLayout layout(v, k);
  step_particle<kReport, kMode>(layout);
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
