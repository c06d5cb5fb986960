// Bonds that break inside the explicit kernels: one bond driven to its strength in tension,
// shear, bending and twist breaks at the cycle its hand-computed utilisation reaches 1, from
// either end and in either particle order; softening follows its line; both ends of every bond
// hold the same history to the bit; the fused kernel breaks the bonds the reference loop breaks,
// at the same cycles, on any number of threads; the energy account closes; closed cracks carry
// compression through contacts. On 2 MPI ranks (the "2 MPI ranks:" cases, run under mpiexec) a
// coupon split between the ranks gives the one-rank reference run's bits, breaks and account.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "core/bond_failure.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/rank_exchange.hpp"
#include "strategies/registry.hpp"
#include "support/coupon_fixtures.hpp"
#include "support/threads.hpp"

using namespace plydem;
using namespace plydem::test;

namespace {

constexpr double kPi = std::numbers::pi;

// Two particles bonded along the unit `direction` (the bond from `first` to the other one),
// particle 0 in the left grip, particle 1 in the right one.
struct PairSpec {
  Eigen::Vector3d direction = Eigen::Vector3d(0.8, 0.6, 0.0);
  double radius[2] = {50e-6, 50e-6};
  double k_n = 1e6, k_s = 4e5, k_b = 3e-4, k_t = 2e-4;
  double section_radius = 40e-6;
  double tensile = std::numeric_limits<double>::infinity();
  double cohesion = std::numeric_limits<double>::infinity();
  double friction = 0;
  double ductility = 1;
  int first = 0;  // which particle is the bond's first end
};

Model pair_model(const PairSpec& spec) {
  Model m;
  m.particles.resize(2);
  m.particles.reference_position.row(1) =
      ((spec.radius[0] + spec.radius[1]) * spec.direction.normalized()).transpose().array();
  for (int i = 0; i < 2; ++i) {
    m.particles.radius(i) = spec.radius[i];
    m.particles.mass(i) = 1e-9;
    m.particles.moment_of_inertia(i) = 1e-18;
    m.particles.group(i) =
        static_cast<int>(i == 0 ? BoundaryGroup::kLeftGrip : BoundaryGroup::kRightGrip);
  }
  m.bonds.resize(1);
  m.bonds.first(0) = spec.first;
  m.bonds.second(0) = 1 - spec.first;
  m.bonds.normal_stiffness(0) = spec.k_n;
  m.bonds.shear_stiffness(0) = spec.k_s;
  m.bonds.bending_stiffness(0) = spec.k_b;
  m.bonds.twisting_stiffness(0) = spec.k_t;
  m.bonds.strength_radius(0) = spec.section_radius;
  m.bonds.tensile_strength(0) = spec.tensile;
  m.bonds.cohesion(0) = spec.cohesion;
  m.bonds.friction_coefficient(0) = spec.friction;
  m.bonds.ductility(0) = spec.ductility;
  set_bond_geometry(m.particles, m.bonds, 0);
  m.check_consistency();
  return m;
}

// Both particles fully prescribed: particle 0 at v0, w0 and particle 1 at v1, w1.
std::vector<PrescribedMotion> drive(const Eigen::Vector3d& v0, const Eigen::Vector3d& w0,
                                    const Eigen::Vector3d& v1, const Eigen::Vector3d& w1) {
  PrescribedMotion a, b;
  a.group = BoundaryGroup::kLeftGrip;
  b.group = BoundaryGroup::kRightGrip;
  a.velocity = v0;
  a.angular_velocity = w0;
  b.velocity = v1;
  b.angular_velocity = w1;
  for (PrescribedMotion* m : {&a, &b}) {
    m->fix_velocity = {true, true, true};
    m->fix_angular_velocity = {true, true, true};
  }
  return {a, b};
}

ExplicitSettings kernel_settings(ExplicitBackend kernel, ParticleOrder order, double dt) {
  ExplicitSettings s;
  s.backend = kernel;
  s.particle_order = order;
  s.time_step = dt;
  return s;
}

struct PairRun {
  long break_cycle = -1;  // the cycle whose state the break was decided at
  BondState mode = BondState::kIntact;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double load_at_break = 0;  // |F| + |M| on particle 1 at the break's cycle
  double load_after = 0;     // at the next cycle
  Model model;
};

// Cycles one by one until the bond breaks (at most `limit` cycles), then one more.
PairRun run_pair(const PairSpec& spec, const std::vector<PrescribedMotion>& motion,
                 const ExplicitSettings& settings, long limit) {
  PairRun r;
  r.model = pair_model(spec);
  ExplicitIntegrator integrator(r.model, settings);
  integrator.set_prescribed_motions(motion);
  for (long c = 0; c < limit && integrator.breaks().empty(); ++c) integrator.cycle();
  if (integrator.breaks().empty()) return r;
  const BondBreak& b = integrator.breaks().front();
  r.break_cycle = std::lround(b.at / integrator.time_step());
  r.mode = b.mode;
  r.position = b.position;
  auto load = [&] {
    return r.model.particles.force.row(1).matrix().norm() +
           r.model.particles.torque.row(1).matrix().norm() / spec.radius[1];
  };
  r.load_at_break = load();
  integrator.cycle();
  r.load_after = load();
  CHECK(integrator.breaks().size() == 1);
  CHECK(integrator.breaks().front().bond == 0);
  return r;
}

// Uniform strengths on every bond, by hand: the section a disc of the particle radius.
void set_strengths(Model& m, double tensile, double cohesion, double friction,
                   double ductility = 1) {
  Bonds& b = m.bonds;
  for (int k = 0; k < b.size(); ++k) {
    b.strength_radius(k) = m.particles.radius(b.first(k));
    b.tensile_strength(k) = tensile;
    b.cohesion(k) = cohesion;
    b.friction_coefficient(k) = friction;
    b.ductility(k) = ductility;
  }
}

// The stress a coupon's bonds reach per unit grip travel is not known by hand; the strengths of
// the coupon tests are set from the first elastic cycle's largest bond stress, so that the first
// bond breaks after about `cycles_to_break` cycles of pulling at `speed` (the coupon is linear).
double tensile_stress_per_cycle(Model m, double speed, double dt) {
  ExplicitSettings s;
  s.time_step = dt;
  s.backend = ExplicitBackend::kReference;
  ExplicitIntegrator integrator(m, s);
  integrator.set_prescribed_motions(pull(speed));
  const long cycles = 2000;
  integrator.advance(cycles);
  double largest = 0;
  for (int b = 0; b < m.bonds.size(); ++b) {
    const BondStresses st =
        bond_stresses(bond_parameters(m.bonds, b), m.particles.radius(m.bonds.first(b)),
                      m.particles.displacement.row(m.bonds.first(b)).matrix().transpose(),
                      m.particles.rotation.row(m.bonds.first(b)).matrix().transpose(),
                      m.particles.displacement.row(m.bonds.second(b)).matrix().transpose(),
                      m.particles.rotation.row(m.bonds.second(b)).matrix().transpose());
    largest = std::max(largest, st.normal);
  }
  return largest / cycles;
}

struct CouponRun {
  Model model;
  std::vector<BondBreak> breaks;
  EnergyAccount energy;
  double worst_balance = 0;  // largest |balance| / boundary work over the checks
  double peak_work = 0;
};

CouponRun run_coupon(Model m, const ExplicitSettings& settings, double speed, long cycles,
                     long check_every = 500) {
  CouponRun r;
  ExplicitIntegrator integrator(m, settings);
  integrator.set_prescribed_motions(pull(speed));
  RunControl control;
  control.check_interval = check_every;
  control.max_cycles = cycles;
  control.on_check = [&](const RunCheck&) {
    const EnergyAccount e = integrator.energy();
    if (e.boundary_work > 0)
      r.worst_balance = std::max(r.worst_balance, std::abs(e.balance()) / e.boundary_work);
    return true;
  };
  integrator.run(control);
  r.energy = integrator.energy();
  r.breaks = integrator.breaks();
  r.model = std::move(m);
  return r;
}

bool same_breaks(const std::vector<BondBreak>& a, const std::vector<BondBreak>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].bond != b[k].bond || a[k].mode != b[k].mode || a[k].at != b[k].at) return false;
  return true;
}

bool bitwise_equal(const Particles& a, const Particles& b) {
  return (a.displacement == b.displacement).all() && (a.rotation == b.rotation).all() &&
         (a.velocity == b.velocity).all() && (a.angular_velocity == b.angular_velocity).all();
}

}  // namespace

TEST_CASE("one bond breaks at the cycle its hand-computed utilisation reaches 1") {
  // Per cycle, the motion below raises the governing stress by `rate`; the strength is set to X
  // times it, X = 123.37, so the bond breaks at the state of cycle ceil(X) = 124 (the state of
  // cycle c is c steps of motion from rest).
  const double dt = 1e-9, v = 0.05, w = 200.0, X = 123.37;
  const long expected = static_cast<long>(std::ceil(X));
  PairSpec base;
  const double R = base.section_radius;
  const double area = kPi * R * R, inertia = kPi * R * R * R * R / 4, polar = 2 * inertia;
  const Eigen::Vector3d n = base.direction.normalized();
  const Eigen::Vector3d t = Eigen::Vector3d::UnitZ().cross(n);  // in-plane, across the bond
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ(), zero = Eigen::Vector3d::Zero();
  struct Case {
    const char* name;
    BondState mode;
    PairSpec spec;
    std::vector<PrescribedMotion> motion;
  };
  std::vector<Case> cases;
  {
    PairSpec s = base;  // tension: particle 1 moves away along n, sigma = k_n du_n / A
    s.radius[1] = 35e-6;
    s.tensile = X * s.k_n * v * dt / area;
    s.cohesion = 1e3 * s.tensile;
    cases.push_back({"tension", BondState::kBrokenTension, s, drive(zero, zero, v * n, zero)});
  }
  {
    PairSpec s = base;  // shear: particle 1 slides across, tau = k_s |du_s| / A
    s.radius[0] = 60e-6;
    s.cohesion = X * s.k_s * v * dt / area;
    s.tensile = 1e3 * s.cohesion;
    cases.push_back({"shear", BondState::kBrokenShear, s, drive(zero, zero, v * t, zero)});
  }
  {
    // Shear under tension with friction: capacity c - (F_n / A) tan(phi), so per cycle
    // tau / capacity grows as k_s v_t dt / (A c - k_n v_n dt tan(phi) cycles).
    PairSpec s = base;
    s.friction = 0.4;
    const double vn = 0.3 * v, vt = v;
    s.cohesion = X * (s.k_s * vt + s.friction * s.k_n * vn) * dt / area;
    s.tensile = 1e3 * s.cohesion;
    cases.push_back({"shear with friction", BondState::kBrokenShear, s,
                     drive(zero, zero, vn * n + vt * t, zero)});
  }
  {
    // Bending: the two particles turn oppositely about z (equal levers: du = 0),
    // sigma = k_b |dtheta_s| R / I with |dtheta_s| = 2 w dt per cycle.
    PairSpec s = base;
    s.tensile = X * s.k_b * 2 * w * dt * R / inertia;
    s.cohesion = 1e3 * s.tensile;
    cases.push_back({"bending", BondState::kBrokenTension, s, drive(zero, -w * z, zero, w * z)});
  }
  {
    // Twist: opposite turns about the bond's axis, tau = k_t |dtheta_n| R / J.
    PairSpec s = base;
    s.cohesion = X * s.k_t * 2 * w * dt * R / polar;
    s.tensile = 1e3 * s.cohesion;
    cases.push_back({"twist", BondState::kBrokenShear, s, drive(zero, -w * n, zero, w * n)});
  }
  for (const Case& c : cases) {
    for (int first : {0, 1}) {
      for (ExplicitBackend kernel : {ExplicitBackend::kReference, ExplicitBackend::kCpu}) {
        for (ParticleOrder order : {ParticleOrder::kAsBuilt, ParticleOrder::kHilbert}) {
          CAPTURE(std::string(c.name));
          CAPTURE(first);
          CAPTURE(static_cast<int>(kernel));
          CAPTURE(static_cast<int>(order));
          PairSpec spec = c.spec;
          spec.first = first;
          const PairRun r = run_pair(spec, c.motion, kernel_settings(kernel, order, dt), 400);
          CHECK(r.break_cycle == expected);
          CHECK(r.mode == c.mode);
          // The bond carried its load at the break's cycle and nothing from the next one on.
          CHECK(r.load_at_break > 0);
          CHECK(r.load_after < 1e-9 * r.load_at_break);
          const Bonds& b = r.model.bonds;
          CHECK(b.state(0) == static_cast<int>(c.mode));
          CHECK(b.damage(0) == 1);
          CHECK(b.normal_stiffness(0) == 0);
          // The contact point: X_first + lever_first n + u_first at the break's state.
          const int i = spec.first;
          const Eigen::Vector3d u_first =
              expected * dt * (c.motion[i].velocity);  // prescribed from rest
          const Eigen::Vector3d point =
              r.model.particles.reference_position.row(i).matrix().transpose() +
              b.lever_first(0) * b.normal.row(0).matrix().transpose() + u_first;
          CHECK((r.position - point).norm() < 1e-12 * point.norm() + 1e-15);
        }
      }
    }
  }
}

TEST_CASE("a softening bond follows its line and breaks when its kappa reaches the ductility") {
  // Tension at a steady rate: U grows by 1/X per cycle. Damage decided at cycle c acts from c + 1:
  // the force at cycle c is (1 - d(U_{c-1})) k_n du_n, with 1 - d(kappa) = (ku - kappa) /
  // (kappa (ku - 1)) on the softening line, and the bond breaks at the first cycle with
  // U >= ku.
  const double dt = 1e-9, v = 0.05, X = 40.3, ku = 3.5;
  PairSpec s;
  const double area = kPi * s.section_radius * s.section_radius;
  s.tensile = X * s.k_n * v * dt / area;
  s.cohesion = 1e3 * s.tensile;
  s.ductility = ku;
  const Eigen::Vector3d n = s.direction.normalized(), zero = Eigen::Vector3d::Zero();
  for (ExplicitBackend kernel : {ExplicitBackend::kReference, ExplicitBackend::kCpu}) {
    CAPTURE(static_cast<int>(kernel));
    Model m = pair_model(s);
    ExplicitIntegrator integrator(m, kernel_settings(kernel, ParticleOrder::kAutomatic, dt));
    integrator.set_prescribed_motions(drive(zero, zero, v * n, zero));
    double worst = 0;
    for (long c = 0; integrator.breaks().empty() && c < 1000; ++c) {
      integrator.cycle();
      const double u_prev = (c - 1) / X;  // the utilisation the force's damage was decided at
      const double remaining =
          u_prev > 1 ? (ku - u_prev) / (u_prev * (ku - 1)) : 1.0;  // softening line, by hand
      const double expected = remaining * s.k_n * c * v * dt;
      if (integrator.breaks().empty() && c > 0)
        worst = std::max(worst, std::abs(m.particles.force.row(1).matrix().norm() - expected) /
                                    (s.k_n * X * v * dt));
    }
    CHECK(worst < 1e-9);
    REQUIRE(integrator.breaks().size() == 1);
    CHECK(std::lround(integrator.breaks()[0].at / dt) == static_cast<long>(std::ceil(ku * X)));
    // Dissipated: the triangle under the bilinear law, ku times the peak energy (proportional
    // loading), less what the discrete steps leave: within one step's share.
    const double peak_energy = 0.5 * s.k_n * std::pow(X * v * dt, 2);
    CHECK(integrator.energy().released == doctest::Approx(ku * peak_energy).epsilon(2.0 / X));
  }
}

TEST_CASE("both ends of every bond hold the same history to the bit, in any particle order") {
  // An irregular 3D cloud, unequal radii and levers (the lever term is where a fused multiply-add
  // would split the ends), softening and brittle bonds, pulled by its grips.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Model m;
  const int n = 300;
  m.particles.resize(n);
  for (int i = 0; i < n; ++i) {
    m.particles.reference_position.row(i) << 8 * u(rng), 4 * u(rng), 4 * u(rng);
    m.particles.radius(i) = 0.2 + 0.25 * u(rng);
    m.particles.mass(i) = 0.5 + u(rng);
    m.particles.moment_of_inertia(i) = 0.05 + 0.1 * u(rng);
    const double x = m.particles.reference_position(i, 0);
    m.particles.group(i) = static_cast<int>(x < 1   ? BoundaryGroup::kLeftGrip
                                            : x > 7 ? BoundaryGroup::kRightGrip
                                                    : BoundaryGroup::kFree);
  }
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if ((m.particles.reference_position.row(i) - m.particles.reference_position.row(j))
              .matrix()
              .norm() < 1.2)
        pairs.push_back(u(rng) < 0.5 ? std::pair(i, j) : std::pair(j, i));
  m.bonds.resize(static_cast<int>(pairs.size()));
  for (int b = 0; b < m.bonds.size(); ++b) {
    m.bonds.first(b) = pairs[b].first;
    m.bonds.second(b) = pairs[b].second;
    m.bonds.normal_stiffness(b) = 1 + u(rng);
    m.bonds.shear_stiffness(b) = 0.5 * u(rng);
    m.bonds.bending_stiffness(b) = 0.1 * u(rng);
    m.bonds.twisting_stiffness(b) = 0.1 * u(rng);
    set_bond_geometry(m.particles, m.bonds, b);
    m.bonds.strength_radius(b) = 0.2;
    m.bonds.tensile_strength(b) = 0.02 * (0.5 + u(rng));
    m.bonds.cohesion(b) = 0.03 * (0.5 + u(rng));
    m.bonds.friction_coefficient(b) = 0.3 * u(rng);
    m.bonds.ductility(b) = u(rng) < 0.5 ? 1.0 : 1.5 + 3 * u(rng);
  }
  // Undamped, so that the orders' different summation of a particle's bonds (an irregular packing's
  // slots follow the neighbours' kernel indices) stays a last-bit difference (see the next case).
  ExplicitSettings settings;
  settings.local_damping = 0;
  settings.time_step = 0.5 * critical_time_step(m);
  std::vector<Model> runs;
  std::vector<std::vector<BondBreak>> logs;
  for (ParticleOrder order : {ParticleOrder::kAsBuilt, ParticleOrder::kHilbert}) {
    Model copy = m;
    settings.particle_order = order;
    ExplicitIntegrator integrator(copy, settings);
    integrator.set_prescribed_motions(pull(0.05 / (3000 * settings.time_step)));
    integrator.advance(3000);
    int softened = 0, disagree = 0;
    for (int b = 0; b < copy.bonds.size(); ++b) {
      const std::array<BondEnd, 2> e = integrator.bond_ends(b);
      const bool same = e[0].holds == e[1].holds &&
                        std::memcmp(&e[0].damage, &e[1].damage, sizeof(double)) == 0 &&
                        std::memcmp(&e[0].kappa, &e[1].kappa, sizeof(double)) == 0;
      disagree += same ? 0 : 1;
      softened += e[0].holds && e[0].damage > 0 ? 1 : 0;
    }
    CHECK(disagree == 0);
    CHECK(softened > 10);
    CHECK(integrator.breaks().size() > 10);
    logs.push_back(integrator.breaks());
    runs.push_back(copy);
  }
  // The same bonds break in either order, at the same cycles, in the same modes.
  CHECK(same_breaks(logs[0], logs[1]));
}

TEST_CASE("the fused kernel breaks the bonds the reference loop breaks, at the same cycles") {
  // Undamped: local damping's sign(v) turns the kernels' last-bit differences into a step's
  // difference wherever a velocity crosses zero (the kernels then agree in distribution only);
  // without it they agree to rounding, and a break differs only if a bond's utilisation crosses
  // 1 within that rounding.
  Model m = small_coupon();
  ExplicitSettings settings;
  settings.local_damping = 0;
  settings.time_step = 0.8 * critical_time_step(m);
  const double speed = 0.02;
  const double rate = tensile_stress_per_cycle(m, speed, settings.time_step);
  set_strengths(m, 3000.37 * rate, 5000.37 * rate, 0.3);
  settings.backend = ExplicitBackend::kReference;
  const CouponRun slow = run_coupon(m, settings, speed, 12000);
  settings.backend = ExplicitBackend::kCpu;
  const CouponRun fast = run_coupon(m, settings, speed, 12000);
  REQUIRE(slow.breaks.size() > 5);
  CHECK(same_breaks(fast.breaks, slow.breaks));
  for (int b = 0; b < m.bonds.size(); ++b)
    CHECK(fast.model.bonds.state(b) == slow.model.bonds.state(b));
  // Strengths per slot decide exactly as strengths in the types.
  settings.strength_storage = StrengthStorage::kSlots;
  const CouponRun slots = run_coupon(m, settings, speed, 12000);
  CHECK(same_breaks(slots.breaks, fast.breaks));
  CHECK(bitwise_equal(slots.model.particles, fast.model.particles));
}

// A coupon of `length` x `width` at 0.05 mm particles pulled to its first breaks, with one
// thread, two and four threads, and two threads in Hilbert order: the same breaks and the same
// state.
void check_thread_and_order_independence(double length, double width) {
  Model m = small_coupon(length, width, 0.05e-3);
  ExplicitSettings settings;
  settings.time_step = 0.8 * critical_time_step(m);
  const double speed = 0.02;
  const double rate = tensile_stress_per_cycle(m, speed, settings.time_step);
  set_strengths(m, 2500.37 * rate, 4000.37 * rate, 0.3, 1.0);
  CouponRun one, two, four, hilbert;
  {
    Threads threads(1);
    one = run_coupon(m, settings, speed, 6000, 1000);
  }
  {
    Threads threads(4);
    four = run_coupon(m, settings, speed, 6000, 1000);
  }
  {
    Threads threads(2);
    two = run_coupon(m, settings, speed, 6000, 700);
    settings.particle_order = ParticleOrder::kHilbert;
    hilbert = run_coupon(m, settings, speed, 6000, 1000);
  }
  REQUIRE(one.breaks.size() > 5);
  for (const CouponRun* other : {&two, &four}) {
    CHECK(same_breaks(one.breaks, other->breaks));
    CHECK(bitwise_equal(one.model.particles, other->model.particles));
    CHECK(one.energy.boundary_work == other->energy.boundary_work);
    CHECK(one.energy.released == other->energy.released);
  }
  CHECK(same_breaks(one.breaks, hilbert.breaks));
  CHECK(bitwise_equal(one.model.particles, hilbert.model.particles));
}

TEST_CASE("breaking runs do not depend on the thread count or the particle order") {
  // 1.5 x 0.5 mm: about 300 particles, 40 blocks of eight for two threads.
  check_thread_and_order_independence(1.5e-3, 0.5e-3);
}

TEST_CASE("larger coupon: breaking runs do not depend on the thread count or the particle order") {
  // 3 x 1 mm: about 1400 particles.
  check_thread_and_order_independence(3e-3, 1e-3);
}

namespace {

// The small coupon with bonds of `ductility` pulled to failure by each kernel: its energy account
// closes within 1% of the grips' work.
void check_energy_account_to_failure(double ductility) {
  Model m = small_coupon();
  ExplicitSettings settings;
  settings.time_step = 0.8 * critical_time_step(m);
  const double speed = 0.02;
  const double rate = tensile_stress_per_cycle(m, speed, settings.time_step);
  for (ExplicitBackend kernel : {ExplicitBackend::kCpu, ExplicitBackend::kReference}) {
    CAPTURE(ductility);
    CAPTURE(static_cast<int>(kernel));
    Model coupon = m;
    set_strengths(coupon, 3000 * rate, 5000 * rate, 0.3, ductility);
    settings.backend = kernel;
    const CouponRun r = run_coupon(coupon, settings, speed, 20000);
    const EnergyAccount& e = r.energy;
    // Failed: many bonds broke, the grips did work, breaking released a good share of it.
    CHECK(r.breaks.size() > 10);
    CHECK(e.boundary_work > 0);
    CHECK(e.released > 0.01 * e.boundary_work);
    CHECK(e.damping > 0);
    CHECK(std::abs(e.balance()) < 0.01 * e.boundary_work);
    CHECK(r.worst_balance < 0.01);
  }
}

}  // namespace

TEST_CASE("the energy account closes within 1% on a coupon pulled to failure: softening bonds") {
  check_energy_account_to_failure(4.0);
}

// The release build only (label slow): the same account, bonds that soften less.
TEST_CASE("slow: the energy account closes within 1% on a coupon pulled to failure: ductility 1") {
  check_energy_account_to_failure(1.0);
}

TEST_CASE("an elastic run's account closes to rounding") {
  // Linear bonds, no breaks: the leapfrog account is exact.
  Model m = small_coupon();
  ExplicitSettings settings;
  settings.energy_account = true;
  for (ExplicitBackend kernel : {ExplicitBackend::kCpu, ExplicitBackend::kReference}) {
    settings.backend = kernel;
    const CouponRun r = run_coupon(m, settings, 0.02, 3000, 250);
    CHECK(r.breaks.empty());
    CHECK(r.energy.boundary_work > 0);
    CHECK(r.energy.damping > 0);
    CHECK(std::abs(r.energy.balance()) < 1e-9 * r.energy.boundary_work);
    CHECK(r.worst_balance < 1e-9);
  }
  // Without the account an elastic model runs the elastic kernel and reports none.
  Model plain = m;
  ExplicitIntegrator integrator(plain, ExplicitSettings{});
  integrator.advance(10);
  CHECK(!integrator.breaking());
  CHECK(integrator.energy().boundary_work == 0);
}

TEST_CASE("a closed crack carries compression, an open one nothing") {
  const double dt = 1e-9, v = 0.05;
  PairSpec s;
  s.tensile = 1e3;  // breakable; the bond is broken by hand below
  const Eigen::Vector3d n = s.direction.normalized(), zero = Eigen::Vector3d::Zero();
  const Eigen::Vector3d t = Eigen::Vector3d::UnitZ().cross(n);
  for (ExplicitBackend kernel : {ExplicitBackend::kReference, ExplicitBackend::kCpu}) {
    CAPTURE(static_cast<int>(kernel));
    // Pulled apart: nothing.
    {
      Model m = pair_model(s);
      ExplicitIntegrator integrator(m, kernel_settings(kernel, ParticleOrder::kAutomatic, dt));
      integrator.break_bond(0);
      integrator.set_prescribed_motions(drive(zero, zero, v * n, zero));
      integrator.advance(50);
      CHECK(m.particles.force.matrix().norm() == 0);
      REQUIRE(integrator.contacts() != nullptr);
      CHECK(integrator.contacts()->touching() == 0);
    }
    // Pushed together: a repulsion k_n delta with the bond's intact k_n, delta the closure.
    {
      Model m = pair_model(s);
      ExplicitIntegrator integrator(m, kernel_settings(kernel, ParticleOrder::kAutomatic, dt));
      integrator.break_bond(0);
      integrator.set_prescribed_motions(drive(zero, zero, -v * n, zero));
      const long cycles = 40;
      integrator.advance(cycles);
      // The last cycle's forces are those at the state of cycle `cycles - 1`.
      const double closure = (cycles - 1) * v * dt;
      const Eigen::Vector3d f1 = m.particles.force.row(1).matrix().transpose();
      CHECK(f1.dot(n) == doctest::Approx(s.k_n * closure).epsilon(1e-9));  // pushes 1 away
      CHECK((f1 - f1.dot(n) * n).norm() < 1e-9 * f1.norm());
      CHECK(integrator.contacts()->touching() == 1);
      const EnergyAccount e = integrator.energy();
      CHECK(e.contact_energy == doctest::Approx(0.5 * s.k_n * closure * closure).epsilon(1e-9));
    }
    // Pushed together and slid: the tangential force grows with the slide up to mu F_n.
    {
      Model m = pair_model(s);
      ExplicitSettings settings = kernel_settings(kernel, ParticleOrder::kAutomatic, dt);
      settings.contact.friction = 0.3;
      ExplicitIntegrator integrator(m, settings);
      integrator.break_bond(0);
      integrator.set_prescribed_motions(drive(zero, zero, -v * n, zero));
      integrator.advance(40);  // closed by 39 v dt
      integrator.set_prescribed_motions(drive(zero, zero, 0.01 * v * t, zero));
      integrator.advance(3);
      Eigen::Vector3d f1 = m.particles.force.row(1).matrix().transpose();
      const double normal = f1.dot(n);
      const double tangential = (f1 - normal * n).norm();
      CHECK(tangential > 0);
      CHECK(tangential < 0.3 * normal);  // sticking
      integrator.set_prescribed_motions(drive(zero, zero, v * t, zero));
      integrator.advance(200);
      f1 = m.particles.force.row(1).matrix().transpose();
      // Sliding: along the current normal (the forces' state is one step behind the model's).
      const Eigen::Vector3d branch =
          (m.particles.reference_position.row(1) - m.particles.reference_position.row(0) +
           m.particles.displacement.row(1) - m.particles.displacement.row(0))
              .matrix()
              .transpose() -
          dt * v * t;
      const Eigen::Vector3d normal_now = branch.normalized();
      const double normal_after = f1.dot(normal_now);
      CHECK((f1 - normal_after * normal_now).norm() ==
            doctest::Approx(0.3 * normal_after).epsilon(1e-9));
      CHECK(integrator.energy().friction > 0);
    }
  }
}

TEST_CASE("a bond broken by the law becomes a contact: the closed crack carries compression") {
  const double dt = 1e-9, v = 0.05, X = 30.37;
  PairSpec s;
  const double area = kPi * s.section_radius * s.section_radius;
  s.tensile = X * s.k_n * v * dt / area;
  s.cohesion = 1e3 * s.tensile;
  const Eigen::Vector3d n = s.direction.normalized(), zero = Eigen::Vector3d::Zero();
  for (ExplicitBackend kernel : {ExplicitBackend::kReference, ExplicitBackend::kCpu}) {
    Model m = pair_model(s);
    ExplicitIntegrator integrator(m, kernel_settings(kernel, ParticleOrder::kAutomatic, dt));
    integrator.set_prescribed_motions(drive(zero, zero, v * n, zero));
    integrator.advance(40);
    REQUIRE(integrator.breaks().size() == 1);
    CHECK(m.particles.force.matrix().norm() == 0);  // open: nothing
    integrator.set_prescribed_motions(drive(zero, zero, -v * n, zero));
    integrator.advance(60);  // back 60 steps from 40 forward: closed by 19 steps at the last
    const Eigen::Vector3d f1 = m.particles.force.row(1).matrix().transpose();
    CHECK(f1.dot(n) == doctest::Approx(s.k_n * 19 * v * dt).epsilon(1e-6));
  }
}

TEST_CASE("bad breaking settings are clear errors") {
  Model m = pair_model(PairSpec{});
  ExplicitSettings s;
  s.contact.skin = 0;
  CHECK_THROWS_WITH_AS(ExplicitIntegrator(m, s), doctest::Contains("contact skin"), Error);
  s = ExplicitSettings{};
  s.contact.friction = -0.1;
  CHECK_THROWS_WITH_AS(ExplicitIntegrator(m, s), doctest::Contains("friction"), Error);
  s = ExplicitSettings{};
  s.contact.check_interval = 0;
  CHECK_THROWS_WITH_AS(ExplicitIntegrator(m, s), doctest::Contains("check interval"), Error);
  Model broken = m;
  broken.bonds.strength_radius(0) = 0;
  broken.bonds.tensile_strength(0) = 1e6;
  CHECK_THROWS_WITH_AS(ExplicitIntegrator(broken, ExplicitSettings{}),
                       doctest::Contains("cross-section radius"), Error);
}

// Under mpiexec -n 2 (test_explicit_breaking_mpi2): each rank runs its slice of the particles and
// exchanges its border every cycle (solvers/rank_exchange.hpp); every rank also runs the whole
// model with the reference loops (split_between_ranks off), the one-rank run, to compare with.
namespace {

bool same_account(const EnergyAccount& a, const EnergyAccount& b) {
  return a.initial == b.initial && a.boundary_work == b.boundary_work &&
         a.strain_energy == b.strain_energy && a.kinetic_energy == b.kinetic_energy &&
         a.damping == b.damping && a.released == b.released;
}

// The coupon of the thread-count case, 1.5 x 0.5 mm at 0.05 mm, its strengths set to break it
// (bonds of `ductility`).
Model breakable_coupon(ExplicitSettings& settings, double speed, double ductility) {
  Model m = small_coupon(1.5e-3, 0.5e-3, 0.05e-3);
  settings.time_step = 0.8 * critical_time_step(m);
  const double rate = tensile_stress_per_cycle(m, speed, settings.time_step);
  set_strengths(m, 2500.37 * rate, 4000.37 * rate, 0.3, ductility);
  return m;
}

// The coupon of breakable_coupon pulled for `cycles` by `backend` on one rank (the whole model)
// and split between the ranks: the same bits.
void check_split_run(ExplicitBackend backend, double ductility, long cycles, long check_every) {
  CAPTURE(to_string(backend));
  ExplicitSettings settings;
  settings.backend = backend;
  settings.contacts = false;  // not across ranks yet (the error is a case of its own)
  const double speed = 0.02;
  const Model m = breakable_coupon(settings, speed, ductility);
  settings.split_between_ranks = false;
  const CouponRun whole = run_coupon(m, settings, speed, cycles, check_every);
  settings.split_between_ranks = true;
  const CouponRun split = run_coupon(m, settings, speed, cycles, check_every);
  REQUIRE(whole.breaks.size() > 5);
  CHECK(same_breaks(whole.breaks, split.breaks));
  CHECK(bitwise_equal(whole.model.particles, split.model.particles));
  CHECK((whole.model.particles.force == split.model.particles.force).all());
  CHECK((whole.model.bonds.damage == split.model.bonds.damage).all());
  CHECK((whole.model.bonds.state == split.model.bonds.state).all());
  CHECK((whole.model.bonds.normal_stiffness == split.model.bonds.normal_stiffness).all());
  CHECK(same_account(whole.energy, split.energy));
  CHECK(whole.worst_balance == split.worst_balance);
}

}  // namespace

TEST_CASE(
    "the partition between ranks: each particle owned once, every bond computed by its ends' "
    "ranks, "
    "each ghost sent from its owner's border") {
  const Model m = small_coupon(1.5e-3, 0.5e-3, 0.05e-3);
  const int n = m.particles.size();
  for (int size : {1, 2, 3, 5}) {
    CAPTURE(size);
    std::vector<RankPartition> parts;
    for (int r = 0; r < size; ++r) parts.push_back(partition_between_ranks(m, r, size));
    std::vector<int> owned(static_cast<std::size_t>(n), 0), logged(m.bonds.size(), 0);
    for (int r = 0; r < size; ++r) {
      const RankPartition& part = parts[static_cast<std::size_t>(r)];
      CHECK(part.owner == parts[0].owner);  // the same on every rank
      // Even shares (slices along x, the longest extent: checked below).
      CHECK(std::abs(static_cast<int>(part.own.size()) - n / size) <= 1);
      for (int i : part.own) ++owned[static_cast<std::size_t>(i)];
      for (std::size_t k = 0; k < part.bonds.size(); ++k) {
        const int b = part.bonds[k], i = m.bonds.first(b), j = m.bonds.second(b);
        CHECK((part.owner[static_cast<std::size_t>(i)] == r ||
               part.owner[static_cast<std::size_t>(j)] == r));
        if (part.logs_bond[k]) ++logged[static_cast<std::size_t>(b)];
      }
      for (std::size_t g = 0; g < part.ghosts.size(); ++g) {
        const int i = part.ghosts[g], from = part.owner[static_cast<std::size_t>(i)];
        CHECK(from != r);
        const RankPartition& source = parts[static_cast<std::size_t>(from)];
        REQUIRE(part.ghost_source[g] < static_cast<int>(source.border.size()));
        CHECK(source.border[static_cast<std::size_t>(part.ghost_source[g])] == i);
      }
    }
    CHECK(std::all_of(owned.begin(), owned.end(), [](int c) { return c == 1; }));
    CHECK(std::all_of(logged.begin(), logged.end(), [](int c) { return c == 1; }));
    // A bond reaches a rank's list exactly where one of its ends is the rank's own.
    for (int b = 0; b < m.bonds.size(); ++b) {
      const int a = parts[0].owner[static_cast<std::size_t>(m.bonds.first(b))];
      const int c = parts[0].owner[static_cast<std::size_t>(m.bonds.second(b))];
      for (int r = 0; r < size; ++r) {
        const std::vector<int>& listed = parts[static_cast<std::size_t>(r)].bonds;
        CHECK(std::binary_search(listed.begin(), listed.end(), b) == (r == a || r == c));
      }
    }
    // No particle of the last rank lies left of one of the first.
    if (size > 1) {
      double right_of_rank0 = -1e300, left_of_last = 1e300;
      for (int i = 0; i < n; ++i) {
        const double x = m.particles.reference_position(i, 0);
        const int owner = parts[0].owner[static_cast<std::size_t>(i)];
        if (owner == 0) right_of_rank0 = std::max(right_of_rank0, x);
        if (owner == size - 1) left_of_last = std::min(left_of_last, x);
      }
      CHECK(right_of_rank0 <= left_of_last);
    }
  }
  CHECK(contains(
      error_message([&] { partition_between_ranks(m, 0, n + 1); }),
      fmt::format("a model of {} particles cannot be shared between {} MPI ranks", n, n + 1)));
  // Owners given (the cpu backend's blocks): a rank may own none; every particle needs a rank.
  const RankPartition idle = partition_with_owners(m, std::vector<int>(n, 0), 1, 2);
  CHECK(idle.own.empty());
  CHECK(idle.ghosts.empty());
  CHECK(idle.bonds.empty());
  CHECK(contains(error_message([&] { partition_with_owners(m, std::vector<int>(n - 1, 0), 0, 2); }),
                 "must name a rank for each of"));
  CHECK(contains(error_message([&] { partition_with_owners(m, std::vector<int>(n, 2), 0, 2); }),
                 "must name a rank for each of"));
  CHECK(contains(error_message([&] { partition_with_owners(m, std::vector<int>(n, 0), 2, 2); }),
                 "rank 2 of 2 ranks does not exist"));
}

TEST_CASE("2 MPI ranks: a coupon pulled to failure gives the one-rank run's bits") {
  REQUIRE(mpi_size() == 2);
  for (ExplicitBackend backend : {ExplicitBackend::kReference, ExplicitBackend::kCpu}) {
    check_split_run(backend, 1.0, 6000, 700);
    // Softening bonds: the damage steps one rank decides reach the other's model (reference),
    // each end's slot is stepped by its particle's rank (cpu).
    check_split_run(backend, 4.0, 6000, 500);
  }
}

TEST_CASE("2 MPI ranks: the state hooks gather and the run's report are the one-rank bits") {
  REQUIRE(mpi_size() == 2);
  const Model m = small_coupon(1.5e-3, 0.5e-3, 0.05e-3);
  struct Seen {
    std::vector<Particles> gathered;
    std::vector<CycleReport> reports;
    Model model;
    std::size_t kernel_bytes = 0;
  };
  for (ExplicitBackend backend : {ExplicitBackend::kReference, ExplicitBackend::kCpu}) {
    CAPTURE(to_string(backend));
    auto run = [&](bool split) {
      Seen seen;
      seen.model = m;
      ExplicitSettings settings;
      settings.backend = backend;
      settings.split_between_ranks = split;
      ExplicitIntegrator integrator(seen.model, settings);
      integrator.set_prescribed_motions(pull(0.02));
      std::vector<int> all(static_cast<std::size_t>(m.particles.size()));
      std::iota(all.begin(), all.end(), 0);
      RunControl control;
      control.check_interval = 150;
      control.tolerance = 1e-3;
      control.max_cycles = 3000;
      control.on_check = [&](const RunCheck& check) {
        Particles at_forces = m.particles;
        integrator.gather(all, at_forces, StateAt::kForces);
        seen.gathered.push_back(at_forces);
        seen.reports.push_back(check.report);
        return true;
      };
      // A hook on the clock: the ranks agree on it, so both call it (it gathers) at the same
      // checks.
      control.hooks.push_back(
          {0, 1e-4, [&](const RunCheck&) {
             Particles now = m.particles;
             integrator.gather(std::vector<int>{0, m.particles.size() - 1}, now);
             return true;
           }});
      integrator.run(control);
      seen.kernel_bytes = integrator.kernel_bytes();
      return seen;
    };
    const Seen whole = run(false), split = run(true);
    // On N ranks a backend holds the partition besides (the reference none else).
    CHECK(split.kernel_bytes > whole.kernel_bytes);
    REQUIRE(whole.gathered.size() == split.gathered.size());
    for (std::size_t k = 0; k < whole.gathered.size(); ++k) {
      CAPTURE(k);
      CHECK(bitwise_equal(whole.gathered[k], split.gathered[k]));
      CHECK((whole.gathered[k].force == split.gathered[k].force).all());
      CHECK(whole.reports[k].strain_energy == split.reports[k].strain_energy);
      CHECK(whole.reports[k].kinetic_energy == split.reports[k].kinetic_energy);
      CHECK(whole.reports[k].unbalanced_force_ratio == split.reports[k].unbalanced_force_ratio);
    }
    CHECK(bitwise_equal(whole.model.particles, split.model.particles));
  }
}

TEST_CASE("2 MPI ranks: what does not run across ranks says so") {
  REQUIRE(mpi_size() == 2);
  Model m = small_coupon(1.5e-3, 0.5e-3, 0.05e-3);
  ExplicitSettings settings;
  settings.backend = ExplicitBackend::kDeviceEmulation;
  CHECK(contains(error_message([&] { ExplicitIntegrator integrator(m, settings); }),
                 "runs on one MPI rank only"));
  settings.backend = ExplicitBackend::kReference;
  settings.energy_account = true;  // a breaking run: contacts by default
  CHECK(contains(error_message([&] { ExplicitIntegrator integrator(m, settings); }),
                 "contacts between unbonded particles do not run across MPI ranks yet"));
  settings.backend = ExplicitBackend::kCpu;
  CHECK(contains(error_message([&] { ExplicitIntegrator integrator(m, settings); }),
                 "contacts between unbonded particles do not run across MPI ranks yet"));
  settings.contacts = false;
  CHECK_NOTHROW(ExplicitIntegrator(m, settings));
}
