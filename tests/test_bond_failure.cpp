// The failure law (core/bond_failure.hpp): one bond loaded in each of its four modes breaks where
// the parallel-bond stresses, computed here by hand from the bond's stiffnesses and the section
// of radius R, reach its strength; the decision is the same from either end.

#include "core/bond_failure.hpp"

#include <doctest/doctest.h>

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

using Eigen::Vector3d;
using plydem::BondParameters;
using plydem::BondState;
using plydem::BondStrength;
using plydem::BondStresses;

namespace {

constexpr double kPi = std::numbers::pi;

// A bond along x between two particles of radius r touching at the origin's midpoint.
BondParameters bond_along_x(double r) {
  BondParameters b;
  b.normal = Vector3d::UnitX();
  b.lever_first = r;
  b.lever_second = r;
  b.normal_stiffness = 2.0e6;
  b.shear_stiffness = 0.7e6;
  b.bending_stiffness = 3.0e-3;
  b.twisting_stiffness = 1.1e-3;
  return b;
}

// The same bond described from its other end: first and second swapped.
BondParameters reversed(const BondParameters& b) {
  BondParameters r = b;
  r.normal = -b.normal;
  r.lever_first = b.lever_second;
  r.lever_second = b.lever_first;
  return r;
}

BondStrength strength_of(double radius) {
  BondStrength s;
  s.radius = radius;
  s.tensile = 40e6;
  s.cohesion = 60e6;
  return s;
}

}  // namespace

TEST_CASE("one bond in tension, shear, bending and twist: stresses by hand, failure at strength") {
  const double r = 25e-6;
  const BondParameters b = bond_along_x(r);
  const double area = kPi * r * r, inertia = kPi * std::pow(r, 4) / 4, polar = 2 * inertia;
  const BondStrength strength = strength_of(r);
  const Vector3d zero = Vector3d::Zero();
  const double beta = plydem::kMomentContribution;

  SUBCASE("tension: sigma = k_n du / A") {
    const double du = 1e-7;
    const BondStresses s = plydem::bond_stresses(b, r, zero, zero, Vector3d(du, 0, 0), zero);
    CHECK(s.axial == doctest::Approx(b.normal_stiffness * du / area).epsilon(1e-14));
    CHECK(s.normal == doctest::Approx(s.axial).epsilon(1e-14));
    CHECK(s.shear == 0.0);
    // Breaks exactly when sigma reaches sigma_c: the critical load factor of this deformation.
    const auto critical = plydem::critical_load(s, strength);
    CHECK(critical.mode == BondState::kBrokenTension);
    const double du_break = strength.tensile * area / b.normal_stiffness;
    CHECK(critical.factor * du == doctest::Approx(du_break).epsilon(1e-13));
    const auto below =
        plydem::bond_stresses(b, r, zero, zero, Vector3d(0.999 * du_break, 0, 0), zero);
    const auto above =
        plydem::bond_stresses(b, r, zero, zero, Vector3d(1.001 * du_break, 0, 0), zero);
    CHECK(plydem::utilisation(below, strength).mode == BondState::kIntact);
    CHECK(plydem::utilisation(above, strength).mode == BondState::kBrokenTension);
    CHECK(plydem::utilisation(above, strength).ratio == doctest::Approx(1.001).epsilon(1e-12));
    // Compression never breaks a bond in tension, and without shear not at all.
    const auto pushed = plydem::bond_stresses(b, r, zero, zero, Vector3d(-10 * du, 0, 0), zero);
    CHECK(plydem::critical_load(pushed, strength).factor ==
          std::numeric_limits<double>::infinity());
  }
  SUBCASE("shear: tau = k_s |du_s| / A, against c - sigma tan(phi)") {
    const double du = 1e-7;
    const BondStresses s = plydem::bond_stresses(b, r, zero, zero, Vector3d(0, 0, du), zero);
    CHECK(s.shear == doctest::Approx(b.shear_stiffness * du / area).epsilon(1e-14));
    CHECK(s.axial == 0.0);
    const auto critical = plydem::critical_load(s, strength);
    CHECK(critical.mode == BondState::kBrokenShear);
    CHECK(critical.factor * s.shear == doctest::Approx(strength.cohesion).epsilon(1e-13));
    // With friction, compression adds sigma tan(phi) to the shear strength: a bond pushed by
    // du_n and sheared by du_s breaks at lambda (k_s du_s / A) = c + lambda (k_n du_n / A)
    // tan(phi).
    BondStrength rough = strength;
    rough.friction = std::tan(30 * kPi / 180);
    const auto pushed = plydem::bond_stresses(b, r, zero, zero, Vector3d(-0.5 * du, 0, du), zero);
    const double tau = b.shear_stiffness * du / area, sigma = b.normal_stiffness * 0.5 * du / area;
    const double lambda = rough.cohesion / (tau - sigma * rough.friction);
    const auto c = plydem::critical_load(pushed, rough);
    CHECK(c.mode == BondState::kBrokenShear);
    CHECK(c.factor == doctest::Approx(lambda).epsilon(1e-13));
  }
  SUBCASE("bending: sigma = beta |M_b| R / I with M_b = k_b dtheta") {
    const double phi = 1e-4;  // opposite spins: no shear at the contact point
    const BondStresses s =
        plydem::bond_stresses(b, r, zero, Vector3d(0, 0, -phi / 2), zero, Vector3d(0, 0, phi / 2));
    CHECK(s.axial == doctest::Approx(0.0).epsilon(1e-12));
    CHECK(s.shear == doctest::Approx(0.0).scale(1.0));
    CHECK(s.normal ==
          doctest::Approx(beta * b.bending_stiffness * phi * r / inertia).epsilon(1e-13));
    const auto critical = plydem::critical_load(s, strength);
    CHECK(critical.mode == BondState::kBrokenTension);
    CHECK(critical.factor * s.normal == doctest::Approx(strength.tensile).epsilon(1e-13));
  }
  SUBCASE("twist: tau = beta |M_t| R / J with M_t = k_t dtheta_n") {
    const double psi = 2e-4;
    const BondStresses s =
        plydem::bond_stresses(b, r, zero, Vector3d(-psi / 2, 0, 0), zero, Vector3d(psi / 2, 0, 0));
    CHECK(s.normal == doctest::Approx(0.0).scale(1.0));
    CHECK(s.shear == doctest::Approx(beta * b.twisting_stiffness * psi * r / polar).epsilon(1e-13));
    CHECK(plydem::critical_load(s, strength).mode == BondState::kBrokenShear);
  }
}

TEST_CASE("the decision is the same from either end of the bond, to the bit") {
  const double r = 25e-6;
  BondParameters b = bond_along_x(r);
  b.normal = Vector3d(0.6, 0.8, 0.0);
  b.lever_first = 0.9 * r;
  b.lever_second = 1.3 * r;
  const Vector3d u_i(1.3e-7, -0.4e-7, 0.2e-7), t_i(1e-4, -3e-4, 2e-4);
  const Vector3d u_j(-0.2e-7, 0.9e-7, -0.6e-7), t_j(-2e-4, 1e-4, 5e-4);
  const BondStresses forward = plydem::bond_stresses(b, r, u_i, t_i, u_j, t_j);
  const BondStresses backward = plydem::bond_stresses(reversed(b), r, u_j, t_j, u_i, t_i);
  CHECK(forward.axial == backward.axial);
  CHECK(forward.normal == backward.normal);
  CHECK(forward.shear == backward.shear);
  const BondStrength strength = strength_of(r);
  CHECK(plydem::utilisation(forward, strength).ratio ==
        plydem::utilisation(backward, strength).ratio);
}

TEST_CASE("linear softening: the saw-tooth inverse, and the dissipated energy kappa_u E_peak") {
  const double ductility = 7.5;
  CHECK(plydem::softening_damage(0.5, ductility) == 0.0);
  CHECK(plydem::softening_damage(1.0, ductility) == 0.0);
  CHECK(plydem::softening_damage(ductility, ductility) == 1.0);
  CHECK(plydem::softening_ratio(0.0, ductility) == doctest::Approx(1.0));
  CHECK(plydem::softening_ratio(1.0, ductility) == doctest::Approx(ductility));
  for (double d : {0.1, 0.5, 0.9, 0.999}) {
    CHECK(plydem::softening_damage(plydem::softening_ratio(d, ductility), ductility) ==
          doctest::Approx(d).epsilon(1e-12));
  }
  // Load F = (1 - d(kappa)) kappa F_peak against separation kappa delta_peak, integrated by the
  // trapezoidal rule from 0 to kappa_u: the area is kappa_u times E_peak = F_peak delta_peak / 2.
  const int steps = 200000;
  double area = 0, previous = 0;
  for (int k = 1; k <= steps; ++k) {
    const double kappa = ductility * k / steps;
    const double load = (1.0 - plydem::softening_damage(kappa, ductility)) * kappa;
    area += 0.5 * (load + previous) * (ductility / steps);
    previous = load;
  }
  CHECK(area == doctest::Approx(ductility * 0.5).epsilon(1e-6));
  // The ductility that dissipates G over A_crack; brittle where the bond holds more than that.
  CHECK(plydem::bond_ductility(100.0, 2e-9, 1e-8) == doctest::Approx(20.0));
  CHECK(plydem::bond_ductility(100.0, 2e-9, 1e-6) == 1.0);
}

TEST_CASE("the energy-equivalent saw-tooth dissipates the softening line's area") {
  // A member loaded in proportion, tooth by tooth as the events solver takes them: each tooth
  // loads the secant of stiffness s from 0 to kappa_k (the line's kappa at s, stretched), then
  // drops to s r at that separation; the last breaks at kappa_u'. The path's area, summed here
  // from the forces and separations themselves, is kappa_u E_peak (the unstretched line's), and no
  // tooth carries more than the peak force.
  for (const double ratio : {0.5, 0.8}) {
    for (const double ductility : {1.5, 7.5, 60.0}) {
      CAPTURE(ratio);
      CAPTURE(ductility);
      const double floor = 1e-3;
      const double line = plydem::saw_tooth_ductility(ductility, ratio, floor);
      CHECK(line > ductility);
      double area = 0, s = 1, largest = 0, first = -1;
      while (true) {
        const bool last = s * ratio < floor;
        const double kappa = last ? line : plydem::softening_ratio(1 - s, line);
        const double force = s * kappa;  // in units of the peak force
        if (first < 0) first = force;
        largest = std::max(largest, force);
        // Force-separation triangle of the drop at separation kappa (E_peak = 1/2 in these units).
        area += 0.5 * kappa * (force - (last ? 0.0 : s * ratio * kappa));
        if (last) break;
        s *= ratio;
      }
      CHECK(area == doctest::Approx(ductility * 0.5).epsilon(1e-10));
      CHECK(first == doctest::Approx(1.0).epsilon(1e-14));
      CHECK(largest <= 1.0 + 1e-12);
    }
  }
  CHECK(plydem::saw_tooth_ductility(1.0, 0.5, 1e-3) == 1.0);
  CHECK(plydem::saw_tooth_ductility(0.3, 0.5, 1e-3) == 1.0);
}

TEST_CASE("Bonds: strengths start unbreakable and bad strengths are refused") {
  plydem::Model model;
  model.particles.resize(2);
  model.particles.mass.setConstant(1e-9);
  model.particles.moment_of_inertia.setConstant(1e-19);
  model.particles.radius.setConstant(25e-6);
  model.particles.reference_position.row(1) << 50e-6, 0, 0;
  model.bonds.resize(1);
  model.bonds.second(0) = 1;
  plydem::set_bond_geometry(model.particles, model.bonds, 0);
  model.bonds.normal_stiffness(0) = 1e6;
  CHECK_FALSE(model.bonds.breakable());
  CHECK_NOTHROW(model.check_consistency());
  model.bonds.tensile_strength(0) = 40e6;
  CHECK(model.bonds.breakable());
  CHECK_THROWS_WITH_AS(model.check_consistency(),
                       doctest::Contains("has a strength but its cross-section radius is 0"),
                       plydem::Error);
  model.bonds.strength_radius(0) = 25e-6;
  CHECK_NOTHROW(model.check_consistency());
  model.bonds.cohesion(0) = -1;
  CHECK_THROWS_WITH_AS(model.check_consistency(), doctest::Contains("cohesion of -1 Pa"),
                       plydem::Error);
  model.bonds.cohesion(0) = std::nan("");
  CHECK_THROWS_AS(model.check_consistency(), plydem::Error);
  model.bonds.cohesion(0) = 60e6;
  model.bonds.ductility(0) = 0.5;
  CHECK_THROWS_WITH_AS(model.check_consistency(), doctest::Contains("ductility of 0.5"),
                       plydem::Error);
}
