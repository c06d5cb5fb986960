// The site stress of failure at the material point (contacts/bond_kernel.hpp particle_stresses):
// in a uniform strain state every interior particle's virial stress is the ply's stress, Q-bar
// times the strain of classical lamination theory written out by hand (tests/support), for two
// strategies, two fibre angles and two particle sizes, within the calibration's own accuracy. The
// site failure built on it (contacts/site_failure.hpp): under a uniaxial stress every interior site
// fails at the closed-form off-axis strength of its criterion, in the criterion's mode, and opens
// the crack plane that mode gives; a line of cracked sites opens every bond across it, diagonals
// included, and leaves the coupon in two halves that carry nothing (a crack of axial bonds alone
// does not: the diagonals bridge it).
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "contacts/bond_opening.hpp"
#include "contacts/site_failure.hpp"
#include "core/error.hpp"
#include "core/failure_criteria.hpp"
#include "core/material.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/registry.hpp"
#include "support/coupon_fixtures.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using plydem::test::kDeg;

namespace {

// The built lamina under the uniform in-plane strain (eps_xx, eps_yy, gamma_xy): every particle's
// translation prescribed affine, u = eps x (u_z = 0), its rotations free and solved for (the
// lattice's rotations relax under shear), then each particle's site stress.
struct UniformState {
  Model model;
  std::vector<Eigen::Matrix3d> stress;
};

UniformState uniform_state(const char* strategy, double angle, double diameter,
                           const Eigen::Vector3d& strain, double fibre_offset = -1) {
  CouponSpec spec;
  spec.material = test::eglass();
  spec.ply_angle = angle;
  spec.length = 2e-3;
  spec.width = 1.2e-3;
  spec.particle_diameter = diameter;
  std::unique_ptr<Strategy> packing = default_registry().create(strategy);
  if (fibre_offset >= 0) packing->set_option("fibre_offset", fibre_offset);
  UniformState s{packing->build(spec).model, {}};
  const Particles& p = s.model.particles;
  DofConstraints c(p.size());
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
    c.fix(i, Dof::kUx, strain(0) * x + 0.5 * strain(2) * y);
    c.fix(i, Dof::kUy, 0.5 * strain(2) * x + strain(1) * y);
    c.fix(i, Dof::kUz, 0.0);
  }
  solve_static(s.model, c);
  s.stress = particle_stresses(s.model.particles, s.model.bonds);
  return s;
}

}  // namespace

TEST_CASE("an interior particle's site stress is the ply's stress in a uniform state") {
  const Material m = test::eglass();
  const Eigen::Vector3d strain(1e-3, -4e-4, 6e-4);
  for (const char* strategy : {"square", "hex2d"}) {
    for (double degrees : {0.0, 30.0}) {
      for (double diameter : {0.1e-3, 0.05e-3}) {
        CAPTURE(std::string(strategy));
        CAPTURE(degrees);
        CAPTURE(diameter);
        const UniformState s = uniform_state(strategy, degrees * kDeg, diameter, strain);
        const Eigen::Vector3d expected = test::qbar_by_hand(m, degrees * kDeg) * strain;
        const Particles& p = s.model.particles;
        const double x0 = p.reference_position.col(0).minCoeff();
        const double x1 = p.reference_position.col(0).maxCoeff();
        const double y0 = p.reference_position.col(1).minCoeff();
        const double y1 = p.reference_position.col(1).maxCoeff();
        const double margin = 3 * diameter;
        double worst = 0;
        int interior = 0;
        for (int i = 0; i < p.size(); ++i) {
          const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
          if (x < x0 + margin || x > x1 - margin || y < y0 + margin || y > y1 - margin) continue;
          ++interior;
          const Eigen::Matrix3d& sigma = s.stress[static_cast<std::size_t>(i)];
          const Eigen::Vector3d in_plane(sigma(0, 0), sigma(1, 1), sigma(0, 1));
          worst = std::max(worst, (in_plane - expected).cwiseAbs().maxCoeff());
          CHECK(std::abs(sigma(2, 2)) <= 1e-9 * expected.cwiseAbs().maxCoeff());
        }
        REQUIRE(interior > 10);
        // Measured: 2.3e-6 (square, 0 deg), 1.0e-4 and 1.3e-4 (square, 30 deg), 2.1e-5 and 3.0e-5
        // (hex2d), nearly the same at both particle sizes: the built lamina's own stiffness
        // against CLT, not the site stress's error.
        const double relative = worst / expected.cwiseAbs().maxCoeff();
        MESSAGE(std::string(strategy)
                << " " << degrees << " deg, " << diameter * 1e3
                << " mm particles: site stress against CLT within " << relative);
        CHECK(relative <= 2e-4);
      }
    }
  }
}

TEST_CASE("held only at its grips, a coupon's sites read the ply's stress, edges included") {
  // The built coupon, its long edges free, between grips that carry a uniaxial stress state of
  // CLT: each site stress outside the grips (Q-bar times the site strain) against the stress CLT
  // gives, and the virial of the particle's bonds against it. Where the edges run along lattice
  // lines (square at 90 deg) the coupon stays uniform and every site, edges and corners too, reads
  // the stress; where they cut the lattice the edge strips' balance (strategies/boundary_cells.hpp)
  // is a least-norm fit, and the coupon itself departs from uniform near its edges: the site stress
  // shows it, and reads far closer than the virial, whose edge cells hold fewer bonds.
  const Material m = test::eglass();
  for (const char* strategy : {"square", "hex2d"}) {
    for (double degrees : {30.0, 90.0}) {
      for (double diameter : {0.1e-3, 0.05e-3}) {
        CAPTURE(std::string(strategy));
        CAPTURE(degrees);
        CAPTURE(diameter);
        CouponSpec spec;
        spec.material = m;
        spec.ply_angle = degrees * kDeg;
        spec.length = 2e-3;
        spec.width = 1e-3;
        spec.particle_diameter = diameter;
        Model model = default_registry().create(strategy)->build(spec).model;
        const Eigen::Matrix3d q_bar = test::qbar_by_hand(m, spec.ply_angle);
        const Eigen::Vector3d strain = q_bar.inverse() * Eigen::Vector3d(1e6, 0, 0);
        DofConstraints grips;
        DofFlags reaction;
        test::affine_grips(model, diameter, strain, grips, reaction);
        solve_static(model, grips);
        const Eigen::Vector3d expected = q_bar * strain;  // (1 MPa, 0, 0) to rounding
        const std::vector<Eigen::Vector3d> site = site_strains(model.particles, model.bonds);
        const std::vector<Eigen::Matrix3d> virial = particle_stresses(model.particles, model.bonds);
        double worst = 0, worst_virial = 0;
        for (int i = 0; i < model.particles.size(); ++i) {
          if (grips.fixed(i, static_cast<int>(Dof::kUx))) continue;
          const auto k = static_cast<std::size_t>(i);
          const Eigen::Vector3d sigma = q_bar * site[k];
          worst = std::max(worst, (sigma - expected).cwiseAbs().maxCoeff() / 1e6);
          const Eigen::Vector3d v(virial[k](0, 0), virial[k](1, 1), virial[k](0, 1));
          worst_virial = std::max(worst_virial, (v - expected).cwiseAbs().maxCoeff() / 1e6);
        }
        MESSAGE(std::string(strategy)
                << " " << degrees << " deg, " << diameter * 1e3 << " mm: every site within "
                << worst << " of the stress, the virial within " << worst_virial);
        // Measured: square 90 deg 2.8e-3 and 2.9e-3 (sigma_yy at the corners beside the grips;
        // 3.5e-4 elsewhere), the virial 0.090; square 30 deg 0.24 and 0.27, hex2d 0.19 to 0.26 at
        // the edges beside the grips (0.02 to 0.03 a few diameters from them), the virial 0.58 to
        // 0.75.
        if (std::string(strategy) == "square" && degrees == 90) CHECK(worst <= 4e-3);
        CHECK(worst <= 0.5 * worst_virial);
      }
    }
  }
}

TEST_CASE("a strand's site carries the uniaxial stress of its stretch along the strand") {
  // A 0 deg ply stretched by eps_xx: one particle left with its two axial bonds along x only (the
  // fibre) reads no strain, but fails in fibre tension at eps_xx E1 = XT, as a fibre would.
  const Material m = test::eglass();
  UniformState s = uniform_state("square", 0.0, 0.1e-3, Eigen::Vector3d(1e-3, -3e-4, 0));
  Particles& p = s.model.particles;
  Bonds& bonds = s.model.bonds;
  // The particle nearest the coupon's middle.
  const Eigen::RowVector3d middle =
      0.5 * (p.reference_position.colwise().minCoeff() + p.reference_position.colwise().maxCoeff())
                .matrix();
  int site = 0;
  for (int i = 0; i < p.size(); ++i) {
    if ((p.reference_position.row(i).matrix() - middle).norm() <
        (p.reference_position.row(site).matrix() - middle).norm())
      site = i;
  }
  int kept = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.first(b) != site && bonds.second(b) != site) continue;
    if (std::abs(bonds.normal(b, 1)) < 1e-9) {
      ++kept;
      continue;
    }
    open_bond(bonds, b, BondState::kBrokenTension);
  }
  REQUIRE(kept == 2);
  CHECK(!site_strains(p, bonds)[static_cast<std::size_t>(site)].allFinite());
  const std::vector<double> angles{0.0};
  const SiteFailure f = site_failures(p, bonds, angles, FailureCriterion::kMaxStress,
                                      m)[static_cast<std::size_t>(site)];
  CHECK(f.failure.mode == PlyFailureMode::kFibreTension);
  // Max-stress on sigma1 = E1 eps_xx alone: the load factor XT / (E1 eps_xx).
  CHECK(f.failure.load_factor == doctest::Approx(m.strength.XT / (m.E1 * 1e-3)).epsilon(1e-9));
}

TEST_CASE("a particle without volume reads zero, and broken bonds carry no site stress") {
  UniformState s = uniform_state("square", 0.0, 0.1e-3, Eigen::Vector3d(1e-3, 0, 0));
  CHECK(!particle_stresses(s.model.particles, s.model.bonds)[0].isZero(0.0));
  Particles p = s.model.particles;
  p.volume(0) = 0;
  CHECK(particle_stresses(p, s.model.bonds)[0].isZero(0.0));
  Bonds& bonds = s.model.bonds;
  for (int b = 0; b < bonds.size(); ++b)
    bonds.state(b) = static_cast<int>(BondState::kBrokenTension);
  for (const Eigen::Matrix3d& sigma : particle_stresses(s.model.particles, bonds)) {
    CHECK(sigma.isZero(0.0));
  }
}

namespace {

// The uniform strain of a uniaxial stress sigma_x = 1 Pa in a ply at `angle`: CLT's compliance
// (the inverse of Q-bar written out by hand) times (1, 0, 0).
Eigen::Vector3d uniaxial_strain(double angle) {
  return test::qbar_by_hand(test::eglass(), angle).inverse() * Eigen::Vector3d(1, 0, 0);
}

bool interior(const Particles& p, int i, double margin) {
  const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
  return x >= p.reference_position.col(0).minCoeff() + margin &&
         x <= p.reference_position.col(0).maxCoeff() - margin &&
         y >= p.reference_position.col(1).minCoeff() + margin &&
         y <= p.reference_position.col(1).maxCoeff() - margin;
}

}  // namespace

TEST_CASE("under a uniaxial stress every interior site fails at the off-axis strength") {
  const LaminaStrength x = test::eglass().strength;
  for (const char* strategy : {"square", "hex2d"}) {
    for (double degrees : {0.0, 30.0, 90.0}) {
      for (double diameter : {0.1e-3, 0.05e-3}) {
        CAPTURE(std::string(strategy));
        CAPTURE(degrees);
        CAPTURE(diameter);
        // A strain of 1e-3 in the direction of the unit uniaxial stress (scaled: the sites' load
        // factors are then the strength over the stress the model carries).
        const Eigen::Vector3d unit = uniaxial_strain(degrees * kDeg);
        const double scale = 1e-3 / unit.cwiseAbs().maxCoeff();
        const UniformState s = uniform_state(strategy, degrees * kDeg, diameter, scale * unit);
        const std::vector<double> angles{degrees * kDeg};
        for (FailureCriterion c : {FailureCriterion::kMaxStress, FailureCriterion::kTsaiWu,
                                   FailureCriterion::kHashin, FailureCriterion::kPuck}) {
          CAPTURE(std::string(criterion_name(c)));
          const PlyFailure expected = ply_failure(c, to_ply_axes(1, 0, 0, degrees * kDeg), x);
          const std::vector<SiteFailure> sites =
              site_failures(s.model.particles, s.model.bonds, angles, c, test::eglass());
          double worst = 0;
          for (int i = 0; i < s.model.particles.size(); ++i) {
            if (!interior(s.model.particles, i, 3 * diameter)) continue;
            const SiteFailure& site = sites[static_cast<std::size_t>(i)];
            // The strength in sigma_x: load factor times the sigma_x the site carries (scale).
            worst = std::max(worst,
                             std::abs(site.failure.load_factor * scale / expected.load_factor - 1));
            CHECK(site.failure.mode == expected.mode);
            CHECK((site.crack_normal - crack_normal(expected, degrees * kDeg)).norm() < 1e-12);
          }
          MESSAGE(std::string(strategy)
                  << " " << degrees << " deg, " << diameter * 1e3 << " mm, "
                  << std::string(criterion_name(c)) << ": strength within " << worst);
          // Measured: within 5.7e-4 (square 30 deg, max-stress, which tau12 governs there), 3.0e-4
          // for the other criteria at square 30 deg, 8.3e-5 for hex2d, 2.3e-5 at 0 and 90 deg: the
          // site stress's own accuracy (above), read relative to the component that governs.
          CHECK(worst <= 1e-3);
        }
      }
    }
  }
}

TEST_CASE("a crack's plane: across the fibres in a fibre mode, along them in a matrix mode") {
  const double a = 30 * kDeg;
  const PlyFailure fibre{1.0, PlyFailureMode::kFibreTension, 0.0};
  CHECK((crack_normal(fibre, a) - Eigen::Vector3d(std::cos(a), std::sin(a), 0)).norm() < 1e-15);
  const PlyFailure matrix{1.0, PlyFailureMode::kMatrixTension, 0.0};
  CHECK((crack_normal(matrix, a) - Eigen::Vector3d(-std::sin(a), std::cos(a), 0)).norm() < 1e-15);
  // Transverse compression of a 90 deg ply: the plane holds the fibre (y) and leans from the
  // thickness direction by Puck's fracture angle, so its normal is (-cos phi, 0, sin phi).
  const LaminaStrength x = test::eglass().strength;
  const PlyFailure crushed = ply_failure(FailureCriterion::kPuck, {0, -1, 0}, x);
  REQUIRE(crushed.mode == PlyFailureMode::kMatrixCompression);
  const double phi = crushed.fracture_angle;
  CHECK(phi > 45 * kDeg);
  CHECK(phi < 56 * kDeg);
  const Eigen::Vector3d n = crack_normal(crushed, 90 * kDeg);
  CHECK((n - Eigen::Vector3d(-std::cos(phi), 0, std::sin(phi))).norm() < 1e-12);
  CHECK(n.dot(Eigen::Vector3d::UnitY()) == doctest::Approx(0).epsilon(1e-15));
}

TEST_CASE("site failure names a ply without an angle, and finds the first site to fail") {
  const UniformState s = uniform_state("square", 0.0, 0.1e-3, Eigen::Vector3d(1e-3, 0, 0));
  const std::vector<double> none;
  CHECK_THROWS_WITH_AS(site_failures(s.model.particles, s.model.bonds, none,
                                     FailureCriterion::kPuck, test::eglass()),
                       doctest::Contains("is in ply 0, and 0 ply angle(s) were given"), Error);
  std::vector<SiteFailure> sites(3);
  for (SiteFailure& site : sites)
    site.failure.load_factor = std::numeric_limits<double>::infinity();
  CHECK(first_failing_site(sites) == -1);
  sites[2].failure.load_factor = 2.0;
  sites[1].failure.load_factor = 2.0;
  CHECK(first_failing_site(sites) == 1);
  sites[0].failure.load_factor = 3.0;
  CHECK(first_failing_site(sites) == 1);
}

namespace {

// The strain energy of the built 90 deg lamina stretched between its ends (translations of the
// particles within 1.5 diameters of each end fixed, two columns, so that each half of a cracked
// coupon is held against every rigid motion; the right end moved by 1e-6 m along x), after `crack`
// opened.
double stretched_energy(const Model& built, const std::vector<int>& crack, double diameter) {
  Model model = built;
  open_bonds(model.bonds, crack, BondState::kBrokenTension);
  const Particles& p = model.particles;
  const double x0 = p.reference_position.col(0).minCoeff() + 1.5 * diameter;
  const double x1 = p.reference_position.col(0).maxCoeff() - 1.5 * diameter;
  DofConstraints c(p.size());
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    if (x > x0 && x < x1) continue;
    c.fix(i, Dof::kUx, x <= x0 ? 0.0 : 1e-6);
    c.fix(i, Dof::kUy, 0.0);
    c.fix(i, Dof::kUz, 0.0);
  }
  solve_static(model, c);
  return bond_strain_energy(model.particles, model.bonds);
}

}  // namespace

TEST_CASE("a line of cracked sites opens every bond across it, diagonals too: traction-free") {
  // A 90 deg E-glass ply under sigma_x fails in matrix tension on planes along its fibres (y):
  // crack the column of sites nearest the middle, each site's crack from site_failures.
  for (double diameter : {0.1e-3, 0.05e-3}) {
    CAPTURE(diameter);
    const Eigen::Vector3d unit = uniaxial_strain(90 * kDeg);
    const UniformState s = uniform_state("square", 90 * kDeg, diameter, 1e-3 * unit / unit(0));
    const Particles& p = s.model.particles;
    const std::vector<double> angles{90 * kDeg};
    const std::vector<SiteFailure> sites =
        site_failures(p, s.model.bonds, angles, FailureCriterion::kPuck, test::eglass());
    const double middle =
        0.5 * (p.reference_position.col(0).minCoeff() + p.reference_position.col(0).maxCoeff());
    double column = 0, nearest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < p.size(); ++i) {
      const double d = std::abs(p.reference_position(i, 0) - middle);
      if (d < nearest) nearest = d, column = p.reference_position(i, 0);
    }
    std::vector<int> crack, axial_only;
    int cracked_sites = 0;
    for (int i = 0; i < p.size(); ++i) {
      if (std::abs(p.reference_position(i, 0) - column) > 1e-9) continue;
      ++cracked_sites;
      const SiteFailure& site = sites[static_cast<std::size_t>(i)];
      CHECK(site.failure.mode == PlyFailureMode::kMatrixTension);
      CHECK(std::abs(site.crack_normal.x()) == doctest::Approx(1).epsilon(1e-12));
      for (int b : bonds_across_crack(p, s.model.bonds, i, site.crack_normal)) {
        crack.push_back(b);
        const double along = std::abs(s.model.bonds.normal(b, 0));
        if (along > 1 - 1e-9) axial_only.push_back(b);
      }
    }
    REQUIRE(cracked_sites > 5);
    // Each site opens its axial bond and its two diagonals (one at the coupon's edges).
    CHECK(crack.size() == static_cast<std::size_t>(3 * cracked_sites - 2));
    CHECK(axial_only.size() == static_cast<std::size_t>(cracked_sites));
    const double intact = stretched_energy(s.model, {}, diameter);
    const double cracked = stretched_energy(s.model, crack, diameter);
    const double bridged = stretched_energy(s.model, axial_only, diameter);
    MESSAGE((diameter * 1e3) << " mm: energy cracked / intact " << cracked / intact
                             << ", axial bonds only " << bridged / intact);
    CHECK(intact > 0);
    CHECK(cracked <= 1e-9 * intact);  // both halves move as rigid bodies
    CHECK(bridged > 0.05 * intact);   // the diagonals bridge a crack of axial bonds alone
  }
}

TEST_CASE("a row of cracks in a lattice turned from it is traction-free, and its share exact") {
  // A crack along a lattice direction that is not a row of bonds: a 90 deg ply whose square lattice
  // lies at 45 deg from its fibre (cracks along the lattice's diagonals; the diagonal bonds along
  // x join the sites on either side of a crack's row and cross it between two of its sites), and
  // a 0 deg hex2d ply's fibre crack (normal to the fibre, 30 deg from two of the lattice's three
  // bond families; the rows alternate, so every other one has no site on the plane). The sites
  // nearest a plane x = const through the middle crack, each on the normal's side; every bond
  // across must open, and their shares must sum to the plane's area (width x thickness, the
  // coupon's volume over its length).
  struct Case {
    const char* strategy;
    double angle_deg, fibre_offset;
  };
  for (const Case c : {Case{"square", 90, 45}, Case{"hex2d", 0, -1}}) {
    for (double diameter : {0.1e-3, 0.05e-3}) {
      CAPTURE(std::string(c.strategy));
      CAPTURE(diameter);
      const Eigen::Vector3d unit = uniaxial_strain(c.angle_deg * kDeg);
      const UniformState s = uniform_state(c.strategy, c.angle_deg * kDeg, diameter,
                                           1e-3 * unit / unit(0), c.fibre_offset);
      const Particles& p = s.model.particles;
      const std::vector<double> angles{c.angle_deg * kDeg};
      const std::vector<SiteFailure> sites =
          site_failures(p, s.model.bonds, angles, FailureCriterion::kPuck, test::eglass());
      const double middle =
          0.5 * (p.reference_position.col(0).minCoeff() + p.reference_position.col(0).maxCoeff());
      double plane = 0, nearest = std::numeric_limits<double>::infinity();
      for (int i = 0; i < p.size(); ++i) {
        const double d = std::abs(p.reference_position(i, 0) - middle);
        if (d < nearest) nearest = d, plane = p.reference_position(i, 0);
      }
      std::vector<int> crack;
      double share = 0, volume = 0;
      for (int i = 0; i < p.size(); ++i) volume += p.volume(i);
      for (int i = 0; i < p.size(); ++i) {
        if (std::abs(p.reference_position(i, 0) - plane) > 1e-9) continue;
        const Eigen::Vector3d normal(1, 0, 0);  // the crack's, up to its sign (tested above)
        CHECK(std::abs(sites[static_cast<std::size_t>(i)].crack_normal.x()) ==
              doctest::Approx(1).epsilon(1e-12));
        for (int b : bonds_across_crack(p, s.model.bonds, i, normal)) crack.push_back(b);
        share += crack_share(p, s.model.bonds, i, normal);
      }
      // A bond halfway between two of the row's sites is in both segments: the first opens it.
      std::sort(crack.begin(), crack.end());
      crack.erase(std::unique(crack.begin(), crack.end()), crack.end());
      const double length =
          p.reference_position.col(0).maxCoeff() - p.reference_position.col(0).minCoeff();
      const double intact = stretched_energy(s.model, {}, diameter);
      const double cracked = stretched_energy(s.model, crack, diameter);
      MESSAGE(std::string(c.strategy)
              << " " << (diameter * 1e3) << " mm: energy cracked / intact " << cracked / intact
              << ", shares / (volume / length) " << share / (volume / length));
      CHECK(cracked <= 1e-9 * intact);
      // The edges' cells: within 4% at 0.05 mm (doctest's Approx is absolute below 1: a ratio).
      CHECK(share / (volume / length) ==
            doctest::Approx(1).epsilon(diameter > 0.075e-3 ? 0.11 : 0.055));
    }
  }
}

TEST_CASE("a crack names a site out of range and a normal that is not a unit vector") {
  const UniformState s = uniform_state("square", 0.0, 0.1e-3, Eigen::Vector3d(1e-3, 0, 0));
  const Particles& p = s.model.particles;
  CHECK_THROWS_WITH_AS(bonds_across_crack(p, s.model.bonds, p.size(), Eigen::Vector3d::UnitX()),
                       doctest::Contains("a crack at particle"), Error);
  CHECK_THROWS_WITH_AS(bonds_across_crack(p, s.model.bonds, 0, Eigen::Vector3d(2, 0, 0)),
                       doctest::Contains("unit vector"), Error);
  Bonds bonds = s.model.bonds;
  const std::vector<int> first{0};
  open_bonds(bonds, first, BondState::kBrokenTension);
  CHECK(bonds.is_broken(0));
  CHECK(bonds.damage(0) == 1);
  CHECK(bonds.normal_stiffness(0) == 0);
  CHECK_THROWS_WITH_AS(open_bonds(bonds, first, BondState::kBrokenShear),
                       doctest::Contains("bond 0 is broken already"), Error);
  const std::vector<int> outside{bonds.size()};
  CHECK_THROWS_WITH_AS(open_bonds(bonds, outside, BondState::kBrokenShear),
                       doctest::Contains("the model has"), Error);
  CHECK_THROWS_WITH_AS(open_bond(bonds, 1, BondState::kIntact),
                       doctest::Contains("opens in tension or in shear"), Error);
  CHECK(!bonds.is_broken(1));
  // Broken bonds do not cross a crack: they are open already.
  const Eigen::Vector3d along(bonds.normal(0, 0), bonds.normal(0, 1), bonds.normal(0, 2));
  const std::vector<int> around = bonds_across_crack(p, bonds, bonds.first(0), along);
  CHECK(std::find(around.begin(), around.end(), 0) == around.end());
  CHECK(!bonds_across_crack(p, s.model.bonds, bonds.first(0), along).empty());
}
