#include "experiments/tension_test.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/measurements.hpp"
#include "core/registry.hpp"
#include "core/static_solver.hpp"

namespace plydem {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The specimen's response at the current state: gauge strain and grip stress.
struct Sample {
  GaugeStrain strain;
  double stress = 0;
};

}  // namespace

void TensionSettings::validate() const {
  coupon.validate();
  require(std::isfinite(grip_length) && grip_length >= 0, "grip length must be >= 0");
  require(std::isfinite(gauge_fraction) && gauge_fraction > 0 && gauge_fraction < 1,
          fmt::format("gauge fraction must lie in (0, 1), got {}", gauge_fraction));
  require(std::isfinite(target_strain) && target_strain > 0 && target_strain < 0.05,
          fmt::format("target strain must lie in (0, 0.05) (small-strain model), got {}",
                      target_strain));
  require(load_stages >= 1 && load_stages <= 100, "load stages must lie in [1, 100]");
  require(ramp_cycles >= 1, "ramp cycles must be >= 1");
  require(std::isfinite(grip_velocity) && grip_velocity >= 0, "grip velocity must be >= 0");
  require(std::isfinite(tolerance) && tolerance > 0 && tolerance < 1,
          fmt::format("quasi-static tolerance must lie in (0, 1), got {}", tolerance));
  require(max_cycles >= 1, "max cycles must be >= 1");
  require(fixed_cycles >= 0, "fixed cycles must be >= 0");
  plydem::validate(explicit_settings);  // checked even when a static solve will not use them
}

TensionTest::TensionTest(TensionSettings settings) : settings_(std::move(settings)) {
  settings_.validate();
}

void TensionTest::on_progress(std::function<void(const TensionProgress&)> callback) {
  progress_ = std::move(callback);
}

TensionResult TensionTest::run() const {
  const auto start = Clock::now();
  const std::unique_ptr<Strategy> strategy = default_registry().create(settings_.strategy);
  TensionResult result;
  result.strategy = settings_.strategy;
  result.material = settings_.coupon.material;
  result.ply_angle = settings_.coupon.ply_angle;
  result.calibration = strategy->calibrate(settings_.coupon.material, settings_.coupon.ply_angle,
                                           settings_.coupon.thickness);
  result.theory = in_plane_constants(
      rotate_reduced_stiffness(reduced_stiffness(settings_.coupon.material), result.ply_angle));
  result.along_x = pull(*strategy, result.ply_angle);
  result.along_y = pull(*strategy, result.ply_angle - std::numbers::pi / 2);
  result.dem.Ex = result.along_x.modulus;
  result.dem.nu_xy = result.along_x.poisson;
  result.dem.shear_coupling_x = result.along_x.shear_coupling;
  result.dem.Ey = result.along_y.modulus;
  result.dem.nu_yx = result.along_y.poisson;
  result.wall_seconds = seconds_since(start);
  return result;
}

PullResult TensionTest::pull(const Strategy& strategy, double ply_angle) const {
  const auto start = Clock::now();
  const TensionSettings& s = settings_;
  CouponSpec spec = s.coupon;
  spec.ply_angle = ply_angle;
  Model model = strategy.build(spec);
  Particles& p = model.particles;

  // Grips at both ends, gauge section in the middle.
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  const double span = x_max - x_min;
  const double grip = s.grip_length > 0 ? s.grip_length : 2.0 * spec.particle_diameter;
  require(span > 2 * grip,
          fmt::format("the grips ({} mm each) leave no free length in a {} mm coupon", grip * 1e3,
                      span * 1e3));
  int left = 0, right = 0;
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    if (x <= x_min + grip) {
      p.group(i) = static_cast<int>(BoundaryGroup::kLeftGrip);
      ++left;
    } else if (x >= x_max - grip) {
      p.group(i) = static_cast<int>(BoundaryGroup::kRightGrip);
      ++right;
    }
  }
  require(left > 0 && right > 0, "a grip holds no particle");
  const double x_mid = 0.5 * (x_min + x_max);
  const double gauge_half = 0.5 * s.gauge_fraction * span;
  // Strains from the gauge interior: away from the grips and, by `edge_band`, from the free edges,
  // whose discrete boundary layer relaxes differently from the bulk.
  std::vector<int> gauge;
  {
    const double y_min = p.reference_position.col(1).minCoeff();
    const double y_max = p.reference_position.col(1).maxCoeff();
    const double band =
        std::min(s.edge_band_diameters * spec.particle_diameter, 0.25 * (y_max - y_min));
    for (int i : particles_between(p, x_mid - gauge_half, x_mid + gauge_half)) {
      const double y = p.reference_position(i, 1);
      if (y >= y_min + band && y <= y_max - band) gauge.push_back(i);
    }
  }
  const double area = cross_section_area(p, x_mid - gauge_half, x_mid + gauge_half,
                                         std::min(4.0 * spec.particle_diameter, 0.25 * gauge_half));

  // Only explicit runs need the integrator (and its critical time step over every bond).
  std::optional<ExplicitIntegrator> integrator;
  if (s.solver == TensionSolver::kExplicit) integrator.emplace(model, s.explicit_settings);
  const double dt = integrator ? integrator->time_step() : 0.0;
  auto grips_moving = [&](double velocity) {
    PrescribedMotion motion[2];
    motion[0].group = BoundaryGroup::kLeftGrip;
    motion[1].group = BoundaryGroup::kRightGrip;
    motion[0].velocity = Eigen::Vector3d(-velocity, 0, 0);
    motion[1].velocity = Eigen::Vector3d(velocity, 0, 0);
    const bool clamped = s.grips == GripCondition::kClamped;
    for (PrescribedMotion& m : motion) {
      m.fix_velocity = {true, clamped, true};
      m.fix_angular_velocity = {true, true, clamped};
    }
    integrator->set_prescribed_motions({motion[0], motion[1]});
  };
  auto sample = [&](const Particles& state) {
    double left_force = 0, right_force = 0;
    for (int i = 0; i < state.size(); ++i) {
      if (state.group(i) == static_cast<int>(BoundaryGroup::kLeftGrip))
        left_force += state.force(i, 0);
      if (state.group(i) == static_cast<int>(BoundaryGroup::kRightGrip))
        right_force += state.force(i, 0);
    }
    // The bonds pull the right grip towards -x and the left one towards +x.
    return Sample{fit_gauge_strain(state, gauge), 0.5 * (left_force - right_force) / area};
  };

  PullResult result;
  result.ply_angle = ply_angle;
  result.particles = p.size();
  result.bonds = model.bonds.size();
  result.time_step = dt;
  result.cross_section = area;
  const double total_grip_travel = 0.5 * s.target_strain * span;
  auto last_report = Clock::now();
  auto report = [&](const char* phase, const CycleReport& cycle) {
    if (progress_ && seconds_since(last_report) > 2.0) {
      progress_({phase, integrator->cycles(), cycle.unbalanced_force_ratio});
      last_report = Clock::now();
    }
  };

  // Each stage point goes straight into the result; staged and static runs start from the
  // unloaded origin, which is an exact equilibrium point.
  auto record = [&](const Sample& smp) {
    result.strain.push_back(smp.strain.exx);
    result.lateral_strain.push_back(smp.strain.eyy);
    result.shear_strain.push_back(smp.strain.gamma_xy);
    result.stress.push_back(smp.stress);
  };
  if (s.fixed_cycles == 0 || s.solver == TensionSolver::kStatic) record(Sample{});
  if (s.solver == TensionSolver::kStatic) {
    // The model is linear: one solve at the target strain, fitted through the unloaded origin.
    DofConstraints constraints(p.size());
    const bool clamped = s.grips == GripCondition::kClamped;
    for (int i = 0; i < p.size(); ++i) {
      const int g = p.group(i);
      if (g == static_cast<int>(BoundaryGroup::kFree)) continue;
      const double sign = g == static_cast<int>(BoundaryGroup::kRightGrip) ? 1.0 : -1.0;
      constraints.fix(i, Dof::kUx, sign * total_grip_travel);
      constraints.fix(i, Dof::kUz);
      constraints.fix(i, Dof::kThetaX);
      constraints.fix(i, Dof::kThetaY);
      if (clamped) {
        constraints.fix(i, Dof::kUy);
        constraints.fix(i, Dof::kThetaZ);
      }
    }
    StaticSettings static_settings;
    static_settings.pin_rigid_modes = true;  // free grips leave the y translation to pin
    const StaticResult solved = solve_static(model, constraints, static_settings);
    record(sample(p));
    result.final_ratio = solved.relative_residual;
  } else if (s.fixed_cycles > 0) {
    const double v = s.grip_velocity > 0
                         ? s.grip_velocity
                         : total_grip_travel / (static_cast<double>(s.fixed_cycles) * dt);
    result.grip_velocity = v;
    grips_moving(v);
    const long every = std::max(1L, s.fixed_cycles / 100);
    CycleReport cycle;
    for (long c = 1; c <= s.fixed_cycles; ++c) {
      cycle = integrator->cycle();
      report("loading", cycle);
      // Forces in p.force belong to the state before this cycle's update: sample both together.
      if (c % every == 0 && c > s.fixed_cycles / 2) {
        Particles before = p;
        before.displacement -= dt * before.velocity;
        record(sample(before));
      }
    }
    result.final_ratio = cycle.unbalanced_force_ratio;
  } else {
    const double stage_travel = total_grip_travel / s.load_stages;
    const double v = s.grip_velocity > 0 ? s.grip_velocity
                                         : stage_travel / (static_cast<double>(s.ramp_cycles) * dt);
    result.grip_velocity = v;
    const long ramp = std::max(1L, std::lround(stage_travel / (v * dt)));
    for (int stage = 1; stage <= s.load_stages; ++stage) {
      grips_moving(v);
      for (long c = 0; c < ramp; ++c) report("loading", integrator->cycle());
      grips_moving(0.0);
      CycleReport cycle = integrator->cycle();
      while (cycle.unbalanced_force_ratio > s.tolerance) {
        // Not require(): this runs every cycle, and the message is needed only on failure.
        if (integrator->cycles() >= s.max_cycles) {
          throw Error(fmt::format(
              "the tension test did not reach a quasi-static state within {} cycles "
              "(unbalanced-force ratio {:.3g} > tolerance {:.3g}); raise --max-cycles or the "
              "tolerance",
              s.max_cycles, cycle.unbalanced_force_ratio, s.tolerance));
        }
        cycle = integrator->cycle();
        report("relaxing", cycle);
      }
      result.final_ratio = cycle.unbalanced_force_ratio;
      compute_bond_forces(p, model.bonds);
      record(sample(p));
    }
  }
  const LinearFit stress_fit = linear_fit(result.strain, result.stress);
  result.modulus = stress_fit.slope;
  result.fit_r_squared = stress_fit.r_squared;
  result.poisson = -linear_fit(result.strain, result.lateral_strain).slope;
  result.shear_coupling = linear_fit(result.strain, result.shear_strain).slope;
  result.cycles = integrator ? integrator->cycles() : 0;
  result.wall_seconds = seconds_since(start);
  require(std::isfinite(result.modulus) && result.modulus > 0,
          fmt::format("the tension test measured a non-positive modulus {} Pa", result.modulus));
  return result;
}

}  // namespace plydem
