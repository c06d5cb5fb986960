// The reference backend (solvers/explicit_backend.hpp): the plain loops over the model's own
// arrays, one thread. Each cycle is a scatter pass over the bonds (contacts/bond_kernel.hpp
// compute_bond_forces: each bond adds to both its particles), the contacts' pass, the failure law
// bond by bond (update_bond_damage, the one law), then the shared update of every particle
// (solvers/particle_step.hpp advance_particle, T = double). Its forces are summed in another order
// than the kernel-order backends', so tests hold them to it within rounding, not to the bit.
#include <cmath>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "solvers/explicit_backend.hpp"
#include "solvers/particle_step.hpp"

namespace plydem {
namespace {

class ReferenceBackend final : public KernelBackend {
 public:
  explicit ReferenceBackend(const BackendSetup& setup)
      : model_(*setup.model), history_(*setup.history), breaking_(setup.breaking) {}

  ExplicitBackend kind() const override { return ExplicitBackend::kReference; }
  bool kernel_order() const override { return false; }
  std::size_t bytes() const override { return 0; }  // the model's own arrays

  void set_motions(const MotionTable& table) override { motions_ = table; }

  void start_breaking(bool) override {
    breaking_ = true;
    const int n = model_.particles.size();
    account_.work.setZero(n);
    account_.damping.setZero(n);
    account_.contact_force.setZero(n, 3);
    account_.contact_torque.setZero(n, 3);
  }

  bool supports_contacts(std::string*) const override { return true; }
  void load() override {}
  void store() override {}

  CycleBatch run_cycles(long cycles, bool report_last, const CycleStep& step) override {
    CycleBatch batch;
    for (long c = 0; c < cycles; ++c) {
      const bool report = report_last && c + 1 == cycles;
      if (report) {
        previous_displacement_ = model_.particles.displacement;
        previous_rotation_ = model_.particles.rotation;
      }
      cycle(report, step.first_cycle + c, step, batch);
      batch.cycles = c + 1;
      batch.reported = report;
      if (!batch.events.empty()) break;
    }
    return batch;
  }

  void gather(std::span<const int> particles, Particles& into, StateAt at) const override {
    const Particles& p = model_.particles;
    const bool current = at == StateAt::kCurrent;
    for (int i : particles) {
      for (int c = 0; c < 3; ++c) {
        into.displacement(i, c) = current ? p.displacement(i, c) : previous_displacement_(i, c);
        into.rotation(i, c) = current ? p.rotation(i, c) : previous_rotation_(i, c);
        into.velocity(i, c) = p.velocity(i, c);
        into.angular_velocity(i, c) = p.angular_velocity(i, c);
      }
    }
  }

  double state(int i, int c, bool rotation) const override {
    const Particles& p = model_.particles;
    return rotation ? p.rotation(i, c) : p.displacement(i, c);
  }

  ContactState contact_state() const override {
    const Particles& p = model_.particles;
    ContactState s;
    for (int c = 0; c < 3; ++c) {
      s.displacement[c] = p.displacement.col(c).data();
      s.rotation[c] = p.rotation.col(c).data();
      s.velocity[c] = p.velocity.col(c).data();
      s.angular_velocity[c] = p.angular_velocity.col(c).data();
    }
    return s;
  }

  std::vector<int> contact_index() const override {
    std::vector<int> index(static_cast<std::size_t>(model_.particles.size()));
    for (std::size_t i = 0; i < index.size(); ++i) index[i] = static_cast<int>(i);
    return index;
  }

  void touch_contacts(const std::vector<int>&) override {}
  void clear_bond(int) override {}  // the model's bonds are the table

  std::array<BondEnd, 2> bond_ends(int bond) const override {
    const Bonds& bonds = model_.bonds;
    const BondEnd end{!bonds.is_broken(bond), bonds.damage(bond), history_.kappa(bond)};
    return {end, end};
  }

  // The model's bonds and the history are the backend's own state already.
  void store_bonds(Bonds&, Eigen::ArrayXd&) const override {}
  void restore_bonds(const Bonds&, const Eigen::ArrayXd&) override {}

  AccountArrays account() const override {
    if (breaking_) return account_;
    AccountArrays a;
    const int n = model_.particles.size();
    a.work.setZero(n);
    a.damping.setZero(n);
    a.contact_force.setZero(n, 3);
    a.contact_torque.setZero(n, 3);
    return a;
  }
  void set_account(const AccountArrays& a) override { account_ = a; }

 private:
  void cycle(bool report, long number, const CycleStep& step, CycleBatch& batch);
  void apply_contacts(UnbondedContacts& contacts, double dt);
  void decide_bonds(long number, std::vector<SlotEvent>& events);
  template <bool kReport>
  void advance_all(const CycleStep& step, double (&sums)[kParticlePartials]);

  Model& model_;
  BondHistory& history_;
  bool breaking_;
  MotionTable motions_;
  AccountArrays account_;
  // The displacements and rotations before the last report cycle (gather at StateAt::kForces).
  Vector3Array previous_displacement_, previous_rotation_;
};

void ReferenceBackend::cycle(bool report, long number, const CycleStep& step, CycleBatch& batch) {
  Particles& p = model_.particles;
  const BondPass pass = compute_bond_forces(p, model_.bonds);
  if (step.contacts && !step.contacts->contacts().empty()) apply_contacts(*step.contacts, step.dt);
  // The failure law at this cycle's state; what it decides acts from the next cycle.
  if (breaking_) decide_bonds(number, batch.events);
  double sums[kParticlePartials] = {};
  if (report) {
    advance_all<true>(step, sums);
    sums[0] = pass.strain_energy;
    sums[1] = pass.sum_force_norm;
    std::copy(sums, sums + kParticlePartials, batch.sums);
  } else {
    advance_all<false>(step, sums);
  }
}

void ReferenceBackend::apply_contacts(UnbondedContacts& contacts, double dt) {
  Particles& p = model_.particles;
  ContactForces out;
  for (int c = 0; c < 3; ++c) {
    out.force[c] = account_.contact_force.col(c).data();
    out.torque[c] = account_.contact_torque.col(c).data();
  }
  contacts.apply(contact_state(), dt, out);
  p.force += account_.contact_force;
  p.torque += account_.contact_torque;
}

void ReferenceBackend::decide_bonds(long number, std::vector<SlotEvent>& events) {
  const Particles& p = model_.particles;
  Bonds& bonds = model_.bonds;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) continue;
    const BondStrength strength = bond_strength(bonds, b);
    if (!std::isfinite(strength.tensile) && !std::isfinite(strength.cohesion)) continue;
    double du[3], dtheta[3];
    const BondDeformation d = bond_deformation(p, bonds, b, du, dtheta);
    const BondStiffness intact{history_.intact[0](b), history_.intact[1](b), history_.intact[2](b),
                               history_.intact[3](b)};
    const BondDamageUpdate u =
        update_bond_damage(d, intact, strength, bonds.damage(b), history_.kappa(b));
    if (!u.changed) continue;
    history_.kappa(b) = u.kappa;
    const int i = bonds.first(b);
    const double displacement[3] = {p.displacement(i, 0), p.displacement(i, 1),
                                    p.displacement(i, 2)};
    const double n[3] = {bonds.normal(b, 0), bonds.normal(b, 1), bonds.normal(b, 2)};
    events.push_back(
        damage_event(b, number, u, bonds.damage(b), intact, du, dtheta, n, displacement));
    if (!u.broken) {
      bonds.damage(b) = u.damage;
      bonds.normal_stiffness(b) = (1.0 - u.damage) * intact.normal;
      bonds.shear_stiffness(b) = (1.0 - u.damage) * intact.shear;
      bonds.bending_stiffness(b) = (1.0 - u.damage) * intact.bending;
      bonds.twisting_stiffness(b) = (1.0 - u.damage) * intact.twisting;
    }
  }
}

// Every particle's update (advance_particle, one particle at a time), with the report's sums in
// particle order and the account's per-particle sums.
template <bool kReport>
void ReferenceBackend::advance_all(const CycleStep& step, double (&sums)[kParticlePartials]) {
  using Ops = LaneOps<double>;
  Particles& p = model_.particles;
  const MotionTable& m = motions_;
  for (int i = 0; i < p.size(); ++i) {
    LaneMotion<double> motion;
    bool prescribed = false;
    double force[3], torque[3], u[3], theta[3], v[3], omega[3];
    for (int c = 0; c < 3; ++c) {
      motion.fix_velocity[c] = m.fixed_velocity(i, c);
      motion.fix_angular_velocity[c] = m.fixed_angular_velocity(i, c);
      motion.velocity[c] = m.velocity(i, c);
      motion.angular_velocity[c] = m.angular_velocity(i, c);
      prescribed |= motion.fix_velocity[c] || motion.fix_angular_velocity[c];
      force[c] = p.force(i, c);
      torque[c] = p.torque(i, c);
      u[c] = p.displacement(i, c);
      theta[c] = p.rotation(i, c);
      v[c] = p.velocity(i, c);
      omega[c] = p.angular_velocity(i, c);
    }
    motion.counts_free =
        !(motion.fix_velocity[0] || motion.fix_velocity[1] || motion.fix_velocity[2]);
    StepSums<double> s;
    const double inverse_mass = 1.0 / p.mass(i), inverse_inertia = 1.0 / p.moment_of_inertia(i);
    if (breaking_) {
      advance_particle<kReport, true>(force, torque, motion, inverse_mass, inverse_inertia, step.dt,
                                      step.alpha, u, theta, v, omega, s);
      account_.damping(i) += s.damping_sum;
      if (prescribed) account_.work(i) += s.work_sum;
    } else {
      advance_particle<kReport, false>(force, torque, motion, inverse_mass, inverse_inertia,
                                       step.dt, step.alpha, u, theta, v, omega, s);
    }
    for (int c = 0; c < 3; ++c) {
      p.displacement(i, c) = u[c];
      p.rotation(i, c) = theta[c];
      p.velocity(i, c) = v[c];
      p.angular_velocity(i, c) = omega[c];
    }
    if constexpr (kReport) {
      const double f2 =
          Ops::fmadd(force[2], force[2], Ops::fmadd(force[1], force[1], force[0] * force[0]));
      sums[2] += s.kinetic;
      sums[3] += Ops::keep(Ops::sqrt(f2), motion.counts_free);
      sums[4] += s.work_half;
      sums[5] += s.damping_half;
    }
  }
}

}  // namespace

std::unique_ptr<KernelBackend> make_reference_backend(const BackendSetup& setup) {
  return std::make_unique<ReferenceBackend>(setup);
}

}  // namespace plydem
