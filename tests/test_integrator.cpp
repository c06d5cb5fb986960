// The explicit integrator: exact energy conservation without damping, the critical time step, local
// damping and prescribed velocities.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "core/material.hpp"
#include "solvers/explicit_integrator.hpp"
#include "strategies/hex2d.hpp"

using namespace plydem;

namespace {

Model small_coupon() {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = 0.3;
  spec.length = 0.6e-3;
  spec.width = 0.4e-3;
  return Hex2dStrategy().build(spec).model;
}

void kick(Model& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < m.particles.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      m.particles.velocity(i, c) = 1e-3 * g(rng);
      m.particles.angular_velocity(i, c) = 1e-3 * g(rng) / m.particles.radius(i);
    }
}

}  // namespace

TEST_CASE("undamped central differences conserve the leapfrog energy over 10^4 steps") {
  Model m = small_coupon();
  kick(m, 1);
  ExplicitSettings settings;
  settings.local_damping = 0.0;
  ExplicitIntegrator integrator(m, settings);
  const CycleReport first = integrator.cycle();
  const double e0 = first.kinetic_energy + first.strain_energy;
  REQUIRE(e0 > 0);
  double max_drift = 0, max_strain = 0;
  for (int k = 0; k < 10000; ++k) {
    const CycleReport r = integrator.cycle();
    max_drift = std::max(max_drift, std::abs(r.kinetic_energy + r.strain_energy - e0) / e0);
    max_strain = std::max(max_strain, r.strain_energy);
  }
  CHECK(max_drift < 1e-6);
  CHECK(max_strain > 0.1 * e0);  // energy really moved between kinetic and strain
}

TEST_CASE("the automatic time step is stable and a step above the critical one is refused") {
  Model m = small_coupon();
  const double critical = critical_time_step(m);
  kick(m, 2);
  ExplicitSettings settings;
  settings.local_damping = 0.0;
  settings.safety_factor = 1.0;
  ExplicitIntegrator integrator(m, settings);
  CHECK(integrator.time_step() == doctest::Approx(critical));
  const CycleReport first = integrator.cycle();
  double last = 0;
  for (int k = 0; k < 5000; ++k) {
    const CycleReport r = integrator.cycle();
    last = r.kinetic_energy + r.strain_energy;
  }
  CHECK(last == doctest::Approx(first.kinetic_energy + first.strain_energy).epsilon(1e-6));

  // Two masses joined by one spring are stable below 2/omega = sqrt(m/k) for free-free, i.e.
  // dt_c = 2 / sqrt(2k/m) for the stretching mode: the bound must not exceed it.
  ExplicitSettings too_big;
  too_big.time_step = 1.01 * critical;
  Model copy = small_coupon();
  CHECK_THROWS_AS(ExplicitIntegrator(copy, too_big), Error);
}

TEST_CASE("local damping drains the energy; prescribed velocities are imposed exactly") {
  Model m = small_coupon();
  kick(m, 3);
  ExplicitIntegrator integrator(m, ExplicitSettings{});
  const CycleReport first = integrator.cycle();
  CycleReport r;
  for (int k = 0; k < 3000; ++k) r = integrator.cycle();
  CHECK(r.kinetic_energy + r.strain_energy < 1e-6 * (first.kinetic_energy + first.strain_energy));

  Model g = small_coupon();
  g.particles.group.setZero();
  g.particles.group(0) = static_cast<int>(BoundaryGroup::kLeftGrip);
  ExplicitIntegrator moving(g, ExplicitSettings{});
  PrescribedMotion motion;
  motion.group = BoundaryGroup::kLeftGrip;
  motion.velocity = Eigen::Vector3d(0.01, 0, 0);
  motion.fix_velocity = {true, false, true};
  moving.set_prescribed_motions({motion});
  for (int k = 0; k < 100; ++k) moving.cycle();
  CHECK(g.particles.displacement(0, 0) == doctest::Approx(100 * moving.time_step() * 0.01));
  CHECK(g.particles.velocity(0, 0) == 0.01);
}

TEST_CASE("bad integrator settings are refused") {
  Model m = small_coupon();
  ExplicitSettings s;
  s.local_damping = 1.0;
  CHECK_THROWS_AS(ExplicitIntegrator(m, s), Error);
  s = ExplicitSettings{};
  s.safety_factor = std::nan("");
  CHECK_THROWS_AS(ExplicitIntegrator(m, s), Error);
  s = ExplicitSettings{};
  s.time_step = -1;
  CHECK_THROWS_AS(ExplicitIntegrator(m, s), Error);
}
