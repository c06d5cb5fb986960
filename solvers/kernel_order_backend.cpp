#include "solvers/kernel_order_backend.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <limits>
#include <map>
#include <mutex>

#include "core/error.hpp"
#include "solvers/device_backend.hpp"
#include "solvers/linear_solver.hpp"

namespace plydem {

KernelOrderBackend::KernelOrderBackend(const BackendSetup& setup)
    : model_(*setup.model),
      history_(*setup.history),
      storage_(setup.strength_storage),
      breaking_(setup.breaking),
      softening_(setup.softening) {
  const Particles& p = model_.particles;
  order_ = plydem::kernel_order(model_, setup.particle_order);
  position_.assign(order_.size(), 0);
  for (std::size_t i = 0; i < order_.size(); ++i) position_[order_[i]] = static_cast<int>(i);
  bonds_ = GatherBonds(model_.bonds, order_, {breaking_, softening_, storage_});
  particles_ = p.size();
  padded_ = bonds_.padded_count();
  blocks_ = padded_ / lanes::kCount;
  const KernelSizes s = sizes();
  // The host's own arrays; the bond table's are the GatherBonds' (view()).
  for_each_kernel_array(
      [&](const ArrayInfo& info, auto& array) {
        if (info.extent == ArrayExtent::kParticles || info.extent == ArrayExtent::kPartials) {
          if (uses(info.use, mode())) array.resize(s.count(info.extent));
        }
      },
      arrays_);
  for (int i = 0; i < padded_; ++i) {
    const bool real = i < particles_;
    arrays_.inverse_mass.data()[i] = real ? 1.0 / p.mass(order_[i]) : 1.0;
    arrays_.inverse_inertia.data()[i] = real ? 1.0 / p.moment_of_inertia(order_[i]) : 1.0;
  }
  arrays_.classes.resize(1);
}

int KernelOrderBackend::mode() const {
  if (!breaking_) return kElasticMode;
  const bool slots = bonds_.slot_strengths();
  return (softening_ ? kSofteningTypes : kBrittleTypes) + (slots ? 1 : 0);
}

KernelSizes KernelOrderBackend::sizes() const {
  KernelSizes s;
  s.particles = particles_;
  s.padded = padded_;
  s.width = bonds_.width();
  s.type_count = bonds_.type_count();
  s.class_count = class_count_;
  s.mode = mode();
  return s;
}

KernelView KernelOrderBackend::view() {
  KernelView v = kernel_view(arrays_);
  // The bond table is the GatherBonds' own, whose block tables follow every change to it; the
  // step reads it through these pointers and changes it through GatherBonds::clear_slot only
  // (a device changes its own copy).
  GatherBonds& g = bonds_;
  v.neighbour = const_cast<std::int32_t*>(g.neighbours(0));
  v.type = const_cast<std::int32_t*>(g.types(0));
  v.types = const_cast<HalfBondType*>(&g.type(0));
  if (breaking_) {
    v.failure = &g.failure(0);
    v.slot_bond = const_cast<std::int32_t*>(g.slot_bonds());
  }
  if (g.slot_strengths()) {
    v.slot_alpha = const_cast<double*>(g.slot_screen_displacement());
    v.slot_beta = const_cast<double*>(g.slot_screen_rotation());
    v.slot_tensile = const_cast<double*>(g.slot_tensile_strengths());
    v.slot_cohesion = const_cast<double*>(g.slot_cohesions());
  }
  if (g.softening()) {
    v.slot_damage = g.slot_damage();
    v.slot_kappa = g.slot_kappa();
  }
  return v;
}

std::size_t KernelOrderBackend::bytes() const {
  std::size_t total = bonds_.bytes() + (order_.size() + position_.size()) * sizeof(int);
  for_each_kernel_array([&](const ArrayInfo&, const auto& array) { total += array.bytes(); },
                        arrays_);
  for (int c = 0; c < 3; ++c) total += contact_force_[c].bytes() + contact_torque_[c].bytes();
  return total + contact_block_.size();
}

void KernelOrderBackend::set_motions(const MotionTable& table) {
  // The motions as classes: one per group that a motion names, and one per particle that a motion
  // names alone (key: the group, or -1 - the particle).
  std::vector<MotionClass> classes(1);
  std::map<int, int> class_of;
  for (const PrescribedMotion& m : table.motions) {
    const int key = m.particle >= 0 ? -1 - m.particle : static_cast<int>(m.group);
    const auto [it, inserted] = class_of.try_emplace(key, static_cast<int>(classes.size()));
    if (inserted) classes.emplace_back();
    MotionClass& cls = classes[static_cast<std::size_t>(it->second)];
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
  constexpr std::size_t kClasses = std::numeric_limits<MotionIndex>::max();
  require(classes.size() <= kClasses,
          fmt::format("{} groups and particles have motions of their own: the kernels hold at most "
                      "{}",
                      classes.size() - 1, kClasses - 1));
  class_count_ = static_cast<int>(classes.size());
  arrays_.classes.resize(classes.size());
  std::copy(classes.begin(), classes.end(), arrays_.classes.data());
  const Particles& p = model_.particles;
  MotionIndex* motion = arrays_.motion.data();
  for (int i = 0; i < particles_; ++i) {
    // A particle's own motion replaces its group's (as ExplicitIntegrator's table has it).
    auto it = class_of.find(-1 - order_[i]);
    if (it == class_of.end()) it = class_of.find(p.group(order_[i]));
    motion[i] = static_cast<MotionIndex>(it == class_of.end() ? 0 : it->second);
  }
}

void KernelOrderBackend::start_breaking(bool softening) {
  breaking_ = true;
  softening_ = softening;
  if (!bonds_.breaking()) bonds_ = GatherBonds(model_.bonds, order_, {true, softening_, storage_});
  for (int c = 0; c < 3; ++c) {
    contact_force_[c] = lanes::Array(padded_);
    contact_torque_[c] = lanes::Array(padded_);
  }
  contact_block_.assign(static_cast<std::size_t>(blocks_), 0);
  arrays_.work_sum.resize(padded_);
  arrays_.damping_sum.resize(padded_);
}

void KernelOrderBackend::load() {
  const Particles& p = model_.particles;
  parity_ = 0;
  for (int c = 0; c < 3; ++c) {
    double* u = arrays_.displacement[0][c].data();
    double* t = arrays_.rotation[0][c].data();
    double* v = arrays_.velocity[c].data();
    double* w = arrays_.angular_velocity[c].data();
    for (int i = 0; i < particles_; ++i) {
      const int m = order_[i];
      u[i] = p.displacement(m, c);
      t[i] = p.rotation(m, c);
      v[i] = p.velocity(m, c);
      w[i] = p.angular_velocity(m, c);
    }
  }
  running_ = true;
}

void KernelOrderBackend::store() {
  Particles& p = model_.particles;
  for (int c = 0; c < 3; ++c) {
    const double* u = arrays_.displacement[parity_][c].data();
    const double* t = arrays_.rotation[parity_][c].data();
    const double* v = arrays_.velocity[c].data();
    const double* w = arrays_.angular_velocity[c].data();
    for (int i = 0; i < particles_; ++i) {
      const int m = order_[i];
      p.displacement(m, c) = u[i];
      p.rotation(m, c) = t[i];
      p.velocity(m, c) = v[i];
      p.angular_velocity(m, c) = w[i];
    }
  }
  running_ = false;
}

void KernelOrderBackend::gather(std::span<const int> particles, Particles& into, StateAt at) const {
  const int buffer = at == StateAt::kCurrent ? parity_ : 1 - parity_;
  for (int i : particles) {
    const int j = position_[i];
    for (int c = 0; c < 3; ++c) {
      into.displacement(i, c) = arrays_.displacement[buffer][c].data()[j];
      into.rotation(i, c) = arrays_.rotation[buffer][c].data()[j];
      into.velocity(i, c) = arrays_.velocity[c].data()[j];
      into.angular_velocity(i, c) = arrays_.angular_velocity[c].data()[j];
    }
  }
}

double KernelOrderBackend::state(int i, int c, bool rotation) const {
  const int j = position_[i];
  return rotation ? arrays_.rotation[parity_][c].data()[j]
                  : arrays_.displacement[parity_][c].data()[j];
}

ContactState KernelOrderBackend::state_at(int parity) const {
  ContactState s;
  for (int c = 0; c < 3; ++c) {
    s.displacement[c] = arrays_.displacement[parity][c].data();
    s.rotation[c] = arrays_.rotation[parity][c].data();
    s.velocity[c] = arrays_.velocity[c].data();
    s.angular_velocity[c] = arrays_.angular_velocity[c].data();
  }
  return s;
}

ContactState KernelOrderBackend::contact_state() const {
  return state_at(parity_);
}

void KernelOrderBackend::touch_contacts(const std::vector<int>& touched) {
  std::fill(contact_block_.begin(), contact_block_.end(), 0);
  for (int i : touched) {
    require(i >= 0 && i / lanes::kCount < blocks_, "a touched contact is out of range");
    contact_block_[static_cast<std::size_t>(i / lanes::kCount)] = 1;
  }
}

void KernelOrderBackend::clear_bond(int bond) {
  const int padded = bonds_.padded_count();
  for (const std::int64_t cell : bonds_.bond_cells(bond)) {
    if (cell < 0 || !bonds_.holds(static_cast<std::size_t>(cell))) continue;
    bonds_.clear_slot(static_cast<int>(cell % padded), static_cast<int>(cell / padded));
  }
}

std::array<BondEnd, 2> KernelOrderBackend::bond_ends(int bond) const {
  const Bonds& bonds = model_.bonds;
  if (!breaking_) {
    const BondEnd end{!bonds.is_broken(bond), bonds.damage(bond), history_.kappa(bond)};
    return {end, end};
  }
  const GatherBonds& g = bonds_;
  std::array<BondEnd, 2> ends;
  const std::array<std::int64_t, 2> cells = g.bond_cells(bond);
  for (int e = 0; e < 2; ++e) {
    if (cells[e] < 0) {
      ends[e] = {false, 1.0, history_.kappa(bond)};
      continue;
    }
    const auto cell = static_cast<std::size_t>(cells[e]);
    ends[e].holds = g.holds(cell);
    ends[e].damage = g.softening() ? g.slot_damage()[cell] : (ends[e].holds ? 0.0 : 1.0);
    ends[e].kappa = g.softening() ? g.slot_kappa()[cell] : 1.0;
  }
  return ends;
}

void KernelOrderBackend::store_bonds(Bonds& bonds, Eigen::ArrayXd& kappa) const {
  if (!breaking_) return;
  write_bonds(bonds, kappa, [&](int b) { return KernelOrderBackend::bond_ends(b); });
}

void KernelOrderBackend::write_bonds(
    Bonds& bonds, Eigen::ArrayXd& kappa,
    const std::function<std::array<BondEnd, 2>(int)>& ends_of) const {
  const GatherBonds& g = bonds_;
  const bool soft = g.softening();
  for (int b = 0; b < bonds.size(); ++b) {
    if (g.bond_cells(b)[0] < 0) continue;  // broken before the table was built
    const std::array<BondEnd, 2> ends = ends_of(b);
    const bool agree =
        ends[0].holds == ends[1].holds && ends[0].holds == !bonds.is_broken(b) &&
        (!soft || (ends[0].damage == ends[1].damage && ends[0].kappa == ends[1].kappa));
    if (!agree) {
      throw Error(fmt::format(
          "internal error: the two ends of bond {} disagree in the kernel (held {} and {}, "
          "damage {:.17g} and {:.17g}, kappa {:.17g} and {:.17g}, model state {})",
          b, ends[0].holds, ends[1].holds, ends[0].damage, ends[1].damage, ends[0].kappa,
          ends[1].kappa, bonds.state(b)));
    }
    if (!soft || !ends[0].holds) continue;
    const double damage = ends[0].damage;
    bonds.damage(b) = damage;
    kappa(b) = ends[0].kappa;
    bonds.normal_stiffness(b) = (1.0 - damage) * history_.intact[0](b);
    bonds.shear_stiffness(b) = (1.0 - damage) * history_.intact[1](b);
    bonds.bending_stiffness(b) = (1.0 - damage) * history_.intact[2](b);
    bonds.twisting_stiffness(b) = (1.0 - damage) * history_.intact[3](b);
  }
}

void KernelOrderBackend::restore_bonds(const Bonds& bonds, const Eigen::ArrayXd& kappa) {
  if (!breaking_) return;
  GatherBonds& g = bonds_;
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

AccountArrays KernelOrderBackend::account() const {
  AccountArrays a;
  const int n = particles_;
  a.work.setZero(n);
  a.damping.setZero(n);
  a.contact_force.setZero(n, 3);
  a.contact_torque.setZero(n, 3);
  if (!breaking_) return a;
  for (int i = 0; i < n; ++i) {
    const int j = position_[i];
    a.work(i) = arrays_.work_sum.data()[j];
    a.damping(i) = arrays_.damping_sum.data()[j];
    for (int c = 0; c < 3; ++c) {
      a.contact_force(i, c) = contact_force_[c][j];
      a.contact_torque(i, c) = contact_torque_[c][j];
    }
  }
  return a;
}

void KernelOrderBackend::set_account(const AccountArrays& a) {
  for (int i = 0; i < particles_; ++i) {
    const int j = position_[i];
    arrays_.work_sum.data()[j] = a.work(i);
    arrays_.damping_sum.data()[j] = a.damping(i);
    for (int c = 0; c < 3; ++c) {
      contact_force_[c][j] = a.contact_force(i, c);
      contact_torque_[c][j] = a.contact_torque(i, c);
    }
  }
}

void KernelOrderBackend::store_report(CycleBatch& batch, bool reduce) {
  Particles& p = model_.particles;
  for (int c = 0; c < 3; ++c) {
    const double* f = arrays_.force[c].data();
    const double* m = arrays_.torque[c].data();
    for (int i = 0; i < particles_; ++i) {
      p.force(order_[i], c) = f[i];
      p.torque(order_[i], c) = m[i];
    }
  }
  if (!reduce) return;
  for (int q = 0; q < kParticlePartials; ++q) {
    double sum = 0;
    for (int b = 0; b < blocks_; ++b) sum += block_partial(arrays_.partial.data(), padded_, q, b);
    batch.sums[q] = sum;
  }
}

namespace {

// The kernel-order state mirrored on a device (solvers/device_backend.hpp): uploaded at the start
// of every run, the state downloaded after every batch of cycles (the run loop's checks and hooks
// read the host copy), the table when bonds can break.
class MirroredBackend final : public KernelOrderBackend {
 public:
  MirroredBackend(const BackendSetup& setup, ExplicitBackend kind)
      : KernelOrderBackend(setup), kind_(kind) {
    device_ = kind == ExplicitBackend::kCuda ? make_cuda_backend() : make_emulation_backend();
  }

  ExplicitBackend kind() const override { return kind_; }

  bool supports_contacts(std::string* why) const override {
    if (why)
      *why = fmt::format(
          "the {} backend has no contacts between unbonded particles yet: a run whose bonds can "
          "break (or that keeps the energy account) needs contacts off "
          "(ExplicitSettings::contacts = false), or backend cpu or reference",
          to_string(kind_));
    return false;
  }

  void set_motions(const MotionTable& table) override {
    KernelOrderBackend::set_motions(table);
    motions_changed_ = true;
  }

  void load() override {
    KernelOrderBackend::load();
    device_->upload(arrays());
    motions_changed_ = false;
  }

  void clear_bond(int bond) override {
    KernelOrderBackend::clear_bond(bond);
    // From a hook: the device holds the run's arrays, and the host copy is current; copy it in.
    if (running_) device_->upload(arrays());
  }

  CycleBatch run_cycles(long cycles, bool report_last, const CycleStep& step) override {
    const DeviceArrays host = arrays();
    if (motions_changed_) {
      device_->upload_motions(host);
      motions_changed_ = false;
    }
    DeviceBatch ran =
        device_->run_cycles(cycles, parity_, report_last, step.first_cycle, step.dt, step.alpha);
    parity_ = static_cast<int>((parity_ + ran.cycles) & 1);
    device_->download_state(host);
    CycleBatch batch;
    batch.cycles = ran.cycles;
    batch.reported = ran.reported;
    if (breaking_) {
      // The slots the device emptied are emptied here too (with their blocks' tables).
      device_->download_table(host, types_);
      const std::size_t padded = static_cast<std::size_t>(bonds_.padded_count());
      for (std::size_t cell = 0; cell < types_.size(); ++cell)
        if (types_[cell] == 0 && bonds_.holds(cell))
          bonds_.clear_slot(static_cast<int>(cell % padded), static_cast<int>(cell / padded));
      batch.events = std::move(ran.events);
    }
    if (batch.reported) {
      std::copy(ran.sums, ran.sums + kParticlePartials, batch.sums);  // reduced on the device
      store_report(batch, false);
    }
    return batch;
  }

  std::size_t bytes() const override { return KernelOrderBackend::bytes() + types_.size() * 4; }

 private:
  DeviceArrays arrays() { return {view(), sizes()}; }

  ExplicitBackend kind_;
  std::unique_ptr<DeviceBackend> device_;
  std::vector<std::int32_t> types_;  // the table's types as the device holds them
  bool motions_changed_ = false;
};

}  // namespace

std::unique_ptr<KernelBackend> make_mirrored_backend(const BackendSetup& setup,
                                                     ExplicitBackend kind) {
  return std::make_unique<MirroredBackend>(setup, kind);
}

std::unique_ptr<KernelBackend> make_kernel_backend(ExplicitBackend kind,
                                                   const BackendSetup& setup) {
  if (setup.split_between_ranks) {
    require(kind == ExplicitBackend::kCpu || kind == ExplicitBackend::kReference,
            fmt::format("the {} backend runs on one MPI rank only: under mpiexec the explicit "
                        "engine splits the particles between the ranks with the cpu or reference "
                        "backend",
                        to_string(kind)));
    static std::once_flag said;
    std::call_once(said, [&] {
      spdlog::info(
          "explicit dynamics on {} MPI ranks: each runs the {} backend over its slice of the {} "
          "particles; the same bits as that backend on one rank",
          mpi_size(), to_string(kind), setup.model->particles.size());
    });
    if (kind == ExplicitBackend::kReference) return make_reference_backend(setup);
    return make_cpu_backend(setup);
  }
  switch (kind) {
    case ExplicitBackend::kReference:
      return make_reference_backend(setup);
    case ExplicitBackend::kCuda:
    case ExplicitBackend::kDeviceEmulation:
      return make_mirrored_backend(setup, kind);
    case ExplicitBackend::kCpu:
      break;
  }
  return make_cpu_backend(setup);
}

}  // namespace plydem
