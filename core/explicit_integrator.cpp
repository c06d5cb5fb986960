#include "core/explicit_integrator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"

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
  set_prescribed_motions({});
}

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
}

namespace {

// Central-difference update of one degree of freedom with PFC local damping; returns the
// leapfrog kinetic-energy product m v_old v_new.
inline double advance(double& u, double& v, double force, double inertia, double dt, double alpha) {
  const double damped = force - alpha * std::abs(force) * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0));
  const double v_old = v;
  v += dt * damped / inertia;
  u += dt * v;
  return inertia * v_old * v;
}

}  // namespace

CycleReport ExplicitIntegrator::cycle() {
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
        kinetic2 +=
            advance(p.displacement(i, c), p.velocity(i, c), p.force(i, c), p.mass(i), dt, alpha);
      }
      if (fixed_angular_velocity_(i, c)) {
        p.angular_velocity(i, c) = prescribed_angular_velocity_(i, c);
        p.rotation(i, c) += dt * p.angular_velocity(i, c);
      } else {
        kinetic2 += advance(p.rotation(i, c), p.angular_velocity(i, c), p.torque(i, c),
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
