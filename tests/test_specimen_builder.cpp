// A build returns what it built: the model with the calibration it used; an experiment calibrates
// each distinct ply once and builds each coupon once, and reuses the solved models.
#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/hole_plate.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "strategies/hex2d.hpp"
#include "strategies/laminate.hpp"
#include "strategies/lattice.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"
#include "support/test_support.hpp"

using namespace plydem;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

TensionSettings small_test(const std::string& strategy) {
  TensionSettings s;
  s.strategy = strategy;
  s.coupon.material = load_material("eglass-my750");
  s.coupon.length = 1.5e-3;
  s.coupon.width = 0.5e-3;
  return s;
}

BuildStatistics since(const BuildStatistics& before) {
  const BuildStatistics now = build_statistics();
  return {now.calibrations - before.calibrations, now.builds - before.builds};
}

bool same_model(const Model& a, const Model& b) {
  return a.particles.size() == b.particles.size() && a.bonds.size() == b.bonds.size() &&
         (a.particles.reference_position == b.particles.reference_position).all() &&
         (a.particles.mass == b.particles.mass).all() &&
         (a.bonds.normal_stiffness == b.bonds.normal_stiffness).all() &&
         (a.bonds.shear_stiffness == b.bonds.shear_stiffness).all() &&
         (a.bonds.bending_stiffness == b.bonds.bending_stiffness).all() &&
         (a.bonds.first == b.bonds.first).all() && (a.bonds.second == b.bonds.second).all();
}

// A user's strategy as in examples/custom_strategy/affine_hex2d_strategy.hpp: only calibrate()
// overridden.
class StifferHex2d : public Hex2dStrategy {
 public:
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override {
    Calibration cal = Hex2dStrategy::calibrate(material, ply_angle, thickness);
    for (FamilyCalibration& f : cal.families) f.stiffness.normal *= 2;
    return cal;
  }
};

}  // namespace

TEST_CASE("the tension test calibrates each ply once and builds each coupon once") {
  const BuildStatistics before = build_statistics();
  const TensionResult r = TensionTest(small_test("hex2d")).run();
  const BuildStatistics work = since(before);
  // Two plies (0 and -90 deg), two coupons; the specimen stiffness reuses the coupon along x.
  CHECK(work.calibrations == 2);
  CHECK(work.builds == 2);
  CHECK(r.build_statistics.calibrations == 2);
  CHECK(r.build_statistics.builds == 2);
  // The reported calibration is the one the coupon got, and the solved models come back.
  const Calibration fresh = Hex2dStrategy().calibrate(r.material, 0.0, 0.2e-3);
  CHECK(relative_difference(r.calibration.relaxed, fresh.relaxed) == 0);
  REQUIRE(r.along_x.model);
  REQUIRE(r.along_y.model);
  REQUIRE(r.coupon_x);
  CHECK(r.along_x.model->particles.size() == r.along_x.particles);
  CHECK(r.along_x.model->particles.displacement.abs().maxCoeff() > 0);
  CHECK(r.coupon_x->model.particles.displacement.abs().maxCoeff() == 0);
  CHECK(r.along_x.model->particles.group.maxCoeff() > 0);  // grips assigned
}

TEST_CASE("a laminate's tension test calibrates each distinct ply once") {
  TensionSettings s = small_test("hex2d");
  s.layup = parse_layup("[0/90/0]");
  const BuildStatistics before = build_statistics();
  const TensionResult r = TensionTest(s).run();
  const BuildStatistics work = since(before);
  // Along x the plies 0, 90, 0; along y -90, 0, -90: three distinct plies, each calibrated and
  // built once (six ply builds before the builder kept its plies).
  CHECK(work.calibrations == 3);
  CHECK(work.builds == 3);
  CHECK(r.build_statistics.calibrations == 3);
  CHECK(r.build_statistics.builds == 3);
  REQUIRE(r.ply_calibrations.size() == 3);
  CHECK(relative_difference(r.ply_calibrations[0].target, r.ply_calibrations[2].target) == 0);
  CHECK(relative_difference(r.ply_calibrations[1].target,
                            rotate_reduced_stiffness(reduced_stiffness(r.material), 90 * kDeg)) <
        1e-15);
}

TEST_CASE("a laminate's repeated plies are built once, and are the plies a build gives") {
  CouponSpec coupon = small_test("hex2d").coupon;
  const std::vector<double> layup = parse_layup("[0/45/-45/90]s");
  const auto strategy = default_registry().create("hex2d");
  SpecimenBuilder builder(*strategy);
  const Specimen laminate = build_laminate(builder, {coupon, layup, {}});
  CHECK(builder.statistics().builds == 4);
  CHECK(builder.statistics().calibrations == 4);
  // Each ply is bit for bit the coupon a build of its own gives, shifted to its height.
  const Particles& p = laminate.model.particles;
  const Bonds& b = laminate.model.bonds;
  int first = 0, first_bond = 0;
  for (std::size_t k = 0; k < layup.size(); ++k) {
    CAPTURE(k);
    coupon.ply_angle = layup[k];
    const Specimen alone = strategy->build(coupon);
    const Particles& q = alone.model.particles;
    REQUIRE(first + q.size() <= p.size());
    for (int i = 0; i < q.size(); ++i) {
      CHECK(p.ply(first + i) == static_cast<int>(k));
      CHECK(p.reference_position(first + i, 0) == q.reference_position(i, 0));
      CHECK(p.reference_position(first + i, 1) == q.reference_position(i, 1));
    }
    const Bonds& c = alone.model.bonds;
    REQUIRE(first_bond + c.size() <= b.size());
    for (int j = 0; j < c.size(); ++j) {
      CHECK(b.first(first_bond + j) == first + c.first(j));
      CHECK(b.normal_stiffness(first_bond + j) == c.normal_stiffness(j));
      CHECK(b.shear_stiffness(first_bond + j) == c.shear_stiffness(j));
    }
    first += q.size();
    first_bond += c.size();
  }
  CHECK(first == p.size());
  // A second laminate of the same plies builds nothing more.
  const Specimen again = build_laminate(builder, {coupon, layup, {}});
  CHECK(builder.statistics().builds == 4);
  CHECK(same_model(again.model, laminate.model));
}

TEST_CASE("a build with a calibration already computed is the same build") {
  CouponSpec coupon = small_test("hex2d").coupon;
  coupon.ply_angle = 30 * kDeg;
  for (const char* name : {"hex2d", "square", "hcp"}) {
    CAPTURE(name);
    const auto strategy = default_registry().create(name);
    const Specimen built = strategy->build(coupon);
    REQUIRE(built.ply_calibrations.size() == 1);
    const Specimen again = strategy->build(coupon, built.ply_calibrations.front());
    CHECK(same_model(built.model, again.model));
    SpecimenBuilder builder(*strategy);
    const BuildStatistics before = build_statistics();
    const Specimen first = builder.build(coupon);
    const Specimen second = builder.build(coupon);
    CHECK(builder.statistics().calibrations == 1);
    CHECK(builder.statistics().builds == 2);
    CHECK(since(before).calibrations == 1);
    CHECK(since(before).builds == 2);
    CHECK(same_model(first.model, built.model));
    CHECK(same_model(second.model, built.model));
  }
}

TEST_CASE("a calibration computed for another ply is refused") {
  const Hex2dStrategy hex2d;
  CouponSpec coupon = small_test("hex2d").coupon;
  const Calibration at_30 = hex2d.calibrate(coupon.material, 30 * kDeg, coupon.thickness);
  CHECK_THROWS_WITH_AS(hex2d.build(coupon, at_30), doctest::Contains("another ply"), Error);
}

TEST_CASE("a user's strategy that overrides calibrate() alone builds with its calibration") {
  // With the count completion of the edges, which scales a bond's stiffnesses alike whatever they
  // are (edge equilibrium solves weights from the stiffness ratios).
  StifferHex2d stiffer;
  stiffer.set_option("edge_equilibrium", 0);
  Hex2dStrategy hex2d;
  hex2d.set_option("edge_equilibrium", 0);
  const CouponSpec coupon = small_test("hex2d").coupon;
  const Specimen mine = stiffer.build(coupon);
  const Specimen plain = hex2d.build(coupon);
  REQUIRE(mine.model.bonds.size() == plain.model.bonds.size());
  CHECK((mine.model.bonds.normal_stiffness - 2 * plain.model.bonds.normal_stiffness)
            .abs()
            .maxCoeff() <= 1e-12 * plain.model.bonds.normal_stiffness.maxCoeff());
  CHECK(mine.ply_calibrations.front().families[0].stiffness.normal ==
        2 * plain.ply_calibrations.front().families[0].stiffness.normal);
}

TEST_CASE("lattice returns the calibration of the coupon's own packing, and refuses another") {
  const Material mild = test::mild_ply();
  const LatticeStrategy lattice(false);  // the uncorrected law: quick, same bookkeeping
  CouponSpec coupon;
  coupon.material = mild;
  coupon.length = 0.8e-3;
  coupon.width = 0.6e-3;
  const Specimen built = lattice.build(coupon);
  REQUIRE(built.ply_calibrations.size() == 1);
  const Calibration& own = built.ply_calibrations.front();
  // Not calibrate()'s 16-diameter sample: the coupon's own packing.
  const Calibration sample = lattice.calibrate(mild, 0, coupon.thickness);
  CHECK(relative_difference(own.relaxed, sample.relaxed) > 1e-6);
  const Calibration again = lattice.calibrate_coupon(coupon);
  CHECK(relative_difference(own.relaxed, again.relaxed) == 0);
  CHECK(same_model(lattice.build(coupon, own).model, built.model));
  CHECK_THROWS_WITH_AS(lattice.build(coupon, sample), doctest::Contains("own packing"), Error);
  CouponSpec longer = coupon;
  longer.length = 1.0e-3;
  CHECK_THROWS_WITH_AS(lattice.build(longer, own), doctest::Contains("another coupon"), Error);
}

TEST_CASE("a strategy says whether its boundary cells can be completed again") {
  CHECK(default_registry().create("hex2d")->boundary_completion().family_count == 3);
  CHECK(default_registry().create("square")->boundary_completion().family_count == 4);
  CHECK(default_registry().create("hcp")->boundary_completion().family_count == 0);
  CHECK(default_registry().create("lattice")->boundary_completion().family_count == 0);
}

TEST_CASE("the hole plate asks the strategy how to complete the cut edges") {
  HolePlateSettings s;
  s.strategy = "hcp";
  CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains("its own way"), Error);
  s.strategy = "square";
  CHECK_NOTHROW(s.validate());
}

TEST_CASE("a Table 2 row calibrates each ply once and builds each coupon once") {
  // The static test, the fixed-cycle probe, the staged explicit run and the VTU file of one
  // strategy: before, 8 calibrations and 7 builds; now the explicit runs and the files reuse the
  // static test's coupon and solved model.
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("plydem_table2_row_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "row.toml") << R"(experiment = "lamina-strategies"
material = "eglass-my750"
strategies = ["hex2d"]
[coupon]
length_mm = 1.5
width_mm = 0.5
[explicit]
quick_cycles = 50
ramp_cycles = 200
load_stages = 1
tolerance = 1e-4
)";
  RunOptions options;
  options.config = dir / "row.toml";
  options.out_dir = dir / "out";
  options.quick = true;
  const BuildStatistics before = build_statistics();
  run_experiment(options);
  const BuildStatistics work = since(before);
  CHECK(work.calibrations == 2);
  CHECK(work.builds == 2);
  fs::remove_all(dir);
}
