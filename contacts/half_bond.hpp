#pragma once
/// \file
/// One bond seen from one of its particles: the half-bond math of the gather kernels, the loop over
/// a particle's bonds (gather_half_bonds) and the failure law's decision on a bond, written once
/// for every backend (core/host_device.hpp). The host's SIMD kernel instantiates the templates
/// below with T = lanes::Doubles, eight particles in the lanes of GCC vector extensions
/// (contacts/bond_kernel.hpp: BlockSlots); the CUDA kernel and its host emulation with T = double,
/// one particle (solvers/particle_step.hpp: ParticleSlots). Both evaluate every expression in the
/// same order with the exactly rounded operations of core/lane_ops.hpp (every multiply-add an
/// explicit fused one), so they compute the same numbers to the bit.
///
/// No Eigen and no vector extension here: nvcc compiles this header.

#include <cmath>
#include <cstdint>

#include "core/bond_failure_law.hpp"
#include "core/host_device.hpp"
#include "core/lane_ops.hpp"

namespace plydem {

/// A bond's deformation as the failure law reads it: the four magnitudes the section stresses
/// depend on (core/bond_failure.hpp), the same seen from either end.
struct BondDeformation {
  double normal = 0;  ///< du_n = n.du, extension positive [m]
  double shear = 0;   ///< |du - du_n n| [m]
  double twist = 0;   ///< dtheta_n [rad]
  double bend = 0;    ///< |dtheta - dtheta_n n| [rad]
};

/// A bond's intact stiffnesses (its current ones are 1 - damage times these).
struct BondStiffness {
  double normal = 0;    ///< k_n [N/m]
  double shear = 0;     ///< k_s [N/m]
  double bending = 0;   ///< k_b [N m/rad]
  double twisting = 0;  ///< k_t [N m/rad]
};

/// The deformation from the contact point's relative displacement `du`, the relative rotation
/// `dtheta` and the unit normal `n`, as seen from one end. Seen from the other end all three are
/// negated exactly, and the result is the same to the bit: every product keeps its value
/// ((-a)(-b) = ab), every fused difference is negated (RN(-x) = -RN(x)), and du_n, the norms and
/// the sums are computed in the same order.
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE BondDeformation deformation_of(const double du[3],
                                                                      const double dtheta[3],
                                                                      const double n[3]) {
  BondDeformation d;
  d.normal = fmadd(n[2], du[2], fmadd(n[1], du[1], n[0] * du[0]));
  d.twist = fmadd(n[2], dtheta[2], fmadd(n[1], dtheta[1], n[0] * dtheta[0]));
  double shear2 = 0, bend2 = 0;
  for (int c = 0; c < 3; ++c) {
    const double s = fmadd(-d.normal, n[c], du[c]);
    const double b = fmadd(-d.twist, n[c], dtheta[c]);
    shear2 = fmadd(s, s, shear2);
    bend2 = fmadd(b, b, bend2);
  }
  d.shear = std::sqrt(shear2);
  d.bend = std::sqrt(bend2);
  return d;
}

/// What the failure law does to one bond at one cycle (update_bond_damage).
struct BondDamageUpdate {
  bool changed = false;  ///< damage or kappa moved
  bool broken = false;   ///< the bond breaks: damage 1, state = mode, from the next cycle on
  BondState mode = BondState::kIntact;
  double damage = 0;       ///< after this cycle
  double kappa = 1;        ///< largest utilisation so far (softening), after this cycle
  double utilisation = 0;  ///< U at this cycle (intact-equivalent stresses)
};

/// The one failure law applied to a bond of intact stiffnesses `intact`, damage `damage` and
/// softening history `kappa` (1 for a bond that never softened) at deformation `d`: the section
/// stresses with the current stiffness (1 - damage) x intact (section_stresses), made
/// intact-equivalent (intact_stresses), their utilisation() against `strength`. A brittle bond
/// (ductility 1) breaks at U >= 1 in the mode utilisation() names; a softening one raises kappa
/// to U when U > kappa, takes damage softening_damage(kappa, ductility), and breaks when it
/// reaches 1. A mixed-mode bond (core/bond_failure.hpp) softens alike with the ductility of the
/// mix at this state, kappa_u(B), its damage never falling. Both kernels decide through this
/// function.
PLYDEM_HOST_DEVICE inline BondDamageUpdate update_bond_damage(const BondDeformation& d,
                                                              const BondStiffness& intact,
                                                              const BondStrength& strength,
                                                              double damage, double kappa) {
  const double remaining = 1.0 - damage;
  const BondStresses current =
      section_stresses((remaining * intact.normal) * d.normal, (remaining * intact.shear) * d.shear,
                       (remaining * intact.bending) * d.bend,
                       (remaining * intact.twisting) * std::abs(d.twist), strength.radius);
  const BondStresses stresses = intact_stresses(current, damage);
  const BondUtilisation u = utilisation(stresses, strength);
  BondDamageUpdate r;
  r.damage = damage;
  r.kappa = kappa;
  r.utilisation = u.ratio;
  if (strength.mixed_mode()) {
    if (u.ratio > kappa) {
      r.changed = true;
      r.kappa = u.ratio;
      r.damage =
          std::max(damage, softening_damage(u.ratio, softening_ductility(stresses, strength)));
      if (r.damage >= 1) {
        r.broken = true;
        r.mode = u.mode;  // U >= kappa_u(B) >= 1: tension or shear
        r.damage = 1;
      }
    }
  } else if (!(strength.ductility > 1)) {
    if (u.mode != BondState::kIntact) {
      r.changed = r.broken = true;
      r.mode = u.mode;
      r.damage = 1;
    }
  } else if (u.ratio > kappa) {
    r.changed = true;
    r.kappa = u.ratio;
    r.damage = softening_damage(u.ratio, strength.ductility);
    if (r.damage >= 1) {
      r.broken = true;
      r.mode = u.mode;  // U >= ductility >= 1: tension or shear
      r.damage = 1;
    }
  }
  return r;
}

/// One bond as seen from one of its particles ("own"), toward the other: the parameters of the
/// gather form. With the normal pointing from own to other, the force and moment on own are those
/// parallel_bond_response gives the first particle (it is symmetric under swapping the two ends,
/// which flips n, du and dtheta), written as
///   F = k_s du + (k_n - k_s)(n.du) n,   M_own = s_own n x F + k_b dtheta + (k_t - k_b)(n.dtheta)
///   n.
struct HalfBondType {
  double normal[3] = {0, 0, 0};  ///< unit, own -> other
  double lever_own = 0;          ///< [m]
  double lever_other = 0;        ///< [m]
  double shear_stiffness = 0;    ///< k_s [N/m]
  double lever_shear = 0;        ///< s_own k_s [N]
  double normal_excess = 0;      ///< k_n - k_s [N/m]
  double bending_stiffness = 0;  ///< k_b [N m/rad]
  double twisting_excess = 0;    ///< k_t - k_b [N m/rad]
};

/// What breaking adds to a half-bond type (a GatherBonds built with breaking on). The lever term
/// of du is computed as (sigma (theta_own + theta_other) + delta (theta_other - theta_own)) x n,
/// which both ends of a bond evaluate to the same number (gather_half_bonds). The screen
/// constants let the kernel skip the failure law for bonds far from their strength:
///  - alpha |du|^2 + beta |dtheta|^2 >= 1 whenever U >= 1 (a bound: |du_n|, |du_s| <= |du|,
///    (x + y)^2 <= 2 (x^2 + y^2)), with alpha = 2 max(k_n^2 / T_t^2, (k_s + tan(phi) k_n)^2 /
///    T_c^2), beta = 2 max((4 k_b / R)^2 / T_t^2, (2 k_t / R)^2 / T_c^2), T_t = A sigma_c and T_c =
///    A c the section's strengths as forces; it holds for U >= kappa >= 1 too;
///  - then, lane by lane, the tension and shear tests of core/bond_failure.hpp without square
///    roots (F_n + (4/R)|M_b| >= kappa T_t as (kappa T_t - F_n)^2 <= (4/R)^2 |M_b|^2, and so on),
///    against thresholds lowered by kScreenMargin, and only where one holds the exact law
///    (update_bond_damage).
/// All stiffnesses here are intact ones (a softening bond's current ones are 1 - damage times).
struct HalfBondFailure {
  double lever_mean = 0;             ///< sigma = (s_own + s_other) / 2 [m]
  double lever_half_difference = 0;  ///< delta = (s_other - s_own) / 2 [m]
  double normal_stiffness = 0;       ///< intact k_n [N/m]
  double shear_stiffness = 0;        ///< intact k_s [N/m]
  double bending_stiffness = 0;      ///< intact k_b [N m/rad]
  double twisting_stiffness = 0;     ///< intact k_t [N m/rad]
  /// The bond's strength; with strengths kept per slot, tensile and cohesion are the slot's.
  BondStrength strength;
  double screen_displacement = 0;      ///< alpha [1/m^2] (strengths per type)
  double screen_rotation = 0;          ///< beta [1/rad^2] (strengths per type)
  double tension_threshold = 0;        ///< (1 - kScreenMargin) T_t [N] (strengths per type)
  double shear_threshold = 0;          ///< (1 - kScreenMargin) T_c [N] (strengths per type)
  double shear_friction = 0;           ///< (1 - kScreenMargin) tan(phi)
  double bending_factor = 0;           ///< (4 k_b / R)^2 [N^2/rad^2]; 0 for an unbreakable bond
  double twisting_factor = 0;          ///< 2 k_t / R [N/rad]; 0 for an unbreakable bond
  double shear_stiffness_squared = 0;  ///< k_s^2
};

/// How far below its strength the kernel's screen starts asking the exact law (relative): it
/// covers the rounding between the screen's vector arithmetic and the scalar law's.
inline constexpr double kScreenMargin = 1e-9;
/// The first screen's bound is compared with 1 - kScreenBound.
inline constexpr double kScreenBound = 1e-6;

/// A damage step (a break, or a softening step) that a bond's first end decided. The energy the
/// step releases needs the bond's deformation at the next state: with q the deformation and K the
/// intact stiffness, a step from damage d to d' decided at q_n (acting from n + 1) takes
/// 1/2 (d' - d) q_n.K q_n+1 out of the leapfrog account exactly (the trapezoidal work of the bond
/// over the step, less its change of energy). The event keeps K q_n for that.
struct SlotEvent {
  int bond = 0;    ///< model bond
  long cycle = 0;  ///< BreakingPass::cycle of the pass
  bool broken = false;
  BondState mode = BondState::kIntact;  ///< how it broke
  double damage_before = 0, damage_after = 0;
  double force[3] = {0, 0, 0};   ///< intact force k_n du_n n + k_s du_s on the first end at q_n
  double moment[3] = {0, 0, 0};  ///< intact moment k_t dtheta_n n + k_b dtheta_s at q_n
  double displacement[3] = {0, 0, 0};  ///< of the bond's first particle, at q_n's state
};

/// The event of a bond whose first end saw `update` at deformation (du, dtheta) along n with
/// intact stiffnesses `k` (both kernels build them alike).
PLYDEM_HOST_DEVICE inline SlotEvent damage_event(int bond, long cycle,
                                                 const BondDamageUpdate& update,
                                                 double damage_before, const BondStiffness& k,
                                                 const double du[3], const double dtheta[3],
                                                 const double n[3], const double displacement[3]) {
  SlotEvent e;
  e.bond = bond;
  e.cycle = cycle;
  e.broken = update.broken;
  e.mode = update.mode;
  e.damage_before = damage_before;
  e.damage_after = update.damage;
  const double du_n = fmadd(n[2], du[2], fmadd(n[1], du[1], n[0] * du[0]));
  const double dt_n = fmadd(n[2], dtheta[2], fmadd(n[1], dtheta[1], n[0] * dtheta[0]));
  for (int c = 0; c < 3; ++c) {
    e.force[c] = fmadd(k.normal * du_n, n[c], k.shear * fmadd(-du_n, n[c], du[c]));
    e.moment[c] = fmadd(k.twisting * dt_n, n[c], k.bending * fmadd(-dt_n, n[c], dtheta[c]));
    e.displacement[c] = displacement[c];
  }
  return e;
}

/// The relative rotation dtheta = theta_j - theta_i and the lever term a of du = (u_j - u_i) - a x
/// n in the form the elastic kernel computes: a = s_own theta_i + s_other theta_j (the parallel
/// bond of core/parallel_bond.hpp).
template <class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void lever_term(const T& s_own, const T& s_other,
                                                       const T (&t_i)[3], const T (&t_j)[3],
                                                       T (&dt)[3], T (&a)[3]) {
  for (int c = 0; c < 3; ++c) dt[c] = t_j[c] - t_i[c];
  for (int c = 0; c < 3; ++c) a[c] = LaneOps<T>::fmadd(s_other, t_j[c], s_own * t_i[c]);
}

/// The same in the form the breaking kernels compute, the same number from either end of a bond
/// (gather_half_bonds, "Both ends alike"): a = sigma (theta_i + theta_j) + delta dtheta with
/// sigma = (s_own + s_other) / 2 and delta = (s_other - s_own) / 2. From the other end delta and
/// dtheta are both negated, so the fused product keeps its value and a is the same number.
template <class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void symmetric_lever_term(const T& sigma, const T& delta,
                                                                 const T (&t_i)[3],
                                                                 const T (&t_j)[3], T (&dt)[3],
                                                                 T (&a)[3]) {
  for (int c = 0; c < 3; ++c) dt[c] = t_j[c] - t_i[c];
  for (int c = 0; c < 3; ++c) a[c] = LaneOps<T>::fmadd(delta, dt[c], sigma * (t_i[c] + t_j[c]));
}

/// What one half-bond computes besides its force and moment: the deformation the failure law and
/// the screens read.
template <class T>
struct HalfBondMotion {
  T du[3];          ///< relative displacement of the contact point
  T du_n;           ///< n.du
  T dt_n;           ///< n.dtheta
  T n_cross_du[3];  ///< n x du (its norm is |du_s| without cancellation)
  T du2;            ///< |du|^2
  T dt2;            ///< |dtheta|^2
};

/// The parallel bond (core/parallel_bond.hpp) on the own end of a half-bond of normal `n`, at the
/// other end's displacement `u_j` less the own `u_i`, lever term `a` and relative rotation `dt`
/// (lever_term, symmetric_lever_term), with the stiffnesses of HalfBondType (k_s, s_own k_s,
/// k_n - k_s, k_b, k_t - k_b, each scaled by 1 - damage where the bond softens):
///   F = k_s du + (k_n - k_s)(n.du) n,   M_own = s_own n x F + k_b dtheta + (k_t - k_b)(n.dtheta)
///   n,
/// added to `force` and `torque` term by term. With kEnergy also half the bond's strain energy
/// (each bond is seen from both ends) added to `energy`, and |F|^2 written to `force2`, from
/// scalars only: no product shared with the force, so that report cycles compute the forces with
/// the very same instructions as the others (cycle() and advance(n) agree to the bit).
template <bool kEnergy, class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void half_bond_response(
    const T (&n)[3], const T (&u_i)[3], const T (&u_j)[3], const T (&a)[3], const T (&dt)[3],
    const T& k_s, const T& s_k_s, const T& k_n_excess, const T& k_b, const T& k_t_excess,
    T (&force)[3], T (&torque)[3], T& energy, T& force2, HalfBondMotion<T>& m) {
  using Ops = LaneOps<T>;
  // a x n, each component one rounded product and one fused: from the other end of a bond (a the
  // same, n negated) it is negated exactly, as u_j - u_i is.
  m.du[0] = (u_j[0] - u_i[0]) - Ops::fmadd(a[1], n[2], -(a[2] * n[1]));
  m.du[1] = (u_j[1] - u_i[1]) - Ops::fmadd(a[2], n[0], -(a[0] * n[2]));
  m.du[2] = (u_j[2] - u_i[2]) - Ops::fmadd(a[0], n[1], -(a[1] * n[0]));
  m.du_n = Ops::fmadd(n[2], m.du[2], Ops::fmadd(n[1], m.du[1], n[0] * m.du[0]));
  const T normal_part = k_n_excess * m.du_n;
  for (int c = 0; c < 3; ++c) {
    force[c] = Ops::fmadd(k_s, m.du[c], force[c]);
    force[c] = Ops::fmadd(normal_part, n[c], force[c]);
  }
  m.n_cross_du[0] = Ops::fmadd(n[1], m.du[2], -(n[2] * m.du[1]));
  m.n_cross_du[1] = Ops::fmadd(n[2], m.du[0], -(n[0] * m.du[2]));
  m.n_cross_du[2] = Ops::fmadd(n[0], m.du[1], -(n[1] * m.du[0]));
  m.dt_n = Ops::fmadd(n[2], dt[2], Ops::fmadd(n[1], dt[1], n[0] * dt[0]));
  const T twist_part = k_t_excess * m.dt_n;
  for (int c = 0; c < 3; ++c) {
    torque[c] = Ops::fmadd(s_k_s, m.n_cross_du[c], torque[c]);
    torque[c] = Ops::fmadd(k_b, dt[c], torque[c]);
    torque[c] = Ops::fmadd(twist_part, n[c], torque[c]);
  }
  m.du2 = Ops::fmadd(m.du[2], m.du[2], Ops::fmadd(m.du[1], m.du[1], m.du[0] * m.du[0]));
  m.dt2 = Ops::fmadd(dt[2], dt[2], Ops::fmadd(dt[1], dt[1], dt[0] * dt[0]));
  if constexpr (kEnergy) {
    // E = 1/2 (k_s |du|^2 + (k_n - k_s) du_n^2 + k_b |dtheta|^2 + (k_t - k_b) dtheta_n^2), half
    // of it per end; |F|^2 = k_s^2 |du|^2 + (k_n^2 - k_s^2) du_n^2.
    const T twice = Ops::fmadd(
        twist_part, m.dt_n, Ops::fmadd(k_b, m.dt2, Ops::fmadd(normal_part, m.du_n, k_s * m.du2)));
    energy = Ops::fmadd(0.25, twice, energy);
    force2 =
        Ops::fmadd(normal_part, Ops::fmadd(2.0 * k_s, m.du_n, normal_part), (k_s * k_s) * m.du2);
  }
}

/// The first screen of the breaking kernels (HalfBondFailure): alpha |du|^2 + beta |dtheta|^2,
/// compared with 1 - kScreenBound; below it the bond is surely below its strength. (An output
/// argument, not a return value: no function boundary depends on the vector ABI.)
template <class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void screen_measure(const T& alpha, const T& beta,
                                                           const HalfBondMotion<T>& m, T& out) {
  out = LaneOps<T>::fmadd(alpha, m.du2, beta * m.dt2);
}

/// The bond loop's variants: elastic, or breaking with strengths per type or per slot, brittle or
/// softening (contacts/bond_kernel.hpp StrengthStorage, GatherBreaking).
enum KernelMode : int {
  kElasticMode = 0,
  kBrittleTypes = 1,
  kBrittleSlots = 2,
  kSofteningTypes = 3,
  kSofteningSlots = 4
};

/// What a mode computes.
constexpr bool breaks_bonds(int mode) {
  return mode != kElasticMode;
}
constexpr bool softens_bonds(int mode) {
  return mode == kSofteningTypes || mode == kSofteningSlots;
}
constexpr bool has_slot_strengths(int mode) {
  return mode == kBrittleSlots || mode == kSofteningSlots;
}

/// One slot's half-bond, as gather_half_bonds loads it (HalfBondType; breaking: the lever terms
/// and screen constants of HalfBondFailure).
template <class T>
struct HalfBondLoad {
  T normal[3];
  /// Elastic: s_own and s_other (lever_term); breaking: sigma and delta (symmetric_lever_term).
  T lever_a, lever_b;
  T shear_stiffness, lever_shear, normal_excess, bending_stiffness, twisting_excess;
  T screen_displacement, screen_rotation;  ///< breaking: alpha and beta
};

/// A slot's half-bond from its type `t` and, breaking, its failure data `f` (HalfBondType and
/// HalfBondFailure for one particle; their lanes, HalfBondLanes and HalfBondFailureLanes, for a
/// block whose particles share the type). The screen's constants are the type's unless strengths
/// are kept per slot (the caller loads those).
template <int kMode, class Type, class Failure, class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void load_half_bond(const Type& t, const Failure* f,
                                                           HalfBondLoad<T>& h) {
  for (int c = 0; c < 3; ++c) h.normal[c] = t.normal[c];
  h.shear_stiffness = t.shear_stiffness;
  h.lever_shear = t.lever_shear;
  h.normal_excess = t.normal_excess;
  h.bending_stiffness = t.bending_stiffness;
  h.twisting_excess = t.twisting_excess;
  if constexpr (breaks_bonds(kMode)) {
    h.lever_a = f->lever_mean;
    h.lever_b = f->lever_half_difference;
    if constexpr (!has_slot_strengths(kMode)) {
      h.screen_displacement = f->screen_displacement;
      h.screen_rotation = f->screen_rotation;
    }
  } else {
    h.lever_a = t.lever_own;
    h.lever_b = t.lever_other;
  }
}

/// The force and moment on one particle (T = double) or on one block of particles (T a vector of
/// lanes) from all its bonds, added to `force` and `torque`, written once for every backend. With
/// kEnergy, also half of each bond's strain energy and half its force magnitude (each bond is seen
/// from both ends), added to `energy` and `force_norm`. Breaking modes (kMode) use the intact
/// stiffnesses times 1 - damage where bonds soften, and hand each bond's deformation to the
/// slots' failure screen and law (Slots::assess), which may empty a slot: the break acts from the
/// next cycle.
///
/// `Slots` is how a backend keeps the bond table (the host's block tables, BlockSlots in
/// contacts/bond_kernel.hpp; the device's per-particle table, ParticleSlots in
/// solvers/particle_step.hpp): width(); empty(slot) (no particle of the lanes has a bond in it);
/// other_state(slot, u_j, theta_j); load<kMode>(slot, HalfBondLoad&); damage(slot, d) (softening);
/// assess<kMode>(slot, measure, n, motion, dtheta, u_i) (breaking).
///
/// Both ends alike (breaking). Seen from the other end, a bond's type is the exact mirror image
/// (n -> -n, s_own <-> s_other; GatherBonds) and its state arrives swapped (u_i <-> u_j, theta_i
/// <-> theta_j). The kernel computes dtheta = theta_j - theta_i (negated exactly: RN(b - a) = -RN(a
/// - b)), a = sigma (theta_i + theta_j) + delta dtheta with sigma = (s_own + s_other) / 2
/// (unchanged: addition commutes) and delta = (s_other - s_own) / 2 (negated), so both products
/// keep their values and a is the same number from either end. Then a x n and u_j - u_i are
/// negated exactly, so du is, and du_n = n.du, dtheta_n, |du|^2, |dtheta|^2 are sums of the same
/// products in the same order: the screens see the same numbers and deformation_of() returns the
/// same deformation at both ends. The exact law then gets the same inputs (the mirror types hold
/// the same stiffnesses and strength, both slots the same damage and kappa, updated alike every
/// cycle), so both ends decide alike, cycle by cycle, with no communication between them; the
/// integrator checks it when it writes the table back (and tests compare the ends bit for bit).
template <bool kEnergy, int kMode, class Slots, class T>
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE void gather_half_bonds(Slots& slots, const T (&u_i)[3],
                                                              const T (&t_i)[3], T (&force)[3],
                                                              T (&torque)[3], T& energy,
                                                              T& force_norm) {
  using Ops = LaneOps<T>;
  for (int slot = 0; slot < slots.width(); ++slot) {
    if (slots.empty(slot)) continue;
    T u_j[3], t_j[3];
    slots.other_state(slot, u_j, t_j);
    HalfBondLoad<T> h;
    slots.template load<kMode>(slot, h);
    if constexpr (softens_bonds(kMode)) {
      T damage;
      slots.damage(slot, damage);
      const T remaining = 1.0 - damage;
      h.shear_stiffness = remaining * h.shear_stiffness;
      h.lever_shear = remaining * h.lever_shear;
      h.normal_excess = remaining * h.normal_excess;
      h.bending_stiffness = remaining * h.bending_stiffness;
      h.twisting_excess = remaining * h.twisting_excess;
    }
    T dt[3], a[3], f2{};
    if constexpr (breaks_bonds(kMode)) {
      symmetric_lever_term(h.lever_a, h.lever_b, t_i, t_j, dt, a);
    } else {
      lever_term(h.lever_a, h.lever_b, t_i, t_j, dt, a);
    }
    HalfBondMotion<T> m;
    half_bond_response<kEnergy>(h.normal, u_i, u_j, a, dt, h.shear_stiffness, h.lever_shear,
                                h.normal_excess, h.bending_stiffness, h.twisting_excess, force,
                                torque, energy, f2, m);
    if constexpr (kEnergy) force_norm = Ops::fmadd(0.5, Ops::sqrt(f2), force_norm);
    if constexpr (breaks_bonds(kMode)) {
      T measure;
      screen_measure(h.screen_displacement, h.screen_rotation, m, measure);
      slots.template assess<kMode>(slot, measure, h.normal, m, dt, u_i);
    }
  }
}

}  // namespace plydem
