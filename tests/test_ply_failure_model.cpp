// The material file's failure model (failure_criterion, Puck's inclinations) and its measured
// shear curve (shear_curve): parsing, the refusals of bad input, and the Ramberg-Osgood fit
// (core/shear_curve.hpp) against the measured E-glass/MY750 curve (Soden et al. 1998, DAMAGE_NOTES
// §9), whose points are written here from the source, not taken from the library.
#include <doctest/doctest.h>

#include <string>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/shear_curve.hpp"
#include "support/coupon_fixtures.hpp"

using namespace plydem;
using plydem::test::contains;
using plydem::test::error_message;

namespace {

const std::string kElastic =
    "name = \"g\"\nE1 = 45.6e9\nE2 = 16.2e9\nG12 = 5.83e9\nnu12 = 0.278\nnu23 = 0.4\n"
    "XT = 1280e6\nYT = 40e6\nS12 = 73e6\n";

std::string refusal(const std::string& extra) {
  return error_message([&] { parse_material(kElastic + extra, "m.toml"); });
}

}  // namespace

TEST_CASE("failure_criterion names the failure model; unknown names are refused") {
  CHECK(parse_material(kElastic, "m.toml").failure_criterion == PlyFailureModel::kBond);
  const struct {
    const char* name;
    PlyFailureModel model;
  } cases[] = {{"bond", PlyFailureModel::kBond},
               {"hashin", PlyFailureModel::kHashin},
               {"puck", PlyFailureModel::kPuck},
               {"max-stress", PlyFailureModel::kMaxStress},
               {"tsai-wu", PlyFailureModel::kTsaiWu}};
  for (const auto& c : cases) {
    CAPTURE(c.name);
    const Material m =
        parse_material(kElastic + "failure_criterion = \"" + c.name + "\"\n", "m.toml");
    CHECK(m.failure_criterion == c.model);
    CHECK(std::string(failure_model_name(m.failure_criterion)) == c.name);
  }
  const std::string unknown = refusal("failure_criterion = \"tsai_hill\"\n");
  CHECK(contains(unknown, "unknown failure_criterion 'tsai_hill'"));
  CHECK(contains(unknown, "bond, hashin, puck, max-stress, tsai-wu"));
  CHECK(contains(refusal("failure_criterion = 3\n"), "must be a string"));
}

TEST_CASE("a criterion the engine does not simulate yet is refused where bonds would break") {
  const Material bond = parse_material(kElastic, "m.toml");
  CHECK_NOTHROW(require_strengths(bond, "the cross-ply experiment"));
  const Material hashin = parse_material(kElastic + "failure_criterion = \"hashin\"\n", "m.toml");
  const std::string message =
      error_message([&] { require_strengths(hashin, "the cross-ply experiment"); });
  CHECK(contains(message, "failure_criterion = 'hashin'"));
  CHECK(contains(message, "the cross-ply experiment"));
  CHECK(contains(message, "not in the engine yet except in plydem strength"));
}

TEST_CASE("Puck's inclination parameters are read and checked") {
  const Material m =
      parse_material(kElastic + "puck_p12_tension = 0.35\npuck_p12_compression = 0.3\n", "m.toml");
  CHECK(m.strength.puck_p12_tension == 0.35);
  CHECK(m.strength.puck_p12_compression == 0.3);
  CHECK(contains(refusal("puck_p12_compression = 1.2\n"), "puck_p12_compression must lie in"));
  CHECK(contains(refusal("puck_p12_tension = -0.1\n"), "puck_p12_tension must lie in"));
}

TEST_CASE("shear_curve is read as [gamma12, tau12] points and refused when it is not a curve") {
  const Material m = parse_material(
      kElastic + "shear_curve = [[0.01, 47.4e6], [0.02, 63.8e6], [0.04, 73.0e6]]\n", "m.toml");
  REQUIRE(m.shear_curve.size() == 3);
  CHECK(m.shear_curve[1].strain == 0.02);
  CHECK(m.shear_curve[1].stress == 63.8e6);
  // Not monotonic.
  CHECK(contains(refusal("shear_curve = [[0.01, 47.4e6], [0.02, 63.8e6], [0.03, 60e6]]\n"),
                 "not monotonic"));
  CHECK(contains(refusal("shear_curve = [[0.02, 47.4e6], [0.01, 63.8e6]]\n"), "not monotonic"));
  // Stiffer than G12, negative, malformed.
  CHECK(contains(refusal("shear_curve = [[0.01, 70e6]]\n"), "above the linear response"));
  CHECK(contains(refusal("shear_curve = [[-0.01, 10e6]]\n"), "finite and positive"));
  CHECK(contains(refusal("shear_curve = [[0.01, 47.4e6, 1]]\n"), "pair"));
  CHECK(contains(refusal("shear_curve = [[0.01, \"a\"]]\n"), "two numbers"));
  CHECK(contains(refusal("shear_curve = []\n"), "non-empty list"));
  CHECK(contains(refusal("shear_curve = 3\n"), "non-empty list"));
}

TEST_CASE("the Ramberg-Osgood fit follows the measured E-glass/MY750 shear curve") {
  // Soden, Hinton & Kaddour 1998 (DAMAGE_NOTES §1, §9): 47.4, 63.8 and 73.0 MPa at 1, 2, 4 %, in
  // tests/data/eglass_my750_soden.toml (also an example of a material file with the new keys).
  const Material eglass = load_material(PLYDEM_TEST_DATA_DIR "/eglass_my750_soden.toml");
  const RambergOsgoodShear law(eglass);
  MESSAGE("Ramberg-Osgood fit of E-glass/MY750: eta = "
          << law.eta() << ", alpha = " << law.alpha()
          << " Pa^(1-eta); tau at 1, 2, 4 %: " << law.stress_at(0.01) / 1e6 << ", "
          << law.stress_at(0.02) / 1e6 << ", " << law.stress_at(0.04) / 1e6 << " MPa");
  CHECK(law.stress_at(0.01) == doctest::Approx(47.4e6).epsilon(0.03));
  CHECK(law.stress_at(0.02) == doctest::Approx(63.8e6).epsilon(0.03));
  CHECK(law.stress_at(0.04) == doctest::Approx(73.0e6).epsilon(0.03));
  CHECK(law.worst_stress_error() < 0.03);
  CHECK(law.eta() > 1);
  CHECK(law.alpha() > 0);
  // Linear at small strain (G12), and stress_at inverts strain_at.
  CHECK(law.stress_at(1e-5) == doctest::Approx(eglass.G12 * 1e-5).epsilon(1e-3));
  for (double tau : {1e6, 30e6, 60e6, 80e6}) {
    CHECK(law.stress_at(law.strain_at(tau)) == doctest::Approx(tau).epsilon(1e-12));
  }
  // A curve of one point cannot be fitted; a linear one has no softening to fit.
  Material one = eglass;
  one.shear_curve.resize(1);
  CHECK(contains(error_message([&] { RambergOsgoodShear{one}; }), "at least two"));
  Material linear = eglass;
  linear.shear_curve = {{0.01, 58.3e6}, {0.02, 116.6e6}};
  CHECK(contains(error_message([&] { RambergOsgoodShear{linear}; }), "no Ramberg-Osgood law"));
}
