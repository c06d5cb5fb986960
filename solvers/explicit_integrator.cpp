#include "solvers/explicit_integrator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <string_view>

#include "contacts/bond_opening.hpp"
#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/rank_exchange.hpp"

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
  require(settings.backend == ExplicitBackend::kCpu || settings.backend == ExplicitBackend::kCuda ||
              settings.backend == ExplicitBackend::kDeviceEmulation ||
              settings.backend == ExplicitBackend::kReference,
          "the backend is no ExplicitBackend");
  require(settings.strength_storage == StrengthStorage::kAutomatic ||
              settings.strength_storage == StrengthStorage::kTypes ||
              settings.strength_storage == StrengthStorage::kSlots,
          "the strength storage is no StrengthStorage");
}

bool splits_between_ranks(const ExplicitSettings& settings) {
  return settings.split_between_ranks && mpi_size() > 1;
}

namespace {

// The bonds' intact stiffnesses (the arrays hold 1 - damage times them; unknown, 0, for a bond
// that came broken) and softening histories, and what the model asks of the kernel.
struct BondsAsGiven {
  bool broken = false, damaged = false, softening = false;
};

BondsAsGiven read_history(const Bonds& bonds, BondHistory& h) {
  for (Eigen::ArrayXd& k : h.intact) k.setZero(bonds.size());
  h.kappa.setOnes(bonds.size());
  BondsAsGiven given;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) {
      given.broken = true;
      continue;
    }
    const double scale = 1.0 / (1.0 - bonds.damage(b));
    h.intact[0](b) = scale * bonds.normal_stiffness(b);
    h.intact[1](b) = scale * bonds.shear_stiffness(b);
    h.intact[2](b) = scale * bonds.bending_stiffness(b);
    h.intact[3](b) = scale * bonds.twisting_stiffness(b);
    given.damaged |= bonds.damage(b) > 0;
    const bool breakable =
        std::isfinite(bonds.tensile_strength(b)) || std::isfinite(bonds.cohesion(b));
    const BondStrength strength = bond_strength(bonds, b);
    given.softening |= breakable && may_soften(strength);
    h.kappa(b) = softening_history(bonds.damage(b), strength);
  }
  return given;
}

// The critical time step; a damaged or broken bond's contact is as stiff as the intact bond: the
// time step is theirs.
double time_step_of(const Model& model, const BondHistory& h, const BondsAsGiven& given,
                    const ExplicitSettings& settings) {
  double critical = 0;
  if (given.broken || given.damaged) {
    Model intact = model;
    intact.bonds.normal_stiffness = h.intact[0];
    intact.bonds.shear_stiffness = h.intact[1];
    intact.bonds.bending_stiffness = h.intact[2];
    intact.bonds.twisting_stiffness = h.intact[3];
    critical = critical_time_step(intact);
  } else {
    critical = critical_time_step(model);
  }
  if (settings.time_step > 0) {
    require(settings.time_step <= critical,
            fmt::format("time step {:.3e} s exceeds the critical time step {:.3e} s: the explicit "
                        "scheme would be unstable",
                        settings.time_step, critical));
    return settings.time_step;
  }
  return settings.safety_factor * critical;
}

}  // namespace

ExplicitIntegrator::ExplicitIntegrator(Model& model, const ExplicitSettings& settings)
    : model_(model), settings_(settings), history_(std::make_unique<BondHistory>()) {
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
  const BondsAsGiven given = read_history(model.bonds, *history_);
  breaking_ = model.bonds.breakable() || given.broken || settings.energy_account;
  softening_ = breaking_ && (given.softening || given.damaged);
  time_step_ = time_step_of(model, *history_, given, settings);
  BackendSetup setup;
  setup.model = &model;
  setup.history = history_.get();
  setup.breaking = breaking_;
  setup.softening = softening_;
  setup.strength_storage = settings.strength_storage;
  setup.particle_order = settings.particle_order;
  setup.split_between_ranks = splits_between_ranks(settings);
  backend_ = make_kernel_backend(settings.backend, setup);
  set_prescribed_motions({});
  if (breaking_) start_breaking();
}

ExplicitIntegrator::~ExplicitIntegrator() = default;
ExplicitIntegrator::ExplicitIntegrator(ExplicitIntegrator&&) noexcept = default;

void ExplicitIntegrator::start_breaking() {
  breaking_ = true;
  backend_->start_breaking(softening_);
  initial_set_ = false;
  make_contacts();
}

void ExplicitIntegrator::make_contacts() {
  if (!settings_.contacts) return;
  std::string why;
  require(backend_->supports_contacts(&why), why);
  if (!running_) backend_->load();  // the contacts read the state in the backend's numbering
  contacts_ = std::make_unique<UnbondedContacts>(model_, history_->intact[0], history_->intact[1],
                                                 backend_->contact_index(), settings_.contact,
                                                 backend_->contact_state());
  if (!running_) backend_->store();
  contact_countdown_ = 0;
}

void ExplicitIntegrator::set_prescribed_motions(const std::vector<PrescribedMotion>& motions) {
  const Particles& p = model_.particles;
  const int n = p.size();
  MotionTable& t = motions_;
  t.fixed_velocity.setConstant(n, 3, false);
  t.fixed_angular_velocity.setConstant(n, 3, false);
  t.velocity.setZero(n, 3);
  t.angular_velocity.setZero(n, 3);
  // A particle's own motion replaces its group's.
  std::vector<bool> own(static_cast<std::size_t>(n), false);
  for (const PrescribedMotion& m : motions) {
    require(m.particle < n,
            fmt::format("a prescribed motion names particle {} of a model of {}", m.particle, n));
    if (m.particle >= 0) own[static_cast<std::size_t>(m.particle)] = true;
  }
  for (const PrescribedMotion& m : motions) {
    require(m.velocity.allFinite() && m.angular_velocity.allFinite(),
            "a prescribed velocity is not finite");
    for (int i = 0; i < n; ++i) {
      const bool applies = m.particle >= 0 ? i == m.particle
                                           : !own[static_cast<std::size_t>(i)] &&
                                                 p.group(i) == static_cast<int>(m.group);
      if (!applies) continue;
      for (int c = 0; c < 3; ++c) {
        if (m.fix_velocity[c]) {
          t.fixed_velocity(i, c) = true;
          t.velocity(i, c) = m.velocity(c);
        }
        if (m.fix_angular_velocity[c]) {
          t.fixed_angular_velocity(i, c) = true;
          t.angular_velocity(i, c) = m.angular_velocity(c);
        }
      }
    }
  }
  t.motions = motions;
  free_particles_ = 0;
  for (int i = 0; i < n; ++i) free_particles_ += t.fixed_velocity.row(i).any() ? 0 : 1;
  backend_->set_motions(t);
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
  for (const RunHook& hook : hooks) {
    require(hook.every_cycles >= 0,
            fmt::format("a hook's period must be >= 0 cycles (0 = every check), got {}",
                        hook.every_cycles));
    require(std::isfinite(hook.every_seconds) && hook.every_seconds >= 0,
            fmt::format("a hook's period must be >= 0 s, got {}", hook.every_seconds));
    require(static_cast<bool>(hook.call), "a hook has nothing to call");
  }
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

void ExplicitIntegrator::start_account() {
  Particles now = model_.particles;
  std::vector<int> all(static_cast<std::size_t>(now.size()));
  std::iota(all.begin(), all.end(), 0);
  gather(all, now);
  double kinetic = 0;
  for (int i = 0; i < now.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      if (!motions_.fixed_velocity(i, c))
        kinetic += now.mass(i) * now.velocity(i, c) * now.velocity(i, c);
      if (!motions_.fixed_angular_velocity(i, c))
        kinetic +=
            now.moment_of_inertia(i) * now.angular_velocity(i, c) * now.angular_velocity(i, c);
    }
  initial_energy_ = bond_strain_energy(now, model_.bonds) + 0.5 * kinetic;
  initial_set_ = true;
}

CycleReport ExplicitIntegrator::step(long cycles) {
  const double dt = time_step_;
  if (breaking_ && !initial_set_) start_account();
  released_ += released_pending_;
  released_pending_ = 0;
  CycleStep args;
  args.dt = dt;
  args.alpha = settings_.local_damping;
  args.contacts = contacts_.get();
  CycleBatch last;
  long remaining = cycles;
  while (remaining > 0) {
    if (contacts_ && contact_countdown_ <= 0)
      contact_countdown_ = contacts_->check(backend_->contact_state(), dt);
    const long chunk = contacts_ ? std::min(remaining, contact_countdown_) : remaining;
    args.first_cycle = cycles_;
    CycleBatch batch = backend_->run_cycles(chunk, chunk == remaining, args);
    const long ran = batch.cycles;
    remaining -= ran;
    if (contacts_) contact_countdown_ -= ran;
    for (long c = 0; c < ran; ++c) time_ += dt;  // as many additions as cycles, however chunked
    cycles_ += ran;
    if (breaking_) resolve_events(batch.events, remaining == 0 ? cycles_ - 1 : -1);
    if (batch.reported) last = std::move(batch);
  }
  const double* sums = last.sums;
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
  // The state now is the one after each event's cycle (batches stop after a cycle with steps).
  const Bonds& bonds = model_.bonds;
  const KernelBackend& k = *backend_;
  for (const SlotEvent& e : events) {
    const int b = e.bond, i = bonds.first(b), j = bonds.second(b);
    double n[3], a[3], dtheta[3], du[3];
    for (int c = 0; c < 3; ++c) {
      n[c] = bonds.normal(b, c);
      a[c] =
          bonds.lever_first(b) * k.state(i, c, true) + bonds.lever_second(b) * k.state(j, c, true);
      dtheta[c] = k.state(j, c, true) - k.state(i, c, true);
    }
    for (int c = 0; c < 3; ++c) {
      const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      du[c] = (k.state(j, c, false) - k.state(i, c, false)) - (a[c1] * n[c2] - a[c2] * n[c1]);
    }
    double product = 0;  // q_n K q_n+1
    for (int c = 0; c < 3; ++c) product += e.force[c] * du[c] + e.moment[c] * dtheta[c];
    double released = 0.5 * (e.damage_after - e.damage_before) * product;
    if (e.broken && contacts_)
      released -= contacts_->handover(b, backend_->contact_state(), time_step_);
    (e.cycle == report_cycle ? released_pending_ : released_) += released;
    if (e.broken) log_break(b, e.mode, e.cycle, e.displacement);
  }
}

void ExplicitIntegrator::store_bonds() {
  backend_->store_bonds(model_.bonds, history_->kappa);
}

EnergyAccount ExplicitIntegrator::energy() const {
  EnergyAccount e;
  if (!breaking_) return e;
  e.initial = initial_energy_;
  e.strain_energy = last_report_.strain_energy;
  e.kinetic_energy = last_report_.kinetic_energy;
  const double half_step = 0.5 * time_step_;
  const AccountArrays a = backend_->account();
  e.released = released_;
  e.boundary_work = half_step * a.work.sum() - pending_work_;
  e.damping = half_step * a.damping.sum() - pending_damping_;
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
  return backend_->bond_ends(bond);
}

namespace {

// The estimate of the seconds left at a check of run(): the least of the cycles left, the ratio's
// exponential decay between the last two checks, the wall-time limit; negative when none gives one.
struct Estimate {
  long previous_cycles = 0;
  double previous_ratio = 0;

  double seconds_left(const RunControl& control, const RunReport& report, double elapsed) {
    double best = -1;
    auto consider = [&](double left) {
      if (left >= 0 && (best < 0 || left < best)) best = left;
    };
    const double ratio = report.last.unbalanced_force_ratio;
    const double per_cycle =
        (report.kernel_seconds + report.check_seconds) / static_cast<double>(report.cycles);
    if (control.max_cycles > 0)
      consider(static_cast<double>(control.max_cycles - report.cycles) * per_cycle);
    if (control.tolerance > 0 && previous_cycles > 0 && ratio < previous_ratio &&
        ratio > control.tolerance) {
      const double decay =
          std::log(previous_ratio / ratio) / static_cast<double>(report.cycles - previous_cycles);
      consider(std::log(ratio / control.tolerance) / decay * per_cycle);
    }
    if (control.time_limit_seconds > 0)
      consider(std::max(0.0, control.time_limit_seconds - elapsed));
    previous_cycles = report.cycles;
    previous_ratio = ratio;
    return best;
  }
};

// The hooks of a run: RunControl::on_check (every check), RunControl::hooks, and
// RunControl::on_progress (every progress_seconds), with when each was last called.
class Hooks {
 public:
  explicit Hooks(const RunControl& control) : control_(control) {
    if (control.on_check) all_.push_back({0, 0, control.on_check});
    all_.insert(all_.end(), control.hooks.begin(), control.hooks.end());
    if (control.on_progress) {
      all_.push_back({0, control.progress_seconds, [&control](const RunCheck& check) {
                        control.on_progress(check);
                        return true;
                      }});
    }
    last_cycles_.assign(all_.size(), 0);
    last_seconds_.assign(all_.size(), 0.0);
  }

  // The cycles of the next chunk, from `done` cycles of the run: at most the check interval and
  // the cycles left, and ending where a hook with a cycle period falls due.
  long next_chunk(long done) const {
    long chunk = control_.check_interval;
    if (control_.max_cycles > 0) chunk = std::min(chunk, control_.max_cycles - done);
    for (std::size_t h = 0; h < all_.size(); ++h) {
      const long every = all_[h].every_cycles;
      if (every > 0) chunk = std::min(chunk, last_cycles_[h] + every - done);
    }
    return std::max(1L, chunk);
  }

  // Calls the hooks due at this check; false if one asked to stop. The time since a hook's last
  // call is counted on the check's clock (RunCheck::elapsed_seconds, the same on every MPI rank,
  // so that every rank calls the same hooks: they may gather from the ranks).
  bool call(const RunCheck& check) {
    bool go_on = true;
    for (std::size_t h = 0; h < all_.size(); ++h) {
      const RunHook& hook = all_[h];
      if (hook.every_cycles > 0 && check.run_cycles < last_cycles_[h] + hook.every_cycles) continue;
      if (hook.every_seconds > 0 && check.elapsed_seconds - last_seconds_[h] <= hook.every_seconds)
        continue;
      last_cycles_[h] = check.run_cycles;
      last_seconds_[h] = check.elapsed_seconds;
      go_on &= hook.call(check);
    }
    return go_on;
  }

 private:
  const RunControl& control_;
  std::vector<RunHook> all_;
  std::vector<long> last_cycles_;
  std::vector<double> last_seconds_;
};

}  // namespace

RunReport ExplicitIntegrator::run(const RunControl& control) {
  using Clock = Stopwatch::Clock;
  require(!running_, "run() was called from one of its own hooks");
  control.validate();
  const Clock::time_point start = Clock::now();
  RunReport report;
  running_ = true;
  backend_->load();
  // The model gets the state back however the run ends (an exception from a hook included).
  struct Finish {
    ExplicitIntegrator& integrator;
    RunReport& report;
    Clock::time_point start;
    ~Finish() {
      const Clock::time_point t = Clock::now();
      integrator.backend_->store();
      integrator.running_ = false;
      report.transfer_seconds += seconds_between(t, Clock::now());
      report.wall_seconds = seconds_since(start);
    }
  } finish{*this, report, start};
  report.transfer_seconds = seconds_since(start);

  Hooks hooks(control);
  Estimate estimate;
  while (true) {
    const long chunk = hooks.next_chunk(report.cycles);
    const Clock::time_point kernel_start = Clock::now();
    report.last = step(chunk);
    const Clock::time_point check_start = Clock::now();
    report.kernel_seconds += seconds_between(kernel_start, check_start);
    report.cycles += chunk;
    ++report.checks;

    RunCheck check;
    check.cycles = cycles_;
    check.run_cycles = report.cycles;
    check.report = report.last;
    // Under mpiexec the slowest rank's clock, so that every rank makes the same decisions.
    check.elapsed_seconds = max_over_ranks(seconds_between(start, check_start));
    check.seconds_left = estimate.seconds_left(control, report, check.elapsed_seconds);
    const bool go_on = hooks.call(check);
    const Clock::time_point check_end = Clock::now();
    report.check_seconds += seconds_between(check_start, check_end);
    const double ratio = report.last.unbalanced_force_ratio;
    if (control.tolerance > 0 && ratio <= control.tolerance) {
      report.stop = RunStop::kQuasiStatic;
      break;
    }
    if (control.max_cycles > 0 && report.cycles >= control.max_cycles) {
      report.stop = RunStop::kCycleLimit;
      break;
    }
    if (control.time_limit_seconds > 0 &&
        max_over_ranks(seconds_between(start, check_end)) >= control.time_limit_seconds) {
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
  if (running_) {
    backend_->gather(particles, into, at);
  } else if (!own) {
    for (int i : particles) {
      into.displacement.row(i) = p.displacement.row(i);
      into.rotation.row(i) = p.rotation.row(i);
      into.velocity.row(i) = p.velocity.row(i);
      into.angular_velocity.row(i) = p.angular_velocity.row(i);
    }
  }
  if (!own) {
    for (int i : particles) {
      into.force.row(i) = p.force.row(i);
      into.torque.row(i) = p.torque.row(i);
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
  backend_->clear_bond(bond);
  open_bond(bonds, bond, mode);
  if (contacts_) {
    contacts_->add_broken_bond(bond);
    contact_countdown_ = 0;
  }
}

std::size_t ExplicitIntegrator::kernel_bytes() const {
  return backend_->bytes();
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
  out.boolean(backend_->kernel_order());
  out.f64(time_step_);
  out.f64(time_);
  out.i64(cycles_);
  out.boolean(breaking_);
  out.boolean(softening_);
  Model state = model_;
  std::vector<int> all(static_cast<std::size_t>(state.particles.size()));
  std::iota(all.begin(), all.end(), 0);
  gather(all, state.particles);
  Eigen::ArrayXd kappa = history_->kappa;
  backend_->store_bonds(state.bonds, kappa);  // what run() would write back at this point
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
    const AccountArrays a = backend_->account();
    out.array(a.work);
    out.array(a.damping);
    out.array(a.contact_force);
    out.array(a.contact_torque);
  }
  out.boolean(contacts_ != nullptr);
  if (contacts_) contacts_->save(out);
  out.i64(contact_countdown_);
}

void ExplicitIntegrator::restore_account(CheckpointReader& in, int n) {
  AccountArrays a;
  in.array(a.work);
  in.array(a.damping);
  in.array(a.contact_force);
  in.array(a.contact_torque);
  if (a.work.size() != n || a.damping.size() != n || a.contact_force.rows() != n ||
      a.contact_torque.rows() != n)
    in.corrupt("the energy account has the wrong size");
  backend_->set_account(a);
}

void ExplicitIntegrator::restore(CheckpointReader& in) {
  require(!running_, "restore() was called during a run");
  const std::string& file = in.file();
  in.section("explicit");
  const bool kernel_order = in.boolean();
  auto layout = [](bool k) { return k ? "kernel order (cpu, emulation, cuda)" : "reference"; };
  if (kernel_order != backend_->kernel_order())
    throw Error(fmt::format("checkpoint {} is for another run: backend is {} there, {} here", file,
                            layout(kernel_order), layout(backend_->kernel_order())));
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
    try {
      backend_->touch_contacts(contacts_->touched());
    } catch (const Error&) {
      in.corrupt("a touched contact is out of range");
    }
  }
  contact_countdown_ = in.i64();

  backend_->restore_bonds(state.bonds, kappa);
  model_.particles = std::move(state.particles);
  model_.bonds = std::move(state.bonds);
  history_->kappa = std::move(kappa);
  breaks_ = std::move(breaks);
  time_ = time;
  cycles_ = cycles;
}

}  // namespace plydem
