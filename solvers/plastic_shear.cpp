#include "solvers/plastic_shear.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "contacts/bond_kernel.hpp"
#include "contacts/bond_opening.hpp"
#include "contacts/site_failure.hpp"
#include "core/error.hpp"
#include "core/parallel_bond.hpp"
#include "core/shear_curve.hpp"
#include "core/stopwatch.hpp"

namespace plydem {

void PlasticShearSettings::validate() const {
  require(steps >= 2, fmt::format("plastic shear: steps must be at least 2 (got {})", steps));
  require(std::isfinite(tolerance) && tolerance > 0,
          fmt::format("plastic shear: tolerance must be positive (got {})", tolerance));
  require(max_iterations >= 1,
          fmt::format("plastic shear: max_iterations must be at least 1 (got {})", max_iterations));
  require(std::isfinite(peak_tolerance) && peak_tolerance > 0 && peak_tolerance < 1,
          fmt::format("plastic shear: peak_tolerance must lie in (0, 1) (got {})", peak_tolerance));
  require(!material_point.material.shear_curve.empty(),
          fmt::format("plastic shear: material '{}' has no shear_curve to follow",
                      material_point.material.name));
  require(!material_point.ply_angles.empty(), "plastic shear: no ply angles given");
  require(!material_point.softening,
          "plastic shear ends at its first crack, which opens brittle: softening does not apply");
}

namespace {

using Clock = Stopwatch::Clock;

// The in-plane strain tensor (coupon axes) of an engineering shear strain gamma in the axes of a
// ply whose fibre lies at `angle` from x: gamma / 2 (e1 e2^T + e2 e1^T).
Eigen::Matrix2d plastic_strain_tensor(double gamma, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Eigen::Matrix2d e;
  e << -gamma * s * c, 0.5 * gamma * (c * c - s * s), 0.5 * gamma * (c * c - s * s), gamma * s * c;
  return e;
}

Eigen::Vector3d row3(const Vector3Array& a, int i) {
  return {a(i, 0), a(i, 1), a(i, 2)};
}

class PlasticShearRun {
 public:
  PlasticShearRun(Model& model, const DofConstraints& unit, const DofFlags& reaction_dofs,
                  const PlasticShearSettings& settings)
      : model_(model),
        reaction_dofs_(reaction_dofs),
        settings_(settings),
        mp_(settings.material_point),
        law_(mp_.material),
        system_(model, unit, direct(settings.static_settings)),
        start_(Clock::now()) {
    const int n = model.particles.size();
    require(reaction_dofs.rows() == n && reaction_dofs.cols() == kDofsPerParticle,
            "plastic shear: the reaction dofs are not the model's");
    system_.solve(model_, unit.value);
    unit_u_ = particle_state_vector(model_.particles);
    u0_ = Eigen::VectorXd::Zero(unit_u_.size());
    const DofFlags& fixed = system_.constraints().fixed;
    judged_.assign(static_cast<std::size_t>(n), false);
    for (int i = 0; i < n; ++i)
      judged_[static_cast<std::size_t>(i)] =
          !fixed(i, static_cast<int>(Dof::kUx)) && !fixed(i, static_cast<int>(Dof::kUy));
    gamma_.assign(static_cast<std::size_t>(n), 0.0);
    kappa_.assign(static_cast<std::size_t>(n), 0.0);
    yield_.assign(static_cast<std::size_t>(n), 0.0);
    offsets_.assign(static_cast<std::size_t>(model.bonds.size()), Eigen::Vector3d::Zero());
  }

  PlasticShearResult run() {
    PlasticShearResult r;
    EventsResult& e = r.events;
    // The estimate of failure: the elastic first failure, stretched by the law's strain at S12.
    write_state(0);
    const double elastic = first_failure(1.0);
    require(std::isfinite(elastic),
            "plastic shear: no site of the coupon is loaded by the unit load (nothing can fail)");
    const double s12 = mp_.material.strength.S12;
    const double stretch =
        s12 > 0 ? std::max(1.0, law_.shear_modulus() * law_.strain_at(s12) / s12) : 1.0;
    const double step = elastic * stretch / settings_.steps;
    double lambda = 0;
    for (int k = 1;; ++k) {
      require(k <= 4 * settings_.steps,
              "plastic shear: no site failed up to 4 times the estimate of failure");
      const State before = state();
      const double next = k * step;
      equilibrate(next, r);
      if (first_failure(next) > 1.0) {
        lambda = next;
        record(next, r, true);
        plastic_work_step(before, r);
        continue;
      }
      // The step crosses the first crack: bisect it from the state before it.
      double low = lambda, high = next;
      while (high - low > settings_.peak_tolerance * high) {
        const double mid = 0.5 * (low + high);
        restore(before);
        equilibrate(mid, r);
        (first_failure(mid) > 1.0 ? low : high) = mid;
      }
      restore(before);
      equilibrate(high, r);
      plastic_work_step(before, r);
      crack(high, r);
      break;
    }
    e.solves = solves_;
    e.factorizations = system_.factorizations();
    e.wall_seconds = seconds_since(start_);
    r.plastic_shear = gamma_;
    if (settings_.on_progress) settings_.on_progress(progress(lambda, e));
    return r;
  }

 private:
  struct State {
    std::vector<double> gamma, kappa, yield;
    Eigen::VectorXd u0;
  };

  static StaticSettings direct(StaticSettings s) {
    if (s.method == StaticMethod::kAuto) s.method = StaticMethod::kDirect;
    require(s.method == StaticMethod::kDirect,
            "plastic shear solves the bonds' free offsets with one factor of the stiffness: the "
            "direct method only");
    return s;
  }

  State state() const { return {gamma_, kappa_, yield_, u0_}; }
  void restore(const State& s) {
    gamma_ = s.gamma;
    kappa_ = s.kappa;
    yield_ = s.yield;
    u0_ = s.u0;
    update_offsets();
  }

  // The particles at load factor lambda: lambda u_unit + u0.
  void write_state(double lambda) {
    Particles& p = model_.particles;
    for (int i = 0; i < p.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        p.displacement(i, c) =
            lambda * unit_u_(kDofsPerParticle * i + c) + u0_(kDofsPerParticle * i + c);
        p.rotation(i, c) =
            lambda * unit_u_(kDofsPerParticle * i + 3 + c) + u0_(kDofsPerParticle * i + 3 + c);
      }
  }

  // Each bond's free offset from its ends' plastic strains (see the file comment); a held
  // particle takes the mean plastic strain of the judged sites it is bonded to.
  void update_offsets() {
    const Particles& p = model_.particles;
    const Bonds& bonds = model_.bonds;
    std::vector<double> held_sum(gamma_.size(), 0.0), held_count(gamma_.size(), 0.0);
    for (int b = 0; b < bonds.size(); ++b) {
      if (bonds.is_broken(b)) continue;
      const auto i = static_cast<std::size_t>(bonds.first(b));
      const auto j = static_cast<std::size_t>(bonds.second(b));
      if (!judged_[i] && judged_[j]) {
        held_sum[i] += gamma_[j];
        held_count[i] += 1;
      }
      if (!judged_[j] && judged_[i]) {
        held_sum[j] += gamma_[i];
        held_count[j] += 1;
      }
    }
    auto plastic = [&](int particle) {
      const auto k = static_cast<std::size_t>(particle);
      if (judged_[k]) return gamma_[k];
      return held_count[k] > 0 ? held_sum[k] / held_count[k] : 0.0;
    };
    for (int b = 0; b < bonds.size(); ++b) {
      const int i = bonds.first(b), j = bonds.second(b);
      const double gi = plastic(i), gj = plastic(j);
      Eigen::Vector3d& offset = offsets_[static_cast<std::size_t>(b)];
      if (gi == 0 && gj == 0) {
        offset.setZero();
        continue;
      }
      const Eigen::Matrix2d strain =
          0.5 * (plastic_strain_tensor(gi, angle(i)) + plastic_strain_tensor(gj, angle(j)));
      const Eigen::Vector2d branch =
          (p.reference_position.row(j).head<2>() - p.reference_position.row(i).head<2>())
              .transpose();
      offset.head<2>() = strain * branch;
      offset.z() = 0;
    }
  }

  double angle(int particle) const {
    return mp_.ply_angles[static_cast<std::size_t>(model_.particles.ply(particle))];
  }

  // u0: the free dofs under the bonds' free offsets' load K q_p (prescribed dofs at zero).
  void solve_offsets() {
    const Bonds& bonds = model_.bonds;
    Eigen::VectorXd load = Eigen::VectorXd::Zero(unit_u_.size());
    const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
    for (int b = 0; b < bonds.size(); ++b) {
      const Eigen::Vector3d& offset = offsets_[static_cast<std::size_t>(b)];
      if (bonds.is_broken(b) || offset.isZero(0)) continue;
      const BondResponse q =
          parallel_bond_response(bond_parameters(bonds, b), zero, zero, offset, zero);
      const int i = kDofsPerParticle * bonds.first(b), j = kDofsPerParticle * bonds.second(b);
      load.segment<3>(i) -= q.force_on_first;
      load.segment<3>(j) += q.force_on_first;
      load.segment<3>(i + 3) -= q.torque_on_first;
      load.segment<3>(j + 3) -= q.torque_on_second;
    }
    const std::vector<int>& free = system_.free_dofs();
    Eigen::MatrixXd rhs(static_cast<Eigen::Index>(free.size()), 1);
    for (std::size_t f = 0; f < free.size(); ++f)
      rhs(static_cast<Eigen::Index>(f), 0) = load(free[f]);
    system_.solve_free_in_place(rhs);
    u0_.setZero();
    for (std::size_t f = 0; f < free.size(); ++f)
      u0_(free[f]) = rhs(static_cast<Eigen::Index>(f), 0);
    ++solves_;
  }

  // The sites' return onto the law at load factor lambda, to convergence.
  void equilibrate(double lambda, PlasticShearResult& r) {
    const double g12 = law_.shear_modulus();
    double largest = 0;
    for (int iteration = 0; iteration < settings_.max_iterations; ++iteration) {
      write_state(lambda);
      const std::vector<PlyStress> stress =
          site_ply_stresses(model_.particles, model_.bonds, mp_.ply_angles, mp_.material, gamma_);
      largest = 0;
      for (std::size_t k = 0; k < stress.size(); ++k) {
        if (!judged_[k] || !std::isfinite(stress[k].tau12)) continue;
        const double trial = std::abs(stress[k].tau12);
        const double strain = trial / g12 + kappa_[k];
        const double tau = law_.stress_at(strain);
        const double grows = strain - tau / g12 - kappa_[k];
        if (!(grows > 0)) continue;
        kappa_[k] += grows;
        yield_[k] = tau;
        gamma_[k] += std::copysign(grows, stress[k].tau12);
        largest = std::max(largest, grows);
        ++r.iterations;
      }
      if (largest <= settings_.tolerance) return;
      update_offsets();
      solve_offsets();
      report_progress(lambda, r.events);
    }
    throw Error(fmt::format(
        "plastic shear: the sites' return onto the shear law did not converge at load factor {} "
        "in {} iterations (the last changed a plastic strain by {:.3g}, tolerance {:.3g})",
        lambda, settings_.max_iterations, largest, settings_.tolerance));
  }

  // The smallest load factor of the judged sites' failure at load factor lambda's state (of their
  // current stress: <= 1, a site has failed).
  double first_failure(double lambda) {
    write_state(lambda);
    const std::vector<SiteFailure> sites = judged_sites();
    double smallest = std::numeric_limits<double>::infinity();
    for (const SiteFailure& s : sites) smallest = std::min(smallest, s.failure.load_factor);
    return smallest;
  }

  std::vector<SiteFailure> judged_sites() const {
    std::vector<SiteFailure> sites =
        site_failures(model_.particles, model_.bonds, mp_.ply_angles, mp_.criterion, mp_.material,
                      mp_.strength_factors, gamma_);
    for (std::size_t k = 0; k < sites.size(); ++k)
      if (!judged_[k]) sites[k].failure.load_factor = std::numeric_limits<double>::infinity();
    return sites;
  }

  // The plastic work of the step from `before` to the current state: V tau12 d(kappa) at each
  // site, tau12 the mean of its yield stresses before and after (the trapezoid rule).
  void plastic_work_step(const State& before, PlasticShearResult& r) const {
    for (std::size_t k = 0; k < kappa_.size(); ++k) {
      const double grown = kappa_[k] - before.kappa[k];
      if (grown > 0)
        r.plastic_work += model_.particles.volume(static_cast<int>(k)) * 0.5 *
                          (yield_[k] + before.yield[k]) * grown;
    }
  }

  // The bonds' generalized forces at the current state (free offsets included) into the
  // particles; returns the strain energy.
  double write_forces() {
    Particles& p = model_.particles;
    const Bonds& bonds = model_.bonds;
    p.force.setZero();
    p.torque.setZero();
    double energy = 0;
    for (int b = 0; b < bonds.size(); ++b) {
      if (bonds.is_broken(b)) continue;
      const int i = bonds.first(b), j = bonds.second(b);
      const BondResponse q = parallel_bond_response(
          bond_parameters(bonds, b), row3(p.displacement, i), row3(p.rotation, i),
          row3(p.displacement, j) - offsets_[static_cast<std::size_t>(b)], row3(p.rotation, j));
      for (int c = 0; c < 3; ++c) {
        p.force(i, c) += q.force_on_first(c);
        p.force(j, c) -= q.force_on_first(c);
        p.torque(i, c) += q.torque_on_first(c);
        p.torque(j, c) += q.torque_on_second(c);
      }
      energy += q.energy;
    }
    return energy;
  }

  double reaction() const {
    const Particles& p = model_.particles;
    double sum = 0;
    for (int i = 0; i < p.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        if (reaction_dofs_(i, c)) sum -= p.force(i, c);
        if (reaction_dofs_(i, 3 + c)) sum -= p.torque(i, c);
      }
    return sum;
  }

  // A point of the path at load factor lambda (the current state).
  EventPoint& record(double lambda, PlasticShearResult& r, bool load_step) {
    EventsResult& e = r.events;
    write_state(lambda);
    EventPoint point;
    point.event = static_cast<long>(e.path.size()) + 1;
    point.load_factor = lambda;
    point.strain_energy = write_forces();
    point.reaction = reaction();
    point.bond = -1;
    point.load_step = load_step;
    e.path.push_back(point);
    if (e.peak < 0 || std::abs(point.reaction) > std::abs(e.path[std::size_t(e.peak)].reaction))
      e.peak = static_cast<int>(e.path.size()) - 1;
    if (load_step && settings_.on_point) settings_.on_point(model_, e.path.back(), offsets_);
    return e.path.back();
  }

  // The first crack at load factor lambda: the critical state, then its bonds open.
  void crack(double lambda, PlasticShearResult& r) {
    EventsResult& e = r.events;
    std::vector<SiteFailure> sites = judged_sites();
    const OpeningSite opening =
        next_opening_site(model_.particles, model_.bonds, sites, kTieTolerance);
    require(opening.particle >= 0, "plastic shear: the failing site has no bond to open");
    EventPoint& point = record(lambda, r, false);
    point.site = opening.particle;
    point.site_mode = opening.site.failure.mode;
    point.site_fracture_angle = opening.site.failure.fracture_angle;
    point.bond = opening.bonds.front();
    point.broken = static_cast<int>(opening.bonds.size());
    // The energy its bonds hold at the critical state goes with them (a brittle crack).
    std::vector<double> energy;
    const Particles& p = model_.particles;
    for (int b : opening.bonds) {
      const int i = model_.bonds.first(b), j = model_.bonds.second(b);
      energy.push_back(
          parallel_bond_response(
              bond_parameters(model_.bonds, b), row3(p.displacement, i), row3(p.rotation, i),
              row3(p.displacement, j) - offsets_[static_cast<std::size_t>(b)], row3(p.rotation, j))
              .energy);
    }
    double crack_energy = 0;
    for (double x : energy) crack_energy += x;
    point.crack_energy = crack_energy;
    e.crack_energy = crack_energy;
    e.dissipated_energy = crack_energy;
    const double area = crack_share(p, model_.bonds, opening.particle, opening.normal);
    const bool fibre = opening.site.failure.mode == PlyFailureMode::kFibreTension ||
                       opening.site.failure.mode == PlyFailureMode::kFibreCompression;
    e.crack_area = area;
    e.crack_fracture_energy =
        area * (fibre ? mp_.material.strength.G_fibre : mp_.material.strength.G_matrix);
    if (settings_.on_point) settings_.on_point(model_, point, offsets_);
    const BondState mode = crack_bond_state(opening.site.failure.mode);
    for (int b : opening.bonds) {
      BondBreak record;
      record.bond = b;
      record.mode = mode;
      record.at = static_cast<double>(point.event);
      record.load = lambda;
      record.position =
          p.reference_position.row(model_.bonds.first(b)).transpose().matrix() +
          model_.bonds.lever_first(b) * model_.bonds.normal.row(b).transpose().matrix();
      e.breaks.push_back(record);
    }
    open_bonds(model_.bonds, opening.bonds, mode);
    e.stop = "failed";
  }

  EventProgress progress(double lambda, const EventsResult& e) const {
    double peak = 0;
    if (e.peak >= 0) peak = std::abs(e.path[static_cast<std::size_t>(e.peak)].reaction);
    return {static_cast<long>(e.path.size()), static_cast<int>(e.breaks.size()), lambda, peak,
            seconds_since(start_)};
  }

  void report_progress(double lambda, const EventsResult& e) {
    if (!settings_.on_progress) return;
    const double elapsed = seconds_since(start_);
    if (elapsed - last_progress_ < settings_.progress_seconds) return;
    last_progress_ = elapsed;
    settings_.on_progress(progress(lambda, e));
  }

  Model& model_;
  const DofFlags& reaction_dofs_;
  const PlasticShearSettings& settings_;
  const MaterialPointFailure& mp_;
  RambergOsgoodShear law_;
  StaticSystem system_;
  Clock::time_point start_;
  Eigen::VectorXd unit_u_, u0_;
  std::vector<bool> judged_;
  // Each site's plastic shear strain (signed), its accumulated magnitude and the stress at which
  // it yields next (the law's at its last return; 0 before any).
  std::vector<double> gamma_, kappa_, yield_;
  std::vector<Eigen::Vector3d> offsets_;
  long solves_ = 0;
  double last_progress_ = 0;
};

}  // namespace

PlasticShearResult run_plastic_shear(Model& model, const DofConstraints& unit,
                                     const DofFlags& reaction_dofs,
                                     const PlasticShearSettings& settings) {
  settings.validate();
  require(!model.bonds.has_free_offsets(),
          "plastic shear: the bonds carry free offsets (cure stresses, thermal.delta_T), which the "
          "plastic shear run does not take yet");
  PlasticShearRun run(model, unit, reaction_dofs, settings);
  return run.run();
}

}  // namespace plydem
