// The reference backend (solvers/explicit_backend.hpp): the plain loops over the model's own
// arrays, one thread. Each cycle is a scatter pass over the bonds (contacts/bond_kernel.hpp
// compute_bond_forces: each bond adds to both its particles), the contacts' pass, the failure law
// bond by bond (update_bond_damage, the one law), then the shared update of every particle
// (solvers/particle_step.hpp advance_particle, T = double). Its forces are summed in another order
// than the kernel-order backends', so tests hold them to it within rounding, not to the bit.
//
// Under mpiexec (BackendSetup::split_between_ranks) the same loops run on each rank over its share
// (solvers/rank_exchange.hpp): the bonds that reach its own particles, then its own particles'
// update, then the ghosts' state from their owners. What the run loop reads (the reports' sums, the
// gathered state, the damage steps) is collected from the owners in model order: the bits of the
// one-rank run.
#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <numeric>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "solvers/explicit_backend.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/particle_step.hpp"
#include "solvers/rank_exchange.hpp"

namespace plydem {
namespace {

class ReferenceBackend final : public KernelBackend {
 public:
  explicit ReferenceBackend(const BackendSetup& setup)
      : model_(*setup.model), history_(*setup.history), breaking_(setup.breaking) {
    if (setup.split_between_ranks) {
      part_ =
          std::make_unique<RankPartition>(partition_between_ranks(model_, mpi_rank(), mpi_size()));
      exchange_ = make_rank_exchange(*part_);
    }
  }

  ExplicitBackend kind() const override { return ExplicitBackend::kReference; }
  bool kernel_order() const override { return false; }
  // The model's own arrays; on N ranks, the partition and the report's buffers besides.
  std::size_t bytes() const override {
    if (!part_) return 0;
    return part_->bytes() + sizeof(double) * (bond_values_.size() + particle_values_.size());
  }

  void set_motions(const MotionTable& table) override { motions_ = table; }

  void start_breaking(bool) override {
    breaking_ = true;
    const int n = model_.particles.size();
    account_.work.setZero(n);
    account_.damping.setZero(n);
    account_.contact_force.setZero(n, 3);
    account_.contact_torque.setZero(n, 3);
  }

  bool supports_contacts(std::string* why) const override {
    if (!part_) return true;
    if (why) *why = no_contacts_across_ranks(part_->size);
    return false;
  }
  void load() override {}
  // On N ranks every rank's model gets every particle's state from its owner.
  void store() override {
    if (part_) share_own_rows(kStateColumns);
  }

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
    if (part_) {
      gather_from_owners(particles, into, current);
      return;
    }
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
    const double value = rotation ? p.rotation(i, c) : p.displacement(i, c);
    if (!part_) return value;
    const int owner = part_->owner[static_cast<std::size_t>(i)];
    return exchange_->broadcast(owner == part_->rank ? value : 0.0, owner);
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
    if (breaking_ && part_) return shared_account();
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
  const RankPartition* partition() const override { return part_.get(); }

 private:
  // The per-particle columns share_own_rows() sends: the state (displacement, rotation, velocity,
  // angular velocity), or the forces (force, torque).
  enum Columns { kStateColumns, kForceColumns };

  void cycle(bool report, long number, const CycleStep& step, CycleBatch& batch);
  void apply_contacts(UnbondedContacts& contacts, double dt);
  void decide_bond(long number, int b, bool logs, std::vector<SlotEvent>& events);
  void set_damage(int b, double d);
  template <bool kReport>
  void advance_all(const CycleStep& step, double (&sums)[kParticlePartials]);
  template <bool kReport>
  void advance_one(int i, const CycleStep& step, double* partials);

  // On N ranks (part_ set):
  // Every rank's damage steps of this cycle, on every rank, each rank's model brought up to them.
  void share_events(std::vector<SlotEvent>& events);
  // The report's sums from every rank's per-particle and per-bond values, in model order.
  void share_report(double (&sums)[kParticlePartials]);
  void share_own_rows(Columns columns);
  void gather_from_owners(std::span<const int> particles, Particles& into, bool current) const;
  AccountArrays shared_account() const;

  Model& model_;
  BondHistory& history_;
  bool breaking_;
  MotionTable motions_;
  AccountArrays account_;
  // The displacements and rotations before the last report cycle (gather at StateAt::kForces).
  Vector3Array previous_displacement_, previous_rotation_;
  // On N ranks: the partition, the exchange, and a report cycle's values of the listed bonds
  // (energy and |F|) and of the own particles (the particle sums of the report).
  std::unique_ptr<RankPartition> part_;
  std::unique_ptr<RankExchange> exchange_;
  std::vector<double> bond_values_, particle_values_;
};

void ReferenceBackend::cycle(bool report, long number, const CycleStep& step, CycleBatch& batch) {
  Particles& p = model_.particles;
  BondPass pass;
  if (part_) {
    if (report) bond_values_.resize(2 * part_->bonds.size());
    pass =
        compute_listed_bond_forces(p, model_.bonds, part_->bonds, part_->local,
                                   report ? std::span<double>(bond_values_) : std::span<double>());
  } else {
    pass = compute_bond_forces(p, model_.bonds);
  }
  if (step.contacts && !step.contacts->contacts().empty()) apply_contacts(*step.contacts, step.dt);
  // The failure law at this cycle's state; what it decides acts from the next cycle.
  if (breaking_) {
    if (part_) {
      for (std::size_t k = 0; k < part_->bonds.size(); ++k)
        decide_bond(number, part_->bonds[k], part_->logs_bond[k] != 0, batch.events);
    } else {
      for (int b = 0; b < model_.bonds.size(); ++b) decide_bond(number, b, true, batch.events);
    }
  }
  double sums[kParticlePartials] = {};
  if (report) {
    advance_all<true>(step, sums);
    sums[0] = pass.strain_energy;
    sums[1] = pass.sum_force_norm;
  } else {
    advance_all<false>(step, sums);
  }
  if (part_) {
    exchange_->update_ghosts(p);
    if (breaking_) share_events(batch.events);
    if (report) {
      share_report(sums);
      share_own_rows(kForceColumns);  // the model's forces are the last cycle's at a report
    }
  }
  if (report) std::copy(sums, sums + kParticlePartials, batch.sums);
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

// Bond b by the failure law; its damage step is logged where `logs` (its first particle's rank).
void ReferenceBackend::decide_bond(long number, int b, bool logs, std::vector<SlotEvent>& events) {
  const Particles& p = model_.particles;
  Bonds& bonds = model_.bonds;
  if (bonds.is_broken(b)) return;
  const BondStrength strength = bond_strength(bonds, b);
  if (!std::isfinite(strength.tensile) && !std::isfinite(strength.cohesion)) return;
  double du[3], dtheta[3];
  const BondDeformation d = bond_deformation(p, bonds, b, du, dtheta);
  const BondStiffness intact{history_.intact[0](b), history_.intact[1](b), history_.intact[2](b),
                             history_.intact[3](b)};
  const BondDamageUpdate u =
      update_bond_damage(d, intact, strength, bonds.damage(b), history_.kappa(b));
  if (!u.changed) return;
  history_.kappa(b) = u.kappa;
  const int i = bonds.first(b);
  const double displacement[3] = {p.displacement(i, 0), p.displacement(i, 1), p.displacement(i, 2)};
  const double n[3] = {bonds.normal(b, 0), bonds.normal(b, 1), bonds.normal(b, 2)};
  if (logs)
    events.push_back(
        damage_event(b, number, u, bonds.damage(b), intact, du, dtheta, n, displacement));
  if (!u.broken) set_damage(b, u.damage);
}

// Bond b at damage d: its stiffnesses 1 - d times its intact ones.
void ReferenceBackend::set_damage(int b, double d) {
  Bonds& bonds = model_.bonds;
  bonds.damage(b) = d;
  bonds.normal_stiffness(b) = (1.0 - d) * history_.intact[0](b);
  bonds.shear_stiffness(b) = (1.0 - d) * history_.intact[1](b);
  bonds.bending_stiffness(b) = (1.0 - d) * history_.intact[2](b);
  bonds.twisting_stiffness(b) = (1.0 - d) * history_.intact[3](b);
}

// Every particle's update (advance_particle, one particle at a time; on N ranks the own ones),
// with the report's sums in particle order (on N ranks each own particle's, summed by
// share_report) and the account's per-particle sums.
template <bool kReport>
void ReferenceBackend::advance_all(const CycleStep& step, double (&sums)[kParticlePartials]) {
  if (part_) {
    constexpr int kWidth = kParticlePartials - 2;
    if (kReport) particle_values_.assign(kWidth * part_->own.size(), 0.0);
    for (std::size_t k = 0; k < part_->own.size(); ++k)
      advance_one<kReport>(part_->own[k], step,
                           kReport ? particle_values_.data() + kWidth * k : nullptr);
    return;
  }
  for (int i = 0; i < model_.particles.size(); ++i) advance_one<kReport>(i, step, sums + 2);
}

// Particle i's update, its report sums added to partials[0 .. 3] (kinetic, unbalanced force, and
// the account's two halves).
template <bool kReport>
void ReferenceBackend::advance_one(int i, const CycleStep& step, double* partials) {
  using Ops = LaneOps<double>;
  Particles& p = model_.particles;
  const MotionTable& m = motions_;
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
    advance_particle<kReport, false>(force, torque, motion, inverse_mass, inverse_inertia, step.dt,
                                     step.alpha, u, theta, v, omega, s);
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
    partials[0] += s.kinetic;
    partials[1] += Ops::keep(Ops::sqrt(f2), motion.counts_free);
    partials[2] += s.work_half;
    partials[3] += s.damping_half;
  }
}

// A damage step as the ranks exchange it: the event and the bond's softening history after it.
struct SharedEvent {
  SlotEvent event;
  double kappa = 1;
};

void ReferenceBackend::share_events(std::vector<SlotEvent>& events) {
  // Most cycles decide nothing anywhere: one reduction says so.
  if (max_over_ranks(static_cast<double>(events.size())) == 0) return;
  std::vector<SharedEvent> mine(events.size());
  for (std::size_t e = 0; e < events.size(); ++e)
    mine[e] = {events[e], history_.kappa(events[e].bond)};
  const std::vector<char> all = exchange_->gather_bytes(std::span<const char>(
      reinterpret_cast<const char*>(mine.data()), mine.size() * sizeof(SharedEvent)));
  const std::size_t count = all.size() / sizeof(SharedEvent);
  events.resize(count);
  Bonds& bonds = model_.bonds;
  const std::vector<int>& owner = part_->owner;
  for (std::size_t e = 0; e < count; ++e) {
    SharedEvent shared;
    std::memcpy(&shared, all.data() + e * sizeof(SharedEvent), sizeof(SharedEvent));
    events[e] = shared.event;
    const int b = shared.event.bond;
    const bool listed = owner[static_cast<std::size_t>(bonds.first(b))] == part_->rank ||
                        owner[static_cast<std::size_t>(bonds.second(b))] == part_->rank;
    if (listed || shared.event.broken) continue;  // a break is the run loop's (log_break)
    // A damage step decided on other ranks: this rank's model gets it too.
    history_.kappa(b) = shared.kappa;
    set_damage(b, shared.event.damage_after);
  }
}

void ReferenceBackend::share_report(double (&sums)[kParticlePartials]) {
  constexpr int kWidth = kParticlePartials - 2;
  const Bonds& bonds = model_.bonds;
  const std::vector<int>& owner = part_->owner;
  std::vector<double> logged;  // energy and |F| of the bonds this rank logs, in bond order
  for (std::size_t k = 0; k < part_->bonds.size(); ++k)
    if (part_->logs_bond[k])
      logged.insert(logged.end(), {bond_values_[2 * k], bond_values_[2 * k + 1]});
  std::vector<std::size_t> at;  // each rank's next value
  const std::vector<double> bond_all = exchange_->gather_all(logged, at);
  // The one-rank pass's order: bond by bond, broken bonds left out.
  double energy = 0, norm = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    std::size_t& next =
        at[static_cast<std::size_t>(owner[static_cast<std::size_t>(bonds.first(b))])];
    if (!bonds.is_broken(b)) {
      energy += bond_all[next];
      norm += bond_all[next + 1];
    }
    next += 2;
  }
  const std::vector<double> particle_all = exchange_->gather_all(particle_values_, at);
  double totals[kWidth] = {};
  for (std::size_t i = 0; i < owner.size(); ++i) {
    std::size_t& next = at[static_cast<std::size_t>(owner[i])];
    for (int w = 0; w < kWidth; ++w) totals[w] += particle_all[next + static_cast<std::size_t>(w)];
    next += kWidth;
  }
  sums[0] = energy;
  sums[1] = norm;
  for (int w = 0; w < kWidth; ++w) sums[2 + w] = totals[w];
}

// The 12 state values of particle i: displacement, rotation, velocity, angular velocity.
void pack_state(const Vector3Array& u, const Vector3Array& theta, const Particles& p, int i,
                double* row) {
  for (int c = 0; c < 3; ++c) {
    row[c] = u(i, c);
    row[3 + c] = theta(i, c);
    row[6 + c] = p.velocity(i, c);
    row[9 + c] = p.angular_velocity(i, c);
  }
}

void ReferenceBackend::share_own_rows(Columns columns) {
  Particles& p = model_.particles;
  std::vector<int> all(static_cast<std::size_t>(p.size()));
  std::iota(all.begin(), all.end(), 0);
  if (columns == kStateColumns) {
    share_particle_rows(
        *part_, *exchange_, all, 12,
        [&](int i, double* row) { pack_state(p.displacement, p.rotation, p, i, row); },
        [&](int i, const double* row) { unpack_particle_state(p, i, row); });
    return;
  }
  share_particle_rows(
      *part_, *exchange_, all, 6,
      [&](int i, double* row) {
        for (int c = 0; c < 3; ++c) {
          row[c] = p.force(i, c);
          row[3 + c] = p.torque(i, c);
        }
      },
      [&](int i, const double* row) {
        for (int c = 0; c < 3; ++c) {
          p.force(i, c) = row[c];
          p.torque(i, c) = row[3 + c];
        }
      });
}

void ReferenceBackend::gather_from_owners(std::span<const int> particles, Particles& into,
                                          bool current) const {
  const Particles& p = model_.particles;
  const Vector3Array& u = current ? p.displacement : previous_displacement_;
  const Vector3Array& theta = current ? p.rotation : previous_rotation_;
  share_particle_rows(
      *part_, *exchange_, particles, 12,
      [&](int i, double* row) { pack_state(u, theta, p, i, row); },
      [&](int i, const double* row) { unpack_particle_state(into, i, row); });
}

AccountArrays ReferenceBackend::shared_account() const {
  AccountArrays a = account_;
  std::vector<int> all(static_cast<std::size_t>(model_.particles.size()));
  std::iota(all.begin(), all.end(), 0);
  share_particle_rows(
      *part_, *exchange_, all, 2,
      [&](int i, double* row) {
        row[0] = account_.work(i);
        row[1] = account_.damping(i);
      },
      [&](int i, const double* row) {
        a.work(i) = row[0];
        a.damping(i) = row[1];
      });
  return a;
}

}  // namespace

std::unique_ptr<KernelBackend> make_reference_backend(const BackendSetup& setup) {
  return std::make_unique<ReferenceBackend>(setup);
}

}  // namespace plydem
