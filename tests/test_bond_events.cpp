// The quasi-static events solver (solvers/bond_events.hpp): a chain breaks at its weakest bond at
// the load computed by hand; a fibre bundle behind a compliant spring follows the staircase (and
// snap-back) computed by hand; the Woodbury-updated path equals the refactor-every-event path on
// a hex2d coupon; a softening bond dissipates its saw-tooth's area, which tends to kappa_u E_peak;
// the energy dissipated by a notched coupon with softening bonds hardly depends on particle size;
// with failure at the material point a 90 deg ply cracks once, straight across, at YT; bad input
// is a clear error.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/failure_criteria.hpp"
#include "core/material.hpp"
#include "core/measurements.hpp"
#include "solvers/bond_events.hpp"
#include "strategies/cure_stress.hpp"
#include "strategies/registry.hpp"
#include "support/coupon_fixtures.hpp"
#include "support/events_path.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using plydem::test::area_under_path;
using plydem::test::grip_constraints;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;

double relative(double a, double b) {
  return std::abs(a - b) / std::max(std::abs(b), 1e-300);
}

// A model of particles at `positions` (radius r each) and no bonds yet.
Model particles_at(const std::vector<Eigen::Vector3d>& positions, double r) {
  Model m;
  Particles& p = m.particles;
  p.resize(static_cast<int>(positions.size()));
  for (int i = 0; i < p.size(); ++i) p.reference_position.row(i) = positions[i].transpose().array();
  p.radius.setConstant(r);
  p.mass.setConstant(1e-9);
  p.moment_of_inertia.setConstant(1e-19);
  p.volume.setConstant(1e-12);
  return m;
}

struct BondSpec {
  int first, second;
  double kn, ks, kb, kt;
  double radius = 0, tensile = kInf, cohesion = kInf, ductility = 1;
};

void add_bonds(Model& m, const std::vector<BondSpec>& specs) {
  Bonds& b = m.bonds;
  b.resize(static_cast<int>(specs.size()));
  for (int k = 0; k < b.size(); ++k) {
    const BondSpec& s = specs[k];
    b.first(k) = s.first;
    b.second(k) = s.second;
    b.normal_stiffness(k) = s.kn;
    b.shear_stiffness(k) = s.ks;
    b.bending_stiffness(k) = s.kb;
    b.twisting_stiffness(k) = s.kt;
    b.strength_radius(k) = s.radius;
    b.tensile_strength(k) = s.tensile;
    b.cohesion(k) = s.cohesion;
    b.ductility(k) = s.ductility;
    set_bond_geometry(m.particles, b, k);
  }
  m.check_consistency();
}

DofFlags flags_for(int particles) {
  return DofFlags::Constant(particles, kDofsPerParticle, false);
}

// `count_completion`: the edges by the count completion (strategies/boundary_cells.hpp), whose few
// weights (1, 1.5) suit a test that gives every bond one strength; edge equilibrium's weights (0.15
// to 3.4) would need their strengths scaled with them, as strategies/strength_calibration.hpp does.
Model hex2d_coupon(double length, double width, double diameter, double ply_angle = 0,
                   bool count_completion = false) {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = ply_angle;
  spec.length = length;
  spec.width = width;
  spec.particle_diameter = diameter;
  const auto strategy = default_registry().create("hex2d");
  if (count_completion) strategy->set_option("edge_equilibrium", 0);
  return strategy->build(spec).model;
}

// Five particles in a row along x, d apart, joined by four bonds of different stiffness and
// strength, the left end held and the right one pulled `travel` along x at unit load; the bond
// that breaks first in series (the smallest sigma_c pi R^2), its force, and the chain's compliance
// sum 1 / k_n, by hand.
struct Chain {
  static constexpr double d = 1e-4, travel = 1e-6;
  Model model;
  DofConstraints unit{5};
  DofFlags reaction = flags_for(5);
  int weakest = 0;
  double weakest_force = kInf, compliance = 0;
};

Chain chain() {
  Chain c;
  std::vector<Eigen::Vector3d> x;
  for (int i = 0; i < 5; ++i) x.emplace_back(i * Chain::d, 0, 0);
  c.model = particles_at(x, 0.5 * Chain::d);
  const std::vector<double> kn = {1e6, 2e6, 1.5e6, 3e6}, radius = {2e-5, 2.5e-5, 1.8e-5, 2.2e-5},
                            tensile = {60e6, 40e6, 50e6, 45e6};
  std::vector<BondSpec> specs;
  for (int b = 0; b < 4; ++b) {
    specs.push_back({b, b + 1, kn[b], 0.5e6, 1e-3, 1e-3, radius[b], tensile[b], 80e6, 1});
    c.compliance += 1 / kn[b];
    const double force = tensile[b] * kPi * radius[b] * radius[b];
    if (force < c.weakest_force) {
      c.weakest_force = force;
      c.weakest = b;
    }
  }
  add_bonds(c.model, specs);
  c.unit.fix_particle(0);
  c.unit.fix_particle(4, {Chain::travel, 0, 0});
  c.reaction(4, 0) = true;
  return c;
}

bool in_grip(const Model& m, int i, double d) {
  const Particles& p = m.particles;
  const double x = p.reference_position(i, 0);
  return x <= p.reference_position.col(0).minCoeff() + 2 * d ||
         x >= p.reference_position.col(0).maxCoeff() - 2 * d;
}

}  // namespace

TEST_CASE("a chain in series breaks at its weakest bond at the load factor computed by hand") {
  // In series every bond carries F = k_eff u with 1 / k_eff = sum 1 / k_n: the bond with the
  // smallest sigma_c pi R^2 breaks first, at lambda = sigma_c A / (k_eff travel).
  Chain c = chain();
  Model& m = c.model;
  const double d = Chain::d, travel = Chain::travel, compliance = c.compliance;
  const double weakest_force = c.weakest_force;
  const int weakest = c.weakest;
  const double lambda = weakest_force * compliance / travel;

  const EventsResult r = run_events(m, c.unit, c.reaction);
  REQUIRE(r.path.size() == 1);
  CHECK(r.path[0].bond == weakest);
  CHECK(relative(r.path[0].load_factor, lambda) < 1e-12);
  CHECK(relative(r.path[0].reaction, weakest_force) < 1e-12);
  CHECK(r.path[0].broken == 1);
  CHECK(relative(r.path[0].strain_energy, 0.5 * weakest_force * weakest_force * compliance) <
        1e-12);
  CHECK(r.stop == "failed");
  REQUIRE(r.breaks.size() == 1);
  CHECK(r.breaks[0].bond == weakest);
  CHECK(r.breaks[0].mode == BondState::kBrokenTension);
  CHECK(r.breaks[0].at == 1);
  CHECK(r.breaks[0].load == doctest::Approx(lambda).epsilon(1e-12));
  CHECK(r.breaks[0].position.x() == doctest::Approx((weakest + 0.5) * d).epsilon(1e-12));
  CHECK(m.bonds.is_broken(weakest));
  CHECK(m.bonds.normal_stiffness(weakest) == 0);
  CHECK(m.bonds.damage(weakest) == 1);
  // The chain falls apart: everything it held is released.
  CHECK(relative(r.dissipated_energy, 0.5 * weakest_force * weakest_force * compliance) < 1e-10);
  CHECK(relative(r.dissipated_energy, area_under_path(r, travel)) < 1e-10);
  // The model is left at the critical state: the pulled end at lambda times its travel.
  CHECK(relative(m.particles.displacement(4, 0), lambda * travel) < 1e-12);
  CHECK(m.particles.displacement(2, 0) > 0);
}

TEST_CASE("a chain under a preload and free offsets breaks where the load computed by hand says") {
  // The chain of the case above, its right end held at p0 before the load (the preload) and two
  // bonds given free offsets q (a shrinkage: they carry no force at du = q). In series every bond
  // carries F = k_eff (p0 + lambda travel - sum q): the weakest breaks at
  // lambda = (F_c / k_eff - p0 + sum q) / travel, the reaction is F, the strain energy
  // F^2 / (2 k_eff). An offset larger than the preload's stretch leaves the chain in compression
  // before the load; one that stretches it past F_c breaks the weakest bond at lambda = 0.
  const double travel = Chain::travel;
  struct Case {
    double preload, offset;  // p0 and each of the two bonds' offset q, in travels
  };
  for (const Case& c : {Case{0.05, 0.0}, Case{0.04, -0.02}, Case{-0.4, 0.25}, Case{0.15, 0.0}}) {
    CAPTURE(c.preload);
    CAPTURE(c.offset);
    Chain held = chain();
    Model& m = held.model;
    const double compliance = held.compliance, weakest_force = held.weakest_force;
    const int weakest = held.weakest;
    for (int b : {0, 2}) m.bonds.free_offset(b, 0) = c.offset * travel;
    EventSettings settings;
    settings.preload = DofArray::Zero(5, kDofsPerParticle);
    settings.preload(4, 0) = c.preload * travel;

    const double before = c.preload * travel - 2 * c.offset * travel;  // stretch less offsets
    const double lambda = std::max(0.0, (weakest_force * compliance - before) / travel);
    const double force = (before + lambda * travel) / compliance;
    const EventsResult r = run_events(m, held.unit, held.reaction, settings);
    REQUIRE(r.path.size() == 1);
    CHECK(r.path[0].bond == weakest);
    CHECK(std::abs(r.path[0].load_factor - lambda) < 1e-12 * std::max(1.0, lambda));
    CHECK(relative(r.path[0].reaction, force) < 1e-10);
    CHECK(relative(r.path[0].strain_energy, 0.5 * force * force * compliance) < 1e-10);
    CHECK(r.stop == "failed");
    // Everything the chain held is released when it falls apart, the preload's part too.
    CHECK(relative(r.dissipated_energy, 0.5 * force * force * compliance) < 1e-9);
    // Left at the critical state: the pulled end at p0 + lambda travel.
    CHECK(relative(m.particles.displacement(4, 0), c.preload * travel + lambda * travel) < 1e-12);
  }
}

TEST_CASE("a chain held only along x: the particle that comes loose is fixed and the rest pinned") {
  // The ends prescribe ux (and uz, theta_x, theta_y) only: the rigid modes in the x-y plane are
  // pinned. When the end bond breaks, the end particle keeps free dofs (uy, theta_z) and no bond,
  // and the rest of the chain keeps its pins: the solver fixes the lone particle, factors afresh,
  // finds the grips disconnected and stops.
  const double d = 1e-4, travel = 1e-6;
  std::vector<Eigen::Vector3d> x;
  for (int i = 0; i < 5; ++i) x.emplace_back(i * d, 0, 0);
  Model m = particles_at(x, 0.5 * d);
  std::vector<BondSpec> specs;
  for (int b = 0; b < 4; ++b)
    specs.push_back({b, b + 1, 1e6, 0.5e6, 1e-3, 1e-3, 2e-5, b == 0 ? 40e6 : 60e6, kInf});
  add_bonds(m, specs);
  DofConstraints unit(5);
  for (int i : {0, 4}) {
    unit.fix(i, Dof::kUx, i == 4 ? travel : 0.0);
    unit.fix(i, Dof::kUz);
    unit.fix(i, Dof::kThetaX);
    unit.fix(i, Dof::kThetaY);
  }
  DofFlags reaction = flags_for(5);
  reaction(4, 0) = true;
  EventSettings settings;
  settings.static_settings.pin_rigid_modes = true;
  const EventsResult r = run_events(m, unit, reaction, settings);
  REQUIRE(r.path.size() == 1);
  CHECK(r.path[0].bond == 0);
  // Four equal springs in series: lambda = sigma_c A / (k_n / 4 travel).
  CHECK(relative(r.path[0].load_factor, 40e6 * kPi * 4e-10 * 4 / (1e6 * travel)) < 1e-12);
  CHECK(r.stop == "failed");
  CHECK(r.message.empty());
  CHECK(r.factorizations == 2);
}

TEST_CASE("equal critical loads: the lowest bond index breaks first") {
  const double d = 1e-4;
  std::vector<Eigen::Vector3d> x;
  for (int i = 0; i < 4; ++i) x.emplace_back(i * d, 0, 0);
  Model m = particles_at(x, 0.5 * d);
  // Bonds 0 and 2 are the same (and so equally loaded in series); bond 1 is stronger.
  add_bonds(m, {{0, 1, 1e6, 5e5, 1e-3, 1e-3, 2e-5, 40e6, kInf},
                {1, 2, 2e6, 5e5, 1e-3, 1e-3, 2e-5, 90e6, kInf},
                {2, 3, 1e6, 5e5, 1e-3, 1e-3, 2e-5, 40e6, kInf}});
  DofConstraints unit(4);
  unit.fix_particle(0);
  unit.fix_particle(3, {1e-6, 0, 0});
  DofFlags reaction = flags_for(4);
  reaction(3, 0) = true;
  const EventsResult r = run_events(m, unit, reaction);
  REQUIRE(!r.path.empty());
  CHECK(r.path[0].bond == 0);
}

TEST_CASE("a fibre bundle behind a spring follows the staircase by hand, snap-backs included") {
  // Five fibres from fixed particles on a cone to one particle M that moves along x only, M held
  // by a spring to the grip G: equal load sharing with a compliant machine.
  const int fibres = 5;
  const double l = 1e-4, rho = 0.3e-4, travel = 1e-6, radius = 1e-5;
  std::vector<Eigen::Vector3d> x = {{0, 0, 0}, {l, 0, 0}};  // M, G
  for (int i = 0; i < fibres; ++i) {
    const double phi = 2 * kPi * i / fibres;
    x.emplace_back(-l, rho * std::cos(phi), rho * std::sin(phi));
  }
  Model m = particles_at(x, 1e-5);
  const double kn = 1e6, ks = 0.3e6, ke = 2e6;
  std::vector<BondSpec> specs = {{0, 1, ke, 1e6, 1e-4, 1e-4}};  // the spring, unbreakable
  std::vector<double> strength;
  for (int i = 0; i < fibres; ++i) {
    strength.push_back(100e6 * (1 + 0.02 * i));
    // Out of order in the bond list, so that the order of failure is the strengths' order.
    specs.push_back({2 + (3 * i) % fibres, 0, kn, ks, 1e-4, 1e-4, radius, 0, kInf});
  }
  for (int i = 0; i < fibres; ++i) specs[1 + i].tensile = strength[(3 * i) % fibres];
  add_bonds(m, specs);
  DofConstraints unit(static_cast<int>(x.size()));
  for (int i = 2; i < static_cast<int>(x.size()); ++i) unit.fix_particle(i);
  unit.fix_particle(1, {travel, 0, 0});
  for (Dof dof : {Dof::kUy, Dof::kUz, Dof::kThetaX, Dof::kThetaY, Dof::kThetaZ}) unit.fix(0, dof);
  DofFlags reaction = flags_for(static_cast<int>(x.size()));
  reaction(1, 0) = true;

  // By hand: every fibre has cos(alpha) = l / sqrt(l^2 + rho^2) to x and adds
  // k_x = k_n cos^2 + k_s sin^2 to M's stiffness along x; M moves u_M = k_e travel / k_M; a fibre
  // is stretched u_M cos(alpha) and fails at lambda = sigma_c A / (k_n u_M cos(alpha)).
  const double cos_a = l / std::hypot(l, rho), sin_a = rho / std::hypot(l, rho);
  const double kx = kn * cos_a * cos_a + ks * sin_a * sin_a, area = kPi * radius * radius;
  EventSettings settings;
  settings.stop_fraction = 0;  // to the last fibre
  const EventsResult r = run_events(m, unit, reaction, settings);
  REQUIRE(r.path.size() == static_cast<std::size_t>(fibres));
  bool snap_back = false;
  for (int k = 0; k < fibres; ++k) {
    const double k_m = ke + (fibres - k) * kx, u_m = ke * travel / k_m;
    const double lambda = strength[k] * area / (kn * u_m * cos_a);
    CAPTURE(k);
    CHECK(relative(r.path[k].load_factor, lambda) < 1e-10);
    CHECK(relative(r.path[k].reaction, lambda * ke * (travel - u_m)) < 1e-10);
    CHECK(m.bonds.tensile_strength(r.path[k].bond) == strength[k]);
    CHECK(r.path[k].broken == k + 1);
    if (k > 0 && r.path[k].load_factor < r.path[k - 1].load_factor) snap_back = true;
  }
  CHECK(snap_back);
  CHECK(r.peak == 0);
  CHECK(r.stop == "failed");
  CHECK(r.breaks.size() == static_cast<std::size_t>(fibres));
  // Completely failed (the spring ends unloaded): the energy released is the grips' work.
  CHECK(r.dissipated_energy > 0);
  CHECK(relative(r.dissipated_energy, area_under_path(r, travel)) < 1e-10);
}

TEST_CASE("the Woodbury-updated path equals the refactor-every-event path on a hex2d coupon") {
  const double d = 0.1e-3, travel = 1e-6;
  for (const double ductility : {1.0, 3.0}) {
    CAPTURE(ductility);
    Model built = hex2d_coupon(2e-3, 0.5e-3, d);
    for (int b = 0; b < built.bonds.size(); ++b) {
      built.bonds.strength_radius(b) = 0.25 * d;
      built.bonds.tensile_strength(b) = 60e6;
      built.bonds.cohesion(b) = 80e6;
      built.bonds.friction_coefficient(b) = 0.2;
      built.bonds.ductility(b) = ductility;
    }
    DofConstraints unit;
    DofFlags reaction;
    grip_constraints(built, d, travel, unit, reaction);
    EventSettings settings;
    settings.static_settings.pin_rigid_modes = true;
    settings.max_events = ductility > 1 ? 400 : 2000;
    settings.max_update_rank = 60;  // several refactorizations along the way
    Model updated = built, refactored = built;
    const EventsResult a = run_events(updated, unit, reaction, settings);
    settings.refactor_every_event = true;
    const EventsResult b = run_events(refactored, unit, reaction, settings);
    MESSAGE(fmt::format("ductility {}: {} events, {} broken, stop '{}', {} vs {} factorizations",
                        ductility, a.path.size(), a.breaks.size(), a.stop, a.factorizations,
                        b.factorizations));
    REQUIRE(a.path.size() == b.path.size());
    CHECK(a.path.size() > 10);
    CHECK(a.factorizations < b.factorizations);
    CHECK(b.factorizations >= static_cast<int>(b.path.size()));
    double worst = 0;
    int same = 0;
    for (std::size_t k = 0; k < a.path.size(); ++k) {
      same += a.path[k].bond == b.path[k].bond ? 1 : 0;
      worst = std::max({worst, relative(a.path[k].load_factor, b.path[k].load_factor),
                        relative(a.path[k].reaction, b.path[k].reaction)});
    }
    CHECK(same == static_cast<int>(a.path.size()));
    CHECK(worst < 1e-9);
    CHECK(relative(a.dissipated_energy, b.dissipated_energy) < 1e-9);
    CHECK(a.stop == b.stop);
    if (ductility == 1.0) {
      CHECK(a.stop == "failed");
      CHECK(relative(a.dissipated_energy, area_under_path(a, travel)) < 1e-8);
    }
  }
}

namespace {

// The saw-tooth of one softening bond held between fixed grips (its deformation is the grips'):
// the energy it dissipates, in units of its elastic energy at the peak, with the teeth of
// solvers/bond_events.hpp worked out on the traction-separation diagram. In units of the peak
// (force 1 at separation 1), the softening line is F = (kappa_u - kappa) / (kappa_u - 1); a
// tooth of stiffness s meets it at s kappa = F, kappa = kappa_u / (1 + s (kappa_u - 1)); at a drop
// from s to s' at fixed separation kappa the bond releases 1/2 (s - s') kappa^2, and the last
// tooth (the next would be below the floor) is loaded to kappa_u and releases 1/2 s kappa_u^2.
double sawtooth_energy(double kappa_u, double r, double floor) {
  double s = 1, released = 0;
  while (s * r >= floor) {
    const double kappa = kappa_u / (1 + s * (kappa_u - 1));
    released += 0.5 * (s - s * r) * kappa * kappa;
    s *= r;
  }
  return (released + 0.5 * s * kappa_u * kappa_u) / 0.5;
}

}  // namespace

TEST_CASE("a softening bond dissipates its saw-tooth's area, which tends to kappa_u E_peak") {
  const double d = 1e-4, travel = 1e-7, kn = 1e6, radius = 2e-5, tensile = 50e6, kappa_u = 3;
  const double area = kPi * radius * radius;
  const double peak_energy = 0.5 * std::pow(tensile * area, 2) / kn;
  double previous_error = kInf;
  for (const double r : {0.5, 0.8, 0.95, 0.99}) {
    CAPTURE(r);
    Model m = particles_at({{0, 0, 0}, {d, 0, 0}}, 0.5 * d);
    add_bonds(m, {{0, 1, kn, 0.5e6, 1e-3, 1e-3, radius, tensile, kInf, kappa_u}});
    DofConstraints unit(2);
    unit.fix_particle(0);
    unit.fix_particle(1, {travel, 0, 0});
    DofFlags reaction = flags_for(2);
    reaction(1, 0) = true;
    EventSettings settings;
    settings.tooth_stiffness_ratio = r;
    settings.stop_fraction = 0;
    const EventsResult result = run_events(m, unit, reaction, settings);
    CHECK(result.stop == "failed");
    CHECK(result.breaks.size() == 1);
    // The first tooth is the elastic peak: lambda = sigma_c A / (k_n travel).
    CHECK(relative(result.path[0].load_factor, tensile * area / (kn * travel)) < 1e-12);
    // The last tooth ends at kappa_u.
    CHECK(relative(result.path.back().load_factor, kappa_u * tensile * area / (kn * travel)) <
          1e-12);
    const double expected = sawtooth_energy(kappa_u, r, settings.last_tooth_stiffness);
    CHECK(relative(result.dissipated_energy / peak_energy, expected) < 1e-10);
    CHECK(relative(result.dissipated_energy, area_under_path(result, travel)) < 1e-10);
    // The bound: every tooth but the last lies under the softening line, and the last adds at
    // most its own triangle 1/2 s kappa_u^2 with s < floor / r.
    const double bound =
        kappa_u + settings.last_tooth_stiffness / r * kappa_u * kappa_u;  // in E_peak
    CHECK(result.dissipated_energy / peak_energy <= bound);
    const double error = std::abs(result.dissipated_energy / (kappa_u * peak_energy) - 1);
    MESSAGE(fmt::format("tooth ratio {}: {} events, dissipated {:.4f} kappa_u E_peak", r,
                        result.path.size(), result.dissipated_energy / (kappa_u * peak_energy)));
    CHECK(error < previous_error);
    previous_error = error;
  }
  CHECK(previous_error < 0.005);
}

TEST_CASE("a softening bond in series with a spring: the energy account and the triangle") {
  // Snap-backs at every tooth: the released energy is still the area under the path, and tends to
  // kappa_u E_peak as the teeth get finer.
  const double d = 1e-4, travel = 1e-7, kn = 1e6, radius = 2e-5, tensile = 50e6, kappa_u = 4;
  const double peak_energy = 0.5 * std::pow(tensile * kPi * radius * radius, 2) / kn;
  std::vector<double> errors;
  for (const double r : {0.5, 0.9, 0.99}) {
    Model m = particles_at({{0, 0, 0}, {d, 0, 0}, {2 * d, 0, 0}}, 0.5 * d);
    add_bonds(m, {{0, 1, kn, 0.5e6, 1e-3, 1e-3, radius, tensile, kInf, kappa_u},
                  {1, 2, 3 * kn, 1e6, 1e-3, 1e-3}});
    DofConstraints unit(3);
    unit.fix_particle(0);
    unit.fix_particle(2, {travel, 0, 0});
    DofFlags reaction = flags_for(3);
    reaction(2, 0) = true;
    EventSettings settings;
    settings.tooth_stiffness_ratio = r;
    settings.stop_fraction = 0;
    const EventsResult result = run_events(m, unit, reaction, settings);
    CAPTURE(r);
    CHECK(result.stop == "failed");
    CHECK(relative(result.dissipated_energy, area_under_path(result, travel)) < 1e-9);
    errors.push_back(std::abs(result.dissipated_energy / (kappa_u * peak_energy) - 1));
    MESSAGE(fmt::format("tooth ratio {}: {} events, dissipated {:.4f} kappa_u E_peak", r,
                        result.path.size(), result.dissipated_energy / (kappa_u * peak_energy)));
  }
  CHECK(errors[1] < errors[0]);
  CHECK(errors[2] < errors[1]);
  CHECK(errors[2] < 0.01);
}

namespace {

// A notched 90 deg hex2d coupon (transverse tension: the crack runs along the fibres, straight
// across the load) with softening bonds set by hand from a fracture energy G.
// - Crack area. Every bond of the hexagonal layer stands for a third of a particle's volume
//   V = sqrt(3)/2 d^2 t (six bonds, each shared by two particles), so its share of crack area is
//   A_crack = V / (3 L), L = d its length.
// - Strength. The bond's section has the particle's radius, R = d/2 (A = pi R^2 scales as d^2,
//   like the bending and twisting terms of the criterion, so that the criterion's mix of axial
//   and bending stress is the same at every size), and its tensile strength makes the axial force
//   at failure sigma_t A_crack (sigma_c = sigma_t A_crack / A): the same force per unit of crack
//   area at every size. Cohesion = sigma_c.
// - Ductility. In pure tension the bond holds E_peak = (sigma_c A)^2 / (2 k_n) at its peak, so
//   kappa_u = G A_crack / E_peak (bond_ductility) makes it dissipate G A_crack there.
// - Notch. The bonds crossing the mid-length below y = 0.3 mm, broken beforehand: 0.3 mm falls
//   between two rows of bond midpoints at both sizes (d = 0.1 mm: midpoints at 0.075 + 0.05 k;
//   d = 0.05 mm: 0.0375 + 0.025 k), so that both lattices have the same notch. Bonds touching a
//   grip never break.
struct NotchedRun {
  EventsResult result;
  int particles = 0;
  double kappa_u = 0;       // the largest of the bonds'
  double crack_energy = 0;  // G times the crack area of the intact bonds across the mid-length
};

NotchedRun notched_run(double d, double tooth_ratio, long max_events) {
  const double length = 2e-3, width = 1e-3, thickness = 0.2e-3;  // CouponSpec's default t
  const double fracture_energy = 100, tensile = 200e6, notch = 0.3e-3;
  Model m = hex2d_coupon(length, width, d, 90 * std::numbers::pi / 180, true);
  const double crack_area = std::sqrt(3.0) / 2 * d * d * thickness / (3 * d);
  const double radius = 0.5 * d, sigma_c = tensile * crack_area / (kPi * radius * radius);
  NotchedRun run;
  run.particles = m.particles.size();
  Bonds& b = m.bonds;
  const Vector3Array& x = m.particles.reference_position;
  const double x_mid = 0.5 * (x.col(0).minCoeff() + x.col(0).maxCoeff());
  for (int k = 0; k < b.size(); ++k) {
    const int i = b.first(k), j = b.second(k);
    if (in_grip(m, i, d) || in_grip(m, j, d)) continue;
    const bool across = (x(i, 0) - x_mid) * (x(j, 0) - x_mid) < 0;
    if (across && 0.5 * (x(i, 1) + x(j, 1)) < notch) {
      b.normal_stiffness(k) = b.shear_stiffness(k) = 0;
      b.bending_stiffness(k) = b.twisting_stiffness(k) = 0;
      b.damage(k) = 1;
      b.state(k) = static_cast<int>(BondState::kBrokenTension);
      continue;
    }
    if (across) run.crack_energy += fracture_energy * crack_area;
    b.strength_radius(k) = radius;
    b.tensile_strength(k) = sigma_c;
    b.cohesion(k) = sigma_c;
    const double peak_energy =
        std::pow(sigma_c * kPi * radius * radius, 2) / (2 * b.normal_stiffness(k));
    b.ductility(k) = bond_ductility(fracture_energy, crack_area, peak_energy);
    run.kappa_u = std::max(run.kappa_u, b.ductility(k));
  }
  DofConstraints unit;
  DofFlags reaction;
  grip_constraints(m, d, 1e-6, unit, reaction);
  EventSettings settings;
  settings.static_settings.pin_rigid_modes = true;
  settings.tooth_stiffness_ratio = tooth_ratio;
  settings.stop_fraction = 0;  // to complete failure: everything the grips did is dissipated
  settings.max_events = max_events;
  run.result = run_events(m, unit, reaction, settings);
  return run;
}

std::string describe(const NotchedRun& run, double d, double tooth_ratio) {
  return fmt::format(
      "d {} mm, tooth ratio {}: {} particles, kappa_u up to {:.3g}, {} events, {} broken, {} "
      "factorizations, {:.1f} s, stop '{}', dissipated {:.4g} J = {:.3f} G A_crack(ligament)",
      d * 1e3, tooth_ratio, run.particles, run.kappa_u, run.result.path.size(),
      run.result.breaks.size(), run.result.factorizations, run.result.wall_seconds, run.result.stop,
      run.result.dissipated_energy, run.result.dissipated_energy / run.crack_energy);
}

}  // namespace

TEST_CASE("a notched coupon with softening bonds, small: runs to complete failure") {
  const NotchedRun run = notched_run(0.125e-3, 0.8, 100000);
  MESSAGE(describe(run, 0.125e-3, 0.8));
  CHECK(run.result.stop == "failed");
  CHECK(run.kappa_u > 1);
  CHECK(run.result.dissipated_energy > 0);
  CHECK(relative(run.result.dissipated_energy, area_under_path(run.result, 1e-6)) < 1e-8);
}

// Measured (this machine, 2 x 1 mm, 209 and 897 particles): with tooth ratio 0.8 the two sizes
// dissipate 5.695e-6 and 5.715e-6 J (0.35%), with 0.9 5.703e-6 and 5.821e-6 J (2.1%), but with
// the default 0.5 5.713e-6 and 5.340e-6 J (6.5%): three teeth per bond are too coarse a
// saw-tooth for the energy to be regularized. The check runs at 0.8 and prints the 0.5 figures.
// The same coupon at 0 deg (it splits along the lattice's inclined families instead of one
// straight crack) dissipated 1.839e-5 and 1.814e-5 J at 0.8 (1.4%), 9.5% apart at 0.5.
// Either way the coupon dissipates about 0.75 G per unit of crack area, not G: the bonds across
// this crack (at +-30 deg to the load) fail with bending and shear, at less elastic energy than
// the pure-tension E_peak their kappa_u was set from.
TEST_CASE("size effect: the energy a notched coupon dissipates changes < 5% as d halves") {
  const NotchedRun coarse = notched_run(0.1e-3, 0.8, 400000);
  const NotchedRun fine = notched_run(0.05e-3, 0.8, 400000);
  MESSAGE(describe(coarse, 0.1e-3, 0.8));
  MESSAGE(describe(fine, 0.05e-3, 0.8));
  CHECK(coarse.result.stop == "failed");
  CHECK(fine.result.stop == "failed");
  CHECK(relative(fine.result.dissipated_energy, coarse.result.dissipated_energy) < 0.05);
  const NotchedRun coarse_teeth = notched_run(0.1e-3, 0.5, 400000);
  const NotchedRun fine_teeth = notched_run(0.05e-3, 0.5, 400000);
  MESSAGE(describe(coarse_teeth, 0.1e-3, 0.5));
  MESSAGE(describe(fine_teeth, 0.05e-3, 0.5));
  MESSAGE(fmt::format(
      "tooth ratio 0.5: the dissipated energy changes by {:.1f}% as d halves",
      100 * relative(fine_teeth.result.dissipated_energy, coarse_teeth.result.dissipated_energy)));
}

TEST_CASE("bad input to the events solver is a clear error") {
  const double d = 1e-4;
  Model m = particles_at({{0, 0, 0}, {d, 0, 0}}, 0.5 * d);
  add_bonds(m, {{0, 1, 1e6, 5e5, 1e-3, 1e-3}});
  DofConstraints unit(2);
  unit.fix_particle(0);
  unit.fix_particle(1, {1e-6, 0, 0});
  DofFlags reaction = flags_for(2);
  reaction(1, 0) = true;
  auto message = [&](Model model, const DofConstraints& c, const DofFlags& f,
                     const EventSettings& s) -> std::string {
    try {
      run_events(model, c, f, s);
    } catch (const Error& e) {
      return e.what();
    }
    return "(no error)";
  };
  CHECK(message(m, unit, reaction, {}).find("unbreakable") != std::string::npos);
  m.bonds.strength_radius(0) = 2e-5;
  m.bonds.tensile_strength(0) = 50e6;
  CHECK(message(m, unit, reaction, {}) == "(no error)");

  EventSettings bad;
  bad.tooth_stiffness_ratio = 1;
  CHECK(message(m, unit, reaction, bad).find("tooth_stiffness_ratio") != std::string::npos);
  bad = {};
  bad.last_tooth_stiffness = 0.6;
  CHECK(message(m, unit, reaction, bad).find("last_tooth_stiffness") != std::string::npos);
  bad = {};
  bad.max_events = 0;
  CHECK(message(m, unit, reaction, bad).find("max_events") != std::string::npos);
  bad = {};
  bad.static_settings.method = StaticMethod::kIterative;
  CHECK(message(m, unit, reaction, bad).find("direct method") != std::string::npos);

  DofFlags free_flag = flags_for(2);
  free_flag(1, 0) = true;
  free_flag(1, 1) = true;
  DofConstraints partly(2);
  partly.fix_particle(0);
  partly.fix(1, Dof::kUx, 1e-6);
  CHECK(message(m, partly, free_flag, {}).find("not prescribed") != std::string::npos);
  CHECK(message(m, unit, flags_for(2), {}).find("no reaction dof") != std::string::npos);

  Model nan = m;
  nan.bonds.tensile_strength(0) = std::nan("");
  CHECK(message(nan, unit, reaction, {}).find("tensile strength") != std::string::npos);
  Model negative = m;
  negative.bonds.cohesion(0) = -1;
  CHECK(message(negative, unit, reaction, {}).find("cohesion") != std::string::npos);
  Model missing_radius = m;
  missing_radius.bonds.strength_radius(0) = 0;
  CHECK(message(missing_radius, unit, reaction, {}).find("radius") != std::string::npos);
}

TEST_CASE("progress and event hooks see every critical state") {
  const double d = 1e-4, travel = 1e-7;
  Model m = particles_at({{0, 0, 0}, {d, 0, 0}}, 0.5 * d);
  add_bonds(m, {{0, 1, 1e6, 5e5, 1e-3, 1e-3, 2e-5, 50e6, kInf, 2.0}});
  DofConstraints unit(2);
  unit.fix_particle(0);
  unit.fix_particle(1, {travel, 0, 0});
  DofFlags reaction = flags_for(2);
  reaction(1, 0) = true;
  EventSettings settings;
  settings.stop_fraction = 0;
  long seen = 0;
  bool states_match = true;
  settings.on_event = [&](const Model& model, const EventPoint& p) {
    ++seen;
    states_match = states_match && p.event == seen &&
                   relative(model.particles.displacement(1, 0), p.load_factor * travel) < 1e-12 &&
                   relative(-model.particles.force(1, 0), p.reaction) < 1e-12;
  };
  long progress_calls = 0;
  settings.progress_seconds = 1e-12;
  settings.on_progress = [&](const EventProgress&) { ++progress_calls; };
  const EventsResult r = run_events(m, unit, reaction, settings);
  CHECK(seen == static_cast<long>(r.path.size()));
  CHECK(states_match);
  CHECK(progress_calls >= 1);
  settings.max_events = 3;
  Model again = particles_at({{0, 0, 0}, {d, 0, 0}}, 0.5 * d);
  add_bonds(again, {{0, 1, 1e6, 5e5, 1e-3, 1e-3, 2e-5, 50e6, kInf, 2.0}});
  seen = 0;
  const EventsResult limited = run_events(again, unit, reaction, settings);
  CHECK(limited.stop == "event limit");
  CHECK(limited.path.size() == 3);
}

namespace {

// The built 90 deg E-glass coupon whose in-ply bonds have no strength of their own (they open only
// with their sites), its grips' unit load, and the events run with failure at the material point
// by `criterion`. `cross_section`: the gauge's mean cross-section (core/measurements.hpp).
struct MaterialPointRun {
  Model model;
  EventsResult result;
  double cross_section = 0;
};

MaterialPointRun material_point_run(const char* material, const char* strategy, double degrees,
                                    double diameter, FailureCriterion criterion) {
  CouponSpec spec;
  spec.material = load_material(material);
  spec.ply_angle = degrees * kPi / 180;
  spec.length = 3e-3;
  spec.width = 1e-3;
  spec.particle_diameter = diameter;
  MaterialPointRun run{default_registry().create(strategy)->build(spec).model, {}, 0};
  Bonds& bonds = run.model.bonds;
  for (int b = 0; b < bonds.size(); ++b) bonds.tensile_strength(b) = bonds.cohesion(b) = kInf;
  const Particles& p = run.model.particles;
  const double x0 = p.reference_position.col(0).minCoeff();
  const double x1 = p.reference_position.col(0).maxCoeff();
  run.cross_section = cross_section_area(p, x0 + 0.3 * (x1 - x0), x1 - 0.3 * (x1 - x0), diameter);
  // Grips that move with the uniaxial stress state of CLT (u = eps x, eps = Q-bar^-1 (1, 0, 0)
  // scaled), so that no grip edge concentrates stress: every site carries the nominal stress.
  const Eigen::Vector3d eps =
      test::qbar_by_hand(spec.material, spec.ply_angle).inverse() * Eigen::Vector3d(1, 0, 0);
  DofConstraints unit;
  DofFlags reaction;
  test::affine_grips(run.model, diameter, 1e-3 * eps / eps(0), unit, reaction);
  EventSettings settings;
  settings.material_point = MaterialPointFailure{criterion, spec.material, {spec.ply_angle}};
  run.result = run_events(run.model, unit, reaction, settings);
  return run;
}

}  // namespace

TEST_CASE("at the material point a ply cracks once, straight across its width, at its strength") {
  // E-glass/MY750 and T300/914C at 90 deg (matrix tension: YT), the crack a plane along the fibres
  // across the width. (At 0 deg the peak is XT, within 8e-5, but the crack splits along the
  // fibres instead of running across them: a single site's crack leaves the crossing diagonals
  // of its neighbours, and the stiff fibre bonds load them; not yet a test.) The square lattice's
  // edges run along its lattice lines, so its coupon is uniform up to the grips and the peak is the
  // strength; hex2d's edges cut its lattice at 90 deg and its edge strips' balance is a least-norm
  // fit (strategies/boundary_cells.hpp): a site beside the grips carries a few per cent more than
  // the gauge, and cracks first.
  struct Case {
    const char* material;
    double degrees;
  };
  for (const Case& c : {Case{"eglass-my750", 90}, Case{"t300-914c", 90}}) {
    const LaminaStrength strength = load_material(c.material).strength;
    const double expected = strength.YT;
    for (const char* strategy : {"square", "hex2d"}) {
      // hex2d cannot represent the carbon ply (its calibration refuses it).
      if (std::string(strategy) == "hex2d" && std::string(c.material) != "eglass-my750") continue;
      for (double diameter : {0.1e-3, 0.05e-3}) {
        CAPTURE(std::string(c.material));
        CAPTURE(c.degrees);
        CAPTURE(std::string(strategy));
        CAPTURE(diameter);
        const MaterialPointRun run =
            material_point_run(c.material, strategy, c.degrees, diameter, FailureCriterion::kPuck);
        const EventsResult& r = run.result;
        REQUIRE(!r.path.empty());
        CHECK(r.stop == "failed");
        const double peak = r.path[static_cast<std::size_t>(r.peak)].reaction / run.cross_section;
        // Every broken bond lies on one crack: their contact points share one x within a
        // diameter.
        double x_min = kInf, x_max = -kInf;
        for (const BondBreak& b : r.breaks) {
          x_min = std::min(x_min, b.position.x());
          x_max = std::max(x_max, b.position.x());
        }
        MESSAGE(std::string(c.material)
                << " " << c.degrees << " deg, " << std::string(strategy) << " " << (diameter * 1e3)
                << " mm: peak " << peak / 1e6 << " MPa (strength " << expected / 1e6 << "), "
                << r.path.size() << " events, " << r.breaks.size() << " bonds broken, crack "
                << (x_max - x_min) * 1e3 << " mm wide");
        if (std::string(strategy) == "square") {
          // Measured: within 1.1e-4 (E-glass) and 3.6e-4 (T300/914C), in 11 and 21 events (one
          // per site across the width, and the last), one column of sites wide.
          CHECK(relative(peak, expected) < 2e-3);
          CHECK(x_max - x_min <= 1.01 * diameter);
        } else {
          // Measured: 4.3% and 1.8% low, the first site beside a grip.
          CHECK(relative(peak, expected) < 0.05);
        }
      }
    }
  }
}

TEST_CASE("a 90 deg ply held along x as it cools cracks at YT less its held cure stress") {
  // A 90 deg E-glass ply cooled by 50 K while held along x and free across: its cure is the
  // uniform state eps_x = 0, sigma_y = 0, so sigma_x = -E2 alpha2 delta_T everywhere (x lies across
  // the fibres) and eps_y = (alpha1 + (Qbar_yx / Qbar_yy) alpha2) delta_T. The grips hold it there
  // (the preload), the bonds carry the cure as free offsets (strategies/cure_stress.hpp), and the
  // load adds the uniaxial sigma_x of the case above: every site reaches YT at once, at the
  // applied sigma_x = YT + E2 alpha2 delta_T, by hand. (The test of each bond's and each site's
  // root under a preload, with grips that hold no load of their own.)
  const double diameter = 0.1e-3, delta_T = -50;
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = kPi / 2;
  spec.length = 3e-3;
  spec.width = 1e-3;
  spec.particle_diameter = diameter;
  Model model = default_registry().create("square")->build(spec).model;
  Bonds& bonds = model.bonds;
  for (int b = 0; b < bonds.size(); ++b) bonds.tensile_strength(b) = bonds.cohesion(b) = kInf;
  set_cure_offsets(model, {Ply{spec.material, spec.ply_angle, spec.thickness}}, delta_T);
  const Material& mat = spec.material;
  const Eigen::Matrix3d qbar = test::qbar_by_hand(mat, spec.ply_angle);
  const double eps_y = (mat.alpha1 + qbar(1, 0) / qbar(1, 1) * mat.alpha2) * delta_T;
  const double held = -mat.E2 * mat.alpha2 * delta_T;  // sigma_x of the cure [Pa]
  const Eigen::Vector3d eps = qbar.inverse() * Eigen::Vector3d(1, 0, 0);
  DofConstraints unit, cured;
  DofFlags reaction, unused;
  test::affine_grips(model, diameter, 1e-3 * eps / eps(0), unit, reaction);
  test::affine_grips(model, diameter, Eigen::Vector3d(0, eps_y, 0), cured, unused);
  EventSettings settings;
  settings.material_point = MaterialPointFailure{FailureCriterion::kPuck, mat, {spec.ply_angle}};
  settings.preload = cured.value;
  const EventsResult r = run_events(model, unit, reaction, settings);
  REQUIRE(!r.path.empty());
  const double per_unit = 1e-3 / eps(0);  // sigma_x per unit load factor [Pa]
  const double expected = (mat.strength.YT - held) / per_unit;
  MESSAGE("held cure sigma_x " << held * 1e-6 << " MPa; first crack at load factor "
                               << r.path[0].load_factor << " (by hand " << expected << ")");
  CHECK(held > 0.3 * mat.strength.YT);  // the cure takes a third of YT: a test that can fail
  // Measured: 2.4e-4 (the lattice's own Poisson contraction under the held cure is not quite
  // Q-bar's, which the grips impose); without the preload the factor would be YT / per_unit,
  // more than twice this.
  CHECK(relative(r.path[0].load_factor, expected) < 1e-3);
  CHECK(r.path[0].site >= 0);
  CHECK(r.path[0].site_mode == PlyFailureMode::kMatrixTension);
}

TEST_CASE("failure at the material point refuses a run without ply angles") {
  EventSettings settings;
  settings.static_settings.pin_rigid_modes = true;  // the grips leave y free
  settings.material_point = MaterialPointFailure{};
  CHECK_THROWS_WITH_AS(settings.validate(), doctest::Contains("the fibre angle of every ply"),
                       Error);
  settings.material_point->ply_angles = {std::numeric_limits<double>::quiet_NaN()};
  CHECK_THROWS_WITH_AS(settings.validate(), doctest::Contains("a ply angle is nan"), Error);
}
