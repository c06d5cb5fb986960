// The explicit integrator: exact energy conservation without damping, the critical time step, local
// damping and prescribed velocities; the run loop (run(): stop conditions, hooks, gather()).
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

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

TEST_CASE("a particle's own motion replaces its group's, on every backend") {
  // The left grip's particles each move at their own velocity (a uniform grip's strain), but one
  // of them, which keeps its group's; the right grip moves as a group.
  for (ExplicitBackend backend :
       {ExplicitBackend::kCpu, ExplicitBackend::kReference, ExplicitBackend::kDeviceEmulation}) {
    Model m = small_coupon();
    Particles& p = m.particles;
    const double x_min = p.reference_position.col(0).minCoeff();
    const double x_max = p.reference_position.col(0).maxCoeff();
    for (int i = 0; i < p.size(); ++i) {
      const double x = p.reference_position(i, 0);
      p.group(i) = static_cast<int>(x < x_min + 0.1e-3   ? BoundaryGroup::kLeftGrip
                                    : x > x_max - 0.1e-3 ? BoundaryGroup::kRightGrip
                                                         : BoundaryGroup::kFree);
    }
    std::vector<PrescribedMotion> motions(2);
    motions[0].group = BoundaryGroup::kLeftGrip;
    motions[0].velocity = Eigen::Vector3d(-0.01, 0, 0);
    motions[0].fix_velocity = {true, true, true};
    motions[1] = motions[0];
    motions[1].group = BoundaryGroup::kRightGrip;
    motions[1].velocity = Eigen::Vector3d(0.01, 0, 0);
    int own = 0, kept = -1;
    for (int i = 0; i < p.size(); ++i) {
      if (p.group(i) != static_cast<int>(BoundaryGroup::kLeftGrip)) continue;
      if (kept < 0) {
        kept = i;
        continue;
      }
      PrescribedMotion one = motions[0];
      one.particle = i;
      one.group = BoundaryGroup::kFree;  // not read
      one.velocity = Eigen::Vector3d(1e-3 * i, -2e-3 * i, 0);
      one.angular_velocity = Eigen::Vector3d(0, 0, 0.5 * i);
      one.fix_angular_velocity = {false, false, true};
      motions.push_back(one);
      ++own;
    }
    REQUIRE(own > 2);
    ExplicitSettings settings;
    settings.backend = backend;
    ExplicitIntegrator integrator(m, settings);
    integrator.set_prescribed_motions(motions);
    integrator.advance(20);
    const double t = 20 * integrator.time_step();
    for (int i = 0; i < p.size(); ++i) {
      CAPTURE(i);
      if (i == kept) {
        CHECK(p.displacement(i, 0) == doctest::Approx(-0.01 * t));
      } else if (p.group(i) == static_cast<int>(BoundaryGroup::kLeftGrip)) {
        CHECK(p.displacement(i, 0) == doctest::Approx(1e-3 * i * t));
        CHECK(p.displacement(i, 1) == doctest::Approx(-2e-3 * i * t));
        CHECK(p.rotation(i, 2) == doctest::Approx(0.5 * i * t));
      } else if (p.group(i) == static_cast<int>(BoundaryGroup::kRightGrip)) {
        CHECK(p.displacement(i, 0) == doctest::Approx(0.01 * t));
      }
    }
  }
  Model m = small_coupon();
  ExplicitIntegrator integrator(m, ExplicitSettings{});
  PrescribedMotion outside;
  outside.particle = m.particles.size();
  CHECK_THROWS_WITH_AS(integrator.set_prescribed_motions({outside}),
                       doctest::Contains("names particle"), Error);
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

// ---- run(): the run loop ----------------------------------------------------------------------

namespace {

// The small coupon pulled by grips at both ends (free laterally), as the tension test loads it.
Model gripped_coupon() {
  Model m = small_coupon();
  Particles& p = m.particles;
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  const double grip = 2.0 * p.radius.maxCoeff();
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    p.group(i) = static_cast<int>(x <= x_min + grip   ? BoundaryGroup::kLeftGrip
                                  : x >= x_max - grip ? BoundaryGroup::kRightGrip
                                                      : BoundaryGroup::kFree);
  }
  return m;
}

void pull(ExplicitIntegrator& integrator, double velocity) {
  PrescribedMotion motion[2];
  motion[0].group = BoundaryGroup::kLeftGrip;
  motion[1].group = BoundaryGroup::kRightGrip;
  motion[0].velocity = Eigen::Vector3d(-velocity, 0, 0);
  motion[1].velocity = Eigen::Vector3d(velocity, 0, 0);
  for (PrescribedMotion& m : motion) {
    m.fix_velocity = {true, false, true};
    m.fix_angular_velocity = {true, true, false};
  }
  integrator.set_prescribed_motions({motion[0], motion[1]});
}

bool bitwise_equal(const Vector3Array& a, const Vector3Array& b) {
  return a.rows() == b.rows() &&
         std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0;
}

bool same_state(const Particles& a, const Particles& b) {
  return bitwise_equal(a.displacement, b.displacement) && bitwise_equal(a.rotation, b.rotation) &&
         bitwise_equal(a.velocity, b.velocity) &&
         bitwise_equal(a.angular_velocity, b.angular_velocity) && bitwise_equal(a.force, b.force) &&
         bitwise_equal(a.torque, b.torque);
}

ExplicitSettings kernel(ExplicitBackend k) {
  ExplicitSettings s;
  s.backend = k;
  return s;
}

}  // namespace

TEST_CASE("run() equals cycle-by-cycle advance bit for bit, whatever the check interval") {
  for (const ExplicitBackend k : {ExplicitBackend::kCpu, ExplicitBackend::kReference}) {
    CAPTURE(static_cast<int>(k));
    Model by_cycle = gripped_coupon();
    kick(by_cycle, 4);
    Model by_run = by_cycle;
    ExplicitIntegrator a(by_cycle, kernel(k)), b(by_run, kernel(k));
    pull(a, 0.05);
    pull(b, 0.05);
    CycleReport last;
    for (int c = 0; c < 250; ++c) last = a.advance(1);
    // Two runs with a change of prescribed motion between them, as a tension stage does.
    RunControl control;
    control.check_interval = 7;
    control.max_cycles = 100;
    const RunReport first = b.run(control);
    CHECK(first.cycles == 100);
    CHECK(first.checks == 15);  // 14 of 7 cycles, then the last 2
    CHECK(first.stop == RunStop::kCycleLimit);
    control.max_cycles = 150;
    control.check_interval = 1000;
    const RunReport second = b.run(control);
    CHECK(second.checks == 1);
    CHECK(b.cycles() == 250);
    CHECK(b.time() == a.time());
    CHECK(same_state(by_cycle.particles, by_run.particles));
    CHECK(second.last.unbalanced_force_ratio == last.unbalanced_force_ratio);
    CHECK(second.last.strain_energy == last.strain_energy);
    CHECK(second.last.kinetic_energy == last.kinetic_energy);
    CHECK(second.kernel_seconds > 0);
    CHECK(second.wall_seconds >= second.kernel_seconds + second.check_seconds);
  }
}

TEST_CASE("run() stops at the quasi-static ratio, at the first check within the tolerance") {
  Model stepped = gripped_coupon();
  Model ran = stepped;
  ExplicitIntegrator a(stepped, ExplicitSettings{}), b(ran, ExplicitSettings{});
  for (ExplicitIntegrator* i : {&a, &b}) {
    pull(*i, 0.05);
    i->advance(300);
    pull(*i, 0.0);
  }
  const double tolerance = 1e-3;
  // The reference: one cycle at a time until the ratio is within the tolerance.
  long cycles = 0;
  CycleReport r;
  do {
    r = a.cycle();
    ++cycles;
  } while (r.unbalanced_force_ratio > tolerance);
  REQUIRE(cycles > 50);  // the test means something: it relaxed for a while

  RunControl control;
  control.check_interval = 1;
  control.tolerance = tolerance;
  control.max_cycles = 1'000'000;
  const RunReport exact = b.run(control);
  CHECK(exact.stop == RunStop::kQuasiStatic);
  CHECK(exact.cycles == cycles);
  CHECK(exact.last.unbalanced_force_ratio == r.unbalanced_force_ratio);
  CHECK(same_state(stepped.particles, ran.particles));

  // Coarser checks stop at the first check within the tolerance: a multiple of the interval.
  Model coarse = gripped_coupon();
  ExplicitIntegrator c(coarse, ExplicitSettings{});
  pull(c, 0.05);
  c.advance(300);
  pull(c, 0.0);
  control.check_interval = 40;
  const RunReport checked = c.run(control);
  CHECK(checked.stop == RunStop::kQuasiStatic);
  CHECK(checked.cycles % 40 == 0);
  CHECK(checked.cycles >= cycles);
  CHECK(checked.last.unbalanced_force_ratio <= tolerance);
}

TEST_CASE("run() stops at its cycle limit, at its wall-time limit and when a hook says so") {
  Model m = gripped_coupon();
  kick(m, 5);
  ExplicitIntegrator integrator(m, ExplicitSettings{});
  pull(integrator, 0.05);

  RunControl limited;
  limited.check_interval = 64;
  limited.max_cycles = 1000;
  limited.tolerance = 1e-300;  // never reached
  const RunReport cycles = integrator.run(limited);
  CHECK(cycles.stop == RunStop::kCycleLimit);
  CHECK(cycles.cycles == 1000);
  CHECK(integrator.cycles() == 1000);

  RunControl timed;
  timed.check_interval = 10;
  timed.time_limit_seconds = 0.05;
  const RunReport time = integrator.run(timed);
  CHECK(time.stop == RunStop::kTimeLimit);
  CHECK(time.wall_seconds >= 0.05);
  CHECK(time.wall_seconds < 5.0);
  CHECK(time.cycles % 10 == 0);

  RunControl hooked;
  hooked.check_interval = 3;
  hooked.max_cycles = 1000;
  hooked.on_check = [](const RunCheck& check) { return check.run_cycles < 30; };
  const RunReport hook = integrator.run(hooked);
  CHECK(hook.stop == RunStop::kHook);
  CHECK(hook.cycles == 30);
  CHECK(to_string(hook.stop) == "hook");
}

TEST_CASE("run()'s hooks come at the check interval and see the state of that cycle") {
  for (const ExplicitBackend k : {ExplicitBackend::kCpu, ExplicitBackend::kReference}) {
    CAPTURE(static_cast<int>(k));
    Model reference = gripped_coupon();
    kick(reference, 6);
    Model m = reference;
    ExplicitIntegrator stepper(reference, kernel(k)), integrator(m, kernel(k));
    pull(stepper, 0.05);
    pull(integrator, 0.05);
    // A few particles to gather: the hook sees exactly what cycle-by-cycle stepping gives.
    const std::vector<int> picked = {0, 7, m.particles.size() / 2, m.particles.size() - 1};
    std::vector<long> checked_at;
    Particles seen = m.particles, before = m.particles;
    int mismatches = 0;
    RunControl control;
    control.check_interval = 25;
    control.max_cycles = 110;
    control.progress_seconds = 0;
    int progress_calls = 0;
    control.on_progress = [&](const RunCheck& check) {
      ++progress_calls;
      CHECK(check.seconds_left >= 0);  // the cycle limit gives an estimate
    };
    control.on_check = [&](const RunCheck& check) {
      checked_at.push_back(check.run_cycles);
      CHECK(check.cycles == integrator.cycles());
      while (stepper.cycles() < check.cycles - 1) stepper.cycle();
      const Vector3Array previous = reference.particles.displacement;
      const Vector3Array previous_rotation = reference.particles.rotation;
      const CycleReport r = stepper.cycle();
      CHECK(r.unbalanced_force_ratio == check.report.unbalanced_force_ratio);
      integrator.gather(picked, seen);
      integrator.gather(picked, before, StateAt::kForces);
      for (int i : picked) {
        const Particles& p = reference.particles;
        for (int c = 0; c < 3; ++c) {
          mismatches += seen.displacement(i, c) != p.displacement(i, c);
          mismatches += seen.rotation(i, c) != p.rotation(i, c);
          mismatches += seen.velocity(i, c) != p.velocity(i, c);
          mismatches += seen.angular_velocity(i, c) != p.angular_velocity(i, c);
          mismatches += seen.force(i, c) != p.force(i, c);
          mismatches += before.displacement(i, c) != previous(i, c);
          mismatches += before.rotation(i, c) != previous_rotation(i, c);
        }
      }
      return true;
    };
    integrator.run(control);
    CHECK(checked_at == std::vector<long>{25, 50, 75, 100, 110});
    CHECK(progress_calls == 5);
    CHECK(mismatches == 0);
    CHECK(same_state(m.particles, reference.particles));
    // The pre-update state exists only during a run; the model's own particles cannot take it.
    CHECK_THROWS_AS(integrator.gather(picked, before, StateAt::kForces), Error);
    RunControl nested;
    nested.max_cycles = 2;
    nested.check_interval = 1;
    nested.on_check = [&](const RunCheck&) {
      CHECK_THROWS_AS(integrator.gather(picked, m.particles, StateAt::kForces), Error);
      CHECK_THROWS_AS(integrator.advance(1), Error);  // no run inside a run
      return true;
    };
    integrator.run(nested);
  }
}

TEST_CASE("a run without a stop condition or with a bad interval is refused") {
  Model m = small_coupon();
  ExplicitIntegrator integrator(m, ExplicitSettings{});
  RunControl none;
  CHECK_THROWS_AS(integrator.run(none), Error);
  RunControl bad;
  bad.max_cycles = 10;
  bad.check_interval = 0;
  CHECK_THROWS_AS(integrator.run(bad), Error);
  bad.check_interval = 1;
  bad.tolerance = -1;
  CHECK_THROWS_AS(integrator.run(bad), Error);
  bad.tolerance = 0;
  bad.time_limit_seconds = std::nan("");
  CHECK_THROWS_AS(integrator.run(bad), Error);
  CHECK(integrator.cycles() == 0);
}

TEST_CASE("periodic hooks fall due at their own periods, in order, and any can stop the run") {
  // Checkpointing every 40 cycles and sampling every 15 beside checks every 25: the chunks end
  // wherever one falls due, and the run equals the same cycles without hooks to the bit.
  for (const ExplicitBackend backend : {ExplicitBackend::kCpu, ExplicitBackend::kReference}) {
    CAPTURE(to_string(backend));
    Model m = small_coupon(), plain = m;
    ExplicitSettings settings;
    settings.backend = backend;
    ExplicitIntegrator integrator(m, settings), without(plain, settings);
    pull(integrator, 0.01);
    pull(without, 0.01);
    std::vector<long> checks, sampled, saved;
    std::vector<char> order;
    RunControl control;
    control.check_interval = 25;
    control.max_cycles = 100;
    control.on_check = [&](const RunCheck& check) {
      checks.push_back(check.run_cycles);
      order.push_back('c');
      return true;
    };
    control.hooks.push_back({15, 0, [&](const RunCheck& check) {
                               sampled.push_back(check.run_cycles);
                               order.push_back('s');
                               return true;
                             }});
    control.hooks.push_back({40, 0, [&](const RunCheck& check) {
                               saved.push_back(check.run_cycles);
                               order.push_back('k');
                               return true;
                             }});
    integrator.run(control);
    CHECK(sampled == std::vector<long>{15, 30, 45, 60, 75, 90});
    CHECK(saved == std::vector<long>{40, 80});
    // At most check_interval cycles between checks.
    CHECK(checks == std::vector<long>{15, 30, 40, 45, 60, 75, 80, 90, 100});
    CHECK(std::string(order.begin(), order.begin() + 4) == "cscs");  // on_check first
    without.advance(100);
    CHECK(same_state(m.particles, plain.particles));
    // A hook that says stop ends the run at its check, after the other hooks of that check.
    RunControl stopping;
    stopping.max_cycles = 1000;
    stopping.check_interval = 10;
    int later = 0;
    stopping.hooks.push_back({30, 0, [](const RunCheck&) { return false; }});
    stopping.hooks.push_back({0, 0, [&](const RunCheck&) { return ++later > 0; }});
    const RunReport r = integrator.run(stopping);
    CHECK(r.stop == RunStop::kHook);
    CHECK(r.cycles == 30);
    CHECK(later == 3);
    // A time period: at most once per interval (none within a run shorter than it).
    RunControl timed;
    timed.max_cycles = 50;
    timed.check_interval = 10;
    int timed_calls = 0;
    timed.hooks.push_back({0, 3600, [&](const RunCheck&) { return ++timed_calls > 0; }});
    integrator.run(timed);
    CHECK(timed_calls == 0);
    RunControl bad;
    bad.max_cycles = 10;
    bad.hooks.push_back({-1, 0, [](const RunCheck&) { return true; }});
    CHECK_THROWS_AS(integrator.run(bad), Error);
    bad.hooks.back() = {5, 0, nullptr};
    CHECK_THROWS_AS(integrator.run(bad), Error);
  }
}
