// One test body for every registered strategy (built-in and variants alike): the coupon it builds
// is a consistent bonded model, its interior has the packing's coordination, and the stiffness the
// built specimen has when the engine loads it agrees with what the strategy's calibration says it
// will simulate; strategies without a suffix (the defaults) must also reach the target.
//
// Each strategy gets a material it can represent: E-glass/MY750, except for the random lattice,
// whose network cannot reach E-glass's G12 (tests/test_lattice.cpp checks that refusal). It gets
// a ply it can reach (E1 20, E2 15, G12 6.5 GPa, nu12 0.25), its smallest calibration sample and a
// small coupon, since it calibrates each coupon's own packing.
#include <doctest/doctest.h>

#include <map>
#include <numbers>
#include <set>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "experiments/protocols/stiffness.hpp"
#include "strategies/registry.hpp"
#include "support/test_support.hpp"

using namespace plydem;

namespace {

// Interior coordination of each built-in packing: [min, max] bonds of a particle at least two
// diameters from every free edge (the three-layer HCP lamina: 9 in the outer layers, 12 inside).
const std::map<std::string, std::pair<int, int>> kCoordination = {
    {"hex2d", {6, 6}}, {"hex2d-paper", {6, 6}}, {"square", {8, 8}},   {"square-paper", {8, 8}},
    {"hcp", {9, 12}},  {"hcp-eq26", {9, 12}},   {"lattice", {4, 40}}, {"lattice-paper", {4, 40}},
};

// The material a strategy is checked with, and the options that keep its calibration small.
struct Subject {
  Material material;
  std::vector<std::pair<std::string, double>> options;
  double length = 1.2e-3, width = 0.9e-3;
  double tolerance = 0.03;  // measured specimen stiffness against the promised one
};
Subject subject_for(const std::string& strategy) {
  Subject s;
  s.material = load_material("eglass-my750");
  if (strategy.rfind("lattice", 0) == 0) {
    s.material = test::mild_ply();
    s.options = {{"sample_diameters", 8}};
    s.length = 0.8e-3;
    s.width = 0.6e-3;
    // The bonds cut at a lattice coupon's free edges are not completed (docs/strategies.md,
    // "Strategies"): this 16 x 12 diameter coupon measures 6.0-7.3% softer than its periodic
    // packing.
    s.tolerance = 0.09;
  } else if (strategy == "hcp-eq26") {
    // Eq. (26) fixes C2233/C1122 and needs C1212 >= C1122: E-glass is refused at every angle
    // (tests/test_hcp.cpp), this ply is not.
    s.material.name = "stiff-shear";
    s.material.G12 = 7e9;
    s.material.nu12 = 0.2;
    s.material.nu23 = 0.2;
  }
  return s;
}

std::vector<int> coordination(const Model& model) {
  std::vector<int> count(model.particles.size(), 0);
  for (int b = 0; b < model.bonds.size(); ++b) {
    ++count[model.bonds.first(b)];
    ++count[model.bonds.second(b)];
  }
  return count;
}

}  // namespace

TEST_CASE("every registered strategy builds a consistent coupon with the stiffness it promises") {
  const Registry& registry = default_registry();
  std::set<std::string> checked;  // strategies that built and measured a coupon
  for (const std::string& name : registry.names()) {
    for (const double degrees : {0.0, 90.0}) {
      CAPTURE(name);
      CAPTURE(degrees);
      const Subject subject = subject_for(name);
      const std::unique_ptr<Strategy> strategy = registry.create(name);
      for (const auto& [option, value] : subject.options) strategy->set_option(option, value);
      CouponSpec coupon;
      coupon.material = subject.material;
      coupon.ply_angle = degrees * std::numbers::pi / 180;
      coupon.length = subject.length;
      coupon.width = subject.width;
      // The calibration checked is the one the coupon got (for the random lattice, that of the
      // coupon's own packing), as the build returns it.
      Specimen specimen;
      try {
        specimen = strategy->build(coupon);
      } catch (const Error& e) {
        // Variants that apply a paper formula as printed may refuse a ply, with a reason; the
        // defaults must represent every E-glass ply.
        CAPTURE(std::string(e.what()));
        CHECK(name.find('-') != std::string::npos);
        continue;
      }
      REQUIRE(specimen.ply_calibrations.size() == 1);
      const Calibration& calibration = specimen.ply_calibrations.front();
      CHECK(is_positive_definite(calibration.relaxed));
      CHECK(calibration.relaxed_error >= 0);
      CHECK(calibration.relaxed_error ==
            doctest::Approx(relative_difference(calibration.relaxed, calibration.target)));
      // It aims at this ply: Q-bar written out by hand.
      CHECK(relative_difference(calibration.target,
                                test::qbar_by_hand(subject.material, coupon.ply_angle)) < 1e-12);
      if (name.find('-') == std::string::npos) CHECK(calibration.relaxed_error < 1e-3);
      for (const FamilyCalibration& family : calibration.families) {
        CHECK(family.stiffness.normal >= 0);
        CHECK(family.stiffness.shear >= 0);
      }
      // Where the calibration does not depend on the coupon, calibrate() reports the same.
      if (name.rfind("lattice", 0) != 0) {
        const Calibration reported =
            strategy->calibrate(subject.material, coupon.ply_angle, coupon.thickness);
        CHECK(relative_difference(reported.relaxed, calibration.relaxed) < 1e-12);
      }

      const Model& model = specimen.model;
      CHECK_NOTHROW(model.check_consistency());  // no self, duplicate or dangling bonds
      const std::vector<int> count = coordination(model);
      const Particles& p = model.particles;
      const double d = coupon.particle_diameter;
      const Eigen::Vector3d low = p.reference_position.colwise().minCoeff().transpose();
      const Eigen::Vector3d high = p.reference_position.colwise().maxCoeff().transpose();
      const auto expected =
          kCoordination.count(name) ? kCoordination.at(name) : std::pair<int, int>{1, 1000};
      int interior = 0;
      for (int i = 0; i < p.size(); ++i) {
        CHECK(count[i] >= 1);  // no loose particle
        const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
        if (x < low.x() + 2 * d || x > high.x() - 2 * d || y < low.y() + 2 * d ||
            y > high.y() - 2 * d) {
          continue;
        }
        ++interior;
        CHECK(count[i] >= expected.first);
        CHECK(count[i] <= expected.second);
      }
      CHECK(interior > 0);

      // The specimen as the engine loads it has the stiffness its calibration predicted (the
      // affine boundary frame of a small coupon costs up to about 1%).
      const Eigen::Matrix3d& promised = calibration.relaxed;
      const SpecimenStiffness measured = measure_specimen_stiffness(model);
      CAPTURE(measured.stiffness);
      CAPTURE(promised);
      CHECK(relative_difference(measured.stiffness, promised) < subject.tolerance);
      checked.insert(name);
    }
  }
  // Every registered strategy built and measured a coupon at one angle at least: lattice included.
  CHECK(checked.size() == registry.names().size());
}
