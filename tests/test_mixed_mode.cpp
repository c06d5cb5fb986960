// The mixed-mode law of interface bonds (core/bond_failure.hpp): one interface bond between two
// particles, pulled at a fixed direction relative to its normal (pure opening, pure sliding and an
// equal mix of energies), by the events solver and by both explicit kernels. The onset load is the
// quadratic nominal-traction criterion and the energy dissipated (the area under the force-travel
// path, integrated here) is the Benzeggagh-Kenane G_c(B) times the bond's interface area, both
// computed here from the interface's constants alone; pure mode I is PFC's tension law exactly;
// bad input is refused by name.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "core/bond_failure.hpp"
#include "core/error.hpp"
#include "core/model.hpp"
#include "solvers/bond_events.hpp"
#include "solvers/explicit_integrator.hpp"
#include "strategies/strength_calibration.hpp"
#include "support/events_path.hpp"

using namespace plydem;
using plydem::test::area_under_path;

namespace {

// The interface of every case: stiffness per unit area K_n, K_s [N/m^3], strengths N, S [Pa],
// fracture energies GIc, GIIc [J/m^2] and the BK exponent; one bond standing for `area` [m^2].
struct Interface {
  double K_n = 1e13, K_s = 4e12;
  double N = 40e6, S = 70e6;
  double GIc = 300, GIIc = 900;
  double eta = 2.284;
  double area = 1e-8;
  double radius = 50e-6;  // of both particles (the bond's section radius too)
};

InterfaceStrength strength_of(const Interface& f) {
  InterfaceStrength s;
  s.normal = f.N;
  s.shear = f.S;
  s.GIc = f.GIc;
  s.GIIc = f.GIIc;
  s.bk_exponent = f.eta;
  return s;
}

// The pull: particle 1 moves along x relative to particle 0; the bond's normal makes the angle
// `angle` with x (0: pure opening, pi/2: pure sliding), in the x-z plane.
Model interface_pair(const Interface& f, double angle) {
  Model m;
  m.particles.resize(2);
  const Eigen::Vector3d n(std::cos(angle), 0.0, std::sin(angle));
  m.particles.reference_position.row(1) = (2 * f.radius * n).transpose().array();
  for (int i = 0; i < 2; ++i) {
    m.particles.radius(i) = f.radius;
    m.particles.mass(i) = 1e-9;
    m.particles.moment_of_inertia(i) = 1e-18;
    m.particles.volume(i) = 1e-12;
    m.particles.ply(i) = i;
    m.particles.group(i) =
        static_cast<int>(i == 0 ? BoundaryGroup::kLeftGrip : BoundaryGroup::kRightGrip);
  }
  m.bonds.resize(1);
  m.bonds.first(0) = 0;
  m.bonds.second(0) = 1;
  m.bonds.normal_stiffness(0) = f.K_n * f.area;
  m.bonds.shear_stiffness(0) = f.K_s * f.area;
  m.bonds.kind(0) = static_cast<int>(BondKind::kInterface);
  m.bonds.strength_radius(0) = f.radius;
  set_bond_geometry(m.particles, m.bonds, 0);
  set_interface_bond_strength(m.bonds, 0, f.area, strength_of(f));
  m.check_consistency();
  return m;
}

// What the interface's constants say for a pull along x at `angle` to the normal, by hand: with
// travel t along x, du_n = t cos(angle), |du_s| = t sin(angle), F_n = K_n a du_n, F_s = K_s a du_s.
struct ClosedForm {
  double onset_travel = 0;              // (F_n / (N a))^2 + (F_s / (S a))^2 = 1
  double onset_force = 0;               // F . x at onset [N]
  double mix = 0;                       // B = G_II / (G_I + G_II)
  double energy = 0;                    // (GIc + (GIIc - GIc) B^eta) a [J]
  double opening = 0, sliding = 0;      // F_n / (N a) and F_s / (S a) per unit travel [1/m]
  BondState mode = BondState::kIntact;  // tension where opening >= sliding, else shear
};

ClosedForm closed_form(const Interface& f, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  const double k_n = f.K_n * f.area, k_s = f.K_s * f.area;
  ClosedForm r;
  const double x = k_n * c / (f.N * f.area), y = k_s * s / (f.S * f.area);  // per unit travel
  r.onset_travel = 1.0 / std::sqrt(x * x + y * y);
  r.onset_force = r.onset_travel * (k_n * c * c + k_s * s * s);
  const double g_I = 0.5 * k_n * c * c, g_II = 0.5 * k_s * s * s;
  r.mix = g_II / (g_I + g_II);
  r.energy = (f.GIc + (f.GIIc - f.GIc) * std::pow(r.mix, f.eta)) * f.area;
  r.opening = x;
  r.sliding = y;
  r.mode = x >= y ? BondState::kBrokenTension : BondState::kBrokenShear;
  return r;
}

// The three cases: pure opening, pure sliding, and the angle at which G_I = G_II (B = 1/2):
// k_n cos^2 = k_s sin^2.
struct Case {
  const char* name;
  double angle;
};

std::vector<Case> cases(const Interface& f) {
  return {{"opening", 0.0},
          {"sliding", std::numbers::pi / 2},
          {"B = 1/2", std::atan(std::sqrt(f.K_n / f.K_s))}};
}

double relative(double a, double b) {
  return std::abs(a - b) / std::abs(b);
}

// Events: particle 0 held, particle 1 moved by `travel` along x per unit load factor.
EventsResult run_pull(Model& m, double travel, const EventSettings& settings) {
  DofConstraints unit(2);
  unit.fix_particle(0);
  unit.fix_particle(1, {travel, 0, 0});
  DofFlags reaction = DofFlags::Constant(2, kDofsPerParticle, false);
  reaction(1, 0) = true;
  return run_events(m, unit, reaction, settings);
}

EventSettings fine_teeth() {
  EventSettings s;
  // A fine saw-tooth: a tooth of ratio r falls short of the softening line by about (1 - r) / 2 of
  // the area it covers (1% here; measured 3.8% at r = 0.9 in pure mode I; the default 0.5 would
  // miss about 25% by the same estimate).
  s.tooth_stiffness_ratio = 0.98;
  s.last_tooth_stiffness = 1e-4;
  s.stop_fraction = 0;  // follow the bond until it breaks
  return s;
}

// Explicit: particle 1 moves at v along x, both particles prescribed, cycle by cycle until the
// bond breaks; the work on particle 1 integrated by the trapezoidal rule.
struct ExplicitPull {
  double peak_force = 0;  // largest F . x on the bond (the onset, within a cycle's travel)
  double work = 0;        // of the grip along the path [J]
  double released = 0;    // EnergyAccount::released [J]
  BondState mode = BondState::kIntact;
  long cycles = 0;
};

ExplicitPull pull_explicit(const Interface& f, double angle, ExplicitBackend kernel, double step,
                           StrengthStorage storage = StrengthStorage::kAutomatic) {
  Model m = interface_pair(f, angle);
  ExplicitSettings settings;
  settings.backend = kernel;
  settings.strength_storage = storage;
  settings.time_step = 1e-9;
  ExplicitIntegrator integrator(m, settings);
  const double v = step / settings.time_step;
  PrescribedMotion a, b;
  a.group = BoundaryGroup::kLeftGrip;
  b.group = BoundaryGroup::kRightGrip;
  b.velocity = Eigen::Vector3d(v, 0, 0);
  for (PrescribedMotion* p : {&a, &b}) {
    p->fix_velocity = {true, true, true};
    p->fix_angular_velocity = {true, true, true};
  }
  integrator.set_prescribed_motions({a, b});
  ExplicitPull r;
  double previous = 0;
  for (long c = 0; integrator.breaks().empty() && c < 200000; ++c) {
    integrator.cycle();
    // The force of cycle c acts at travel c step: the bond's pull on particle 1 is -F . x.
    const double force = -m.particles.force(1, 0);
    if (c > 0) r.work += 0.5 * (force + previous) * step;
    previous = force;
    r.peak_force = std::max(r.peak_force, force);
    r.cycles = c + 1;
  }
  REQUIRE(integrator.breaks().size() == 1);
  r.mode = integrator.breaks().front().mode;
  r.released = integrator.energy().released;
  return r;
}

}  // namespace

TEST_CASE("the mixed-mode law's onset and energy follow the quadratic criterion and BK") {
  const Interface f;
  for (const Case& c : cases(f)) {
    CAPTURE(c.name);
    const ClosedForm expected = closed_form(f, c.angle);
    const double travel = expected.onset_travel;  // unit load factor = onset travel

    // Events solver.
    Model m = interface_pair(f, c.angle);
    const EventsResult r = run_pull(m, travel, fine_teeth());
    REQUIRE(r.breaks.size() == 1);
    REQUIRE(!r.path.empty());
    CHECK(relative(r.path.front().load_factor, 1.0) < 1e-12);
    CHECK(relative(r.path.front().reaction, expected.onset_force) < 1e-12);
    const double area = area_under_path(r, travel);
    CHECK(relative(area, expected.energy) < 0.02);
    CHECK(relative(r.dissipated_energy, area) < 1e-9);
    CHECK(r.breaks.front().mode == expected.mode);
    std::printf(
        "mixed-mode %-8s B = %.3f: onset %.6g N (closed form %.6g N); events %zu teeth, "
        "energy %.5g J vs G_c(B) a = %.5g J (%+.2f%%)\n",
        c.name, expected.mix, r.path.front().reaction, expected.onset_force, r.path.size(), area,
        expected.energy, 100 * (area / expected.energy - 1));

    // Both explicit kernels (the fused one with strengths per type and per slot), about 200
    // cycles to the onset.
    for (const auto& [kernel, storage] :
         {std::pair{ExplicitBackend::kReference, StrengthStorage::kAutomatic},
          std::pair{ExplicitBackend::kCpu, StrengthStorage::kTypes},
          std::pair{ExplicitBackend::kCpu, StrengthStorage::kSlots}}) {
      const bool fused = kernel == ExplicitBackend::kCpu;
      const bool slots = storage == StrengthStorage::kSlots;
      CAPTURE(fused);
      CAPTURE(slots);
      const ExplicitPull e = pull_explicit(f, c.angle, kernel, travel / 200.3, storage);
      CHECK(relative(e.peak_force, expected.onset_force) < 1.0 / 200);
      CHECK(relative(e.work, expected.energy) < 0.02);
      CHECK(relative(e.released, e.work) < 0.01);
      CHECK(e.mode == expected.mode);
      std::printf(
          "mixed-mode %-8s %s kernel: peak %.6g N (%+.3f%%), %ld cycles, work %.5g J (%+.2f%%), "
          "released %.5g J\n",
          c.name, fused ? (slots ? "fused/slots" : "fused/types") : "reference", e.peak_force,
          100 * (e.peak_force / expected.onset_force - 1), e.cycles, e.work,
          100 * (e.work / expected.energy - 1), e.released);
    }
  }
}

TEST_CASE("the mixed-mode law dissipates GIc in pure mode I and GIIc in pure mode II") {
  const Interface f;
  const ClosedForm opening = closed_form(f, 0.0), sliding = closed_form(f, std::numbers::pi / 2);
  CHECK(opening.mix == 0.0);
  CHECK(sliding.mix == doctest::Approx(1.0).epsilon(1e-15));
  // The bond's kappa_u from the law at the two pure modes, against GIc a / E_I and GIIc a / E_II.
  const Model m = interface_pair(f, 0.0);
  const BondStrength s = bond_strength(m.bonds, 0);
  const double k_n = f.K_n * f.area, k_s = f.K_s * f.area;
  const double e_I = 0.5 * std::pow(f.N * f.area, 2) / k_n;
  const double e_II = 0.5 * std::pow(f.S * f.area, 2) / k_s;
  CHECK(relative(mixed_mode_ductility(0.0, s), f.GIc * f.area / e_I) < 1e-14);
  CHECK(relative(mixed_mode_ductility(1.0, s), f.GIIc * f.area / e_II) < 1e-14);
  for (double angle : {0.0, std::numbers::pi / 2}) {
    Model pull = interface_pair(f, angle);
    const ClosedForm expected = closed_form(f, angle);
    const EventsResult r = run_pull(pull, expected.onset_travel, fine_teeth());
    const double pure = angle == 0.0 ? f.GIc : f.GIIc;
    CHECK(relative(area_under_path(r, expected.onset_travel) / f.area, pure) < 0.02);
  }
}

TEST_CASE("in pure mode I the mixed-mode law is PFC's tension law: the same events") {
  // The same bond under the PFC law (exponent 0, the same kappa_I as ductility) and under the
  // mixed-mode law, opened along its normal: the same critical states.
  const Interface f;
  Model mixed = interface_pair(f, 0.0);
  Model pfc = mixed;
  pfc.bonds.mixed_mode_exponent(0) = 0;
  const double travel = closed_form(f, 0.0).onset_travel;
  EventSettings settings;
  settings.stop_fraction = 0;
  const EventsResult a = run_pull(mixed, travel, settings);
  const EventsResult b = run_pull(pfc, travel, settings);
  REQUIRE(a.breaks.size() == 1);
  REQUIRE(b.breaks.size() == 1);
  REQUIRE(a.path.size() == b.path.size());
  REQUIRE(a.path.size() > 1);
  for (std::size_t k = 0; k < a.path.size(); ++k) {
    CHECK(relative(a.path[k].load_factor, b.path[k].load_factor) < 1e-14);
    CHECK(relative(a.path[k].reaction, b.path[k].reaction) < 1e-14);
  }
  CHECK(a.breaks.front().mode == BondState::kBrokenTension);
  CHECK(a.breaks.front().mode == b.breaks.front().mode);
}

TEST_CASE("a brittle mixed-mode interface breaks at the quadratic onset in one event") {
  Interface f;
  f.GIc = f.GIIc = 0;
  const Case mixed = cases(f)[2];
  Model m = interface_pair(f, mixed.angle);
  CHECK(m.bonds.ductility(0) == 1.0);
  const ClosedForm expected = closed_form(f, mixed.angle);
  const EventsResult r = run_pull(m, expected.onset_travel, EventSettings{});
  REQUIRE(r.path.size() == 1);
  REQUIRE(r.breaks.size() == 1);
  CHECK(relative(r.path.front().reaction, expected.onset_force) < 1e-12);
  // PFC's max-stress law holds the same bond to the travel at which the larger component reaches
  // 1: sqrt(x^2 + y^2) / max(x, y) times the quadratic onset.
  Model pfc = interface_pair(f, mixed.angle);
  pfc.bonds.mixed_mode_exponent(0) = 0;
  const EventsResult p = run_pull(pfc, expected.onset_travel, EventSettings{});
  REQUIRE(p.path.size() == 1);
  REQUIRE(p.breaks.size() == 1);
  const double x = expected.opening, y = expected.sliding;
  CHECK(relative(p.path.front().load_factor, std::hypot(x, y) / std::max(x, y)) < 1e-12);
  CHECK(p.path.front().load_factor > 1.05);
}

TEST_CASE("bad mixed-mode input is refused by name") {
  auto refuses = [](const InterfaceStrength& s, const std::string& message) {
    CAPTURE(message);
    CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains(message.c_str()), Error);
  };
  InterfaceStrength s{40e6, 70e6, 300, 900};
  CHECK(s.bk_exponent == 2.284);
  CHECK_NOTHROW(s.validate());
  s.bk_exponent = 0;
  refuses(s, "interface.bk_exponent");
  s.bk_exponent = -1;
  refuses(s, "interface.bk_exponent");
  s.bk_exponent = std::numeric_limits<double>::quiet_NaN();
  refuses(s, "interface.bk_exponent");
  s.bk_exponent = std::numeric_limits<double>::infinity();
  refuses(s, "must be finite and > 0");
  s = InterfaceStrength{40e6, 70e6, 0, 900};
  refuses(s, "GIIc (900 J/m^2) needs GIc (interface.GIc)");
  // GIc alone: GIIc = GIc.
  s = InterfaceStrength{40e6, 70e6, 300, 0};
  CHECK_NOTHROW(s.validate());
  CHECK(s.mode_II_energy() == 300);

  // A model's mixed-mode bond: finite exponent, positive ratios, no friction.
  const Interface f;
  auto model_refuses = [&](auto change, const std::string& message) {
    CAPTURE(message);
    Model m = interface_pair(f, 0.3);
    change(m.bonds);
    CHECK_THROWS_WITH_AS(m.check_consistency(), doctest::Contains(message.c_str()), Error);
  };
  model_refuses([](Bonds& b) { b.mixed_mode_exponent(0) = -2; }, "mixed-mode exponent of -2");
  model_refuses([](Bonds& b) { b.mixed_mode_exponent(0) = std::nan(""); }, "mixed-mode exponent");
  model_refuses([](Bonds& b) { b.peak_energy_ratio(0) = 0; }, "peak energy ratio of 0");
  model_refuses([](Bonds& b) { b.fracture_energy_ratio(0) = -1; },
                "fracture energy ratio GIIc/GIc of -1");
  model_refuses([](Bonds& b) { b.friction_coefficient(0) = 0.2; },
                "the quadratic criterion has no friction term");
}
