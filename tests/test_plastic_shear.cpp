// In-plane shear that follows the ply's measured curve (issue 32, deliverable 3;
// solvers/plastic_shear.hpp): `plydem strength --load shear` of a material with a shear_curve
// runs plastic shear strain at the material point. The references are computed here, apart from
// the model: Soden et al.'s measured E-glass/MY750 curve (tests/data/eglass_my750_soden.toml,
// DAMAGE_NOTES §1), S12, and Puck's first-ply failure under tau_xy written out from the stress
// transformation.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/shear_curve.hpp"
#include "experiments/output/strength_report.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/runner/strength_experiment.hpp"

using namespace plydem;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

Material soden() {
  return load_material(PLYDEM_TEST_DATA_DIR "/eglass_my750_soden.toml");
}

StrengthSettings shear_coupon(double angle_deg, double diameter) {
  StrengthSettings s;
  s.coupon.material = soden();
  s.coupon.ply_angle = angle_deg * kDeg;
  s.coupon.length = 3e-3;
  s.coupon.width = 1e-3;
  s.coupon.particle_diameter = diameter;
  s.failure_criterion = PlyFailureModel::kPuck;
  s.load = StrengthLoad::kShear;
  return s;
}

// The coupon at 0 or 90 deg: tau_xy against gamma_xy is the ply's tau12 against gamma12. Measured
// (square, 3 x 1 mm, Puck, 0.1 and 0.05 mm): the gauge follows the fitted law to 1.4e-4 (linear
// between its steps; its sites return onto it in a uniform state), 1.0126, 0.9781 and 0.9977 of
// Soden's 47.4, 63.8 and 69.5 MPa at 1, 2 and 3%; it cracks at S12 = 73.00 MPa at 3.760%, the law's
// strain there (Soden's ply: 4%).
void check_follows_curve(double angle_deg, double diameter) {
  CAPTURE(angle_deg);
  CAPTURE(diameter);
  const StrengthSettings s = shear_coupon(angle_deg, diameter);
  const StrengthResult r = StrengthTest(s).run();
  const Material& m = s.coupon.material;
  REQUIRE(r.plastic_shear);
  REQUIRE(r.shear_curve.size() == m.shear_curve.size());
  for (const ShearCurveCheck& c : r.shear_curve) {
    CAPTURE(c.strain);
    MESSAGE(angle_deg << " deg, " << (diameter * 1e3) << " mm: gamma12 " << (c.strain * 100)
                      << "%: simulated / measured " << (c.simulated / c.measured));
    if (c.strain > 0.035) {  // beyond the law's strain at S12: cracked
      CHECK(std::isnan(c.simulated));
      continue;
    }
    CHECK(c.simulated == doctest::Approx(c.measured).epsilon(0.03));
    CHECK(c.simulated == doctest::Approx(c.law).epsilon(5e-4));  // linear between its 100 steps
  }
  const RambergOsgoodShear law(m);
  CHECK(r.strength == doctest::Approx(m.strength.S12).epsilon(0.02));
  // (A ratio: doctest's Approx is absolute for values below 1.)
  CHECK(r.strain_at_peak / law.strain_at(m.strength.S12) == doctest::Approx(1).epsilon(0.01));
  CHECK(r.first_failure_stress == doctest::Approx(r.strength).epsilon(1e-9));
  CHECK(r.stop == "failed");
  CHECK(r.cracked_sites == 1);
  CHECK(r.plastic_work > 0);
  // The curve rises to its peak.
  for (std::size_t k = 1; k < r.stress.size(); ++k) CHECK(r.stress[k] > r.stress[k - 1]);
  const nlohmann::json j = strength_json(r, s);
  REQUIRE(j.contains("shear_curve"));
  CHECK(j["shear_curve"].size() == m.shear_curve.size());
  CHECK(j["shear_curve"][1]["measured_tau12"].get<double>() == m.shear_curve[1].stress);
  CHECK(j["plastic_work"].get<double>() == r.plastic_work);
}

}  // namespace

TEST_CASE("in-plane shear follows the material's shear curve, at two particle sizes") {
  check_follows_curve(0, 0.1e-3);
  check_follows_curve(90, 0.1e-3);
  check_follows_curve(0, 0.05e-3);
}

TEST_CASE("in-plane shear of an off-axis ply with a shear curve: Puck's first-ply failure") {
  // At 30 deg pure tau_xy is sigma1 = 2 s c tau, sigma2 = -2 s c tau, tau12 = (c^2 - s^2) tau in
  // the ply's axes (Jones eq. 2.84): Puck's inter-fibre mode C (sigma2 < 0), the closed form of
  // core/failure_criteria.hpp, apart from the model. The frame holds a uniform stress, which
  // plastic shear strain does not change: the peak is the criterion's (measured 137.01 MPa
  // against 136.56, +0.33%).
  const StrengthSettings s = shear_coupon(30, 0.1e-3);
  const StrengthResult r = StrengthTest(s).run();
  CHECK(r.plastic_shear);
  CHECK(r.shear_curve.empty());  // gamma_xy is not gamma12 off axis
  const double puck = [&] {
    for (const CriterionStrength& t : r.theory)
      if (t.criterion == FailureCriterion::kPuck) return *t.strength;
    return 0.0;
  }();
  REQUIRE(puck > 0);
  CHECK(r.strength == doctest::Approx(puck).epsilon(0.03));
  CHECK(r.peak_mode == "matrix compression");
}

TEST_CASE("in-plane shear with a shear curve: what it does not do is a clear error") {
  StrengthSettings s = shear_coupon(0, 0.1e-3);
  s.method = StrengthMethod::kExplicit;
  CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("events method only"), Error);
  s = shear_coupon(0, 0.1e-3);
  s.strength_options.softening = true;
  CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("--softening does not apply"),
                       Error);
  s = shear_coupon(0, 0.1e-3);
  s.checkpoint.every = 10;
  s.checkpoint.file = "plastic.ckpt";
  CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("without checkpoints"), Error);
}

TEST_CASE("the report's model note says how the ply fails and how the run loads it") {
  StrengthSettings s = shear_coupon(0, 0.1e-3);
  const std::string plastic = strength_model_note(s);
  CHECK(plastic.find("at the material point") != std::string::npos);
  CHECK(plastic.find("plastic shear strain") != std::string::npos);
  CHECK(plastic.find("virial tau_xy") != std::string::npos);
  s.load = StrengthLoad::kTension;
  s.method = StrengthMethod::kExplicit;
  const std::string explicit_note = strength_model_note(s);
  CHECK(explicit_note.find("plastic shear strain") == std::string::npos);
  CHECK(explicit_note.find("damped dynamics") != std::string::npos);
  s.failure_criterion = PlyFailureModel::kBond;
  CHECK(strength_model_note(s).find("parallel bonds") != std::string::npos);
}
