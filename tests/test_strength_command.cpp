// The strength test to failure as users run it (experiments/protocols/strength.hpp, `plydem
// strength`, the run kind `strength`): its JSON keys, the 0 and 90 deg strengths of a coupon
// without scatter against XT and YT, the classical criteria it reports against closed forms
// written out here, reproducible scatter, its clear errors and the run kind on a tiny config.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/output/external_tool.hpp"
#include "experiments/output/strength_report.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using namespace plydem::test;
namespace fs = std::filesystem;

namespace {

// A small E-glass coupon: the same code path as the paper's, in seconds.
StrengthSettings small_coupon(double angle_deg) {
  StrengthSettings s;
  s.coupon.material = eglass();
  s.coupon.ply_angle = angle_deg * kDeg;
  s.coupon.length = 2e-3;
  s.coupon.width = 0.5e-3;
  return s;
}

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool finite_number(const nlohmann::json& j) {
  return j.is_number() && std::isfinite(j.get<double>());
}

// The classical off-axis strengths of a ply under sigma_x, written out from the stress
// transformation sigma1 = c^2 sx, sigma2 = s^2 sx, tau12 = -s c sx (Jones, eq. 2.84), independent
// of core/failure_criteria.cpp.
double max_stress_by_hand(const LaminaStrength& st, double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  double f = std::numeric_limits<double>::infinity();
  if (c * c > 0) f = std::min(f, st.XT / (c * c));
  if (s * s > 0) f = std::min(f, st.YT / (s * s));
  if (std::abs(s * c) > 0) f = std::min(f, st.S12 / std::abs(s * c));
  return f;
}
double tsai_hill_by_hand(const LaminaStrength& st, double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  const double q = std::pow(c, 4) / (st.XT * st.XT) +
                   (1 / (st.S12 * st.S12) - 1 / (st.XT * st.XT)) * c * c * s * s +
                   std::pow(s, 4) / (st.YT * st.YT);
  return 1 / std::sqrt(q);
}

}  // namespace

TEST_CASE(
    "strength test: the JSON keys are present and finite, the criteria are the closed forms") {
  const StrengthSettings s = small_coupon(30);
  const StrengthResult r = StrengthTest(s).run();
  const nlohmann::json j = strength_json(r, s);
  for (const char* key : {"strength", "strain_at_peak", "first_failure_stress", "wall_seconds"}) {
    INFO(key);
    REQUIRE(j.contains(key));
    CHECK(finite_number(j[key]));
  }
  CHECK(j["strength"].get<double>() > 0);
  CHECK(j["first_failure_stress"].get<double>() > 0);
  CHECK(j["first_failure_stress"].get<double>() <= j["strength"].get<double>());
  REQUIRE(j["events"].is_number_integer());
  CHECK(j["events"].get<long>() >= 1);

  REQUIRE(j["curve"].is_array());
  CHECK(j["curve"].size() == static_cast<std::size_t>(j["events"].get<long>()) + 1);
  CHECK(j["curve"][0][0].get<double>() == 0);
  CHECK(j["curve"][0][1].get<double>() == 0);
  double peak = 0;
  for (const nlohmann::json& point : j["curve"]) {
    REQUIRE(point.size() == 2);
    CHECK(finite_number(point[0]));
    CHECK(finite_number(point[1]));
    peak = std::max(peak, point[1].get<double>());
  }
  CHECK(j["strength"].get<double>() == peak);
  CHECK(j["curve"][1][1].get<double>() == j["first_failure_stress"].get<double>());

  // Broken bonds: by family and mode, adding up to what the model holds.
  const nlohmann::json& broken = j["broken_bonds"];
  int tension = 0, shear = 0;
  for (const auto& [family, counts] : broken["by_family"].items()) {
    tension += counts["tension"].get<int>();
    shear += counts["shear"].get<int>();
  }
  CHECK(tension == broken["tension"].get<int>());
  CHECK(shear == broken["shear"].get<int>());
  int in_model = 0;
  for (int b = 0; b < r.model->bonds.size(); ++b) in_model += r.model->bonds.is_broken(b) ? 1 : 0;
  CHECK(broken["total"].get<int>() == in_model);
  CHECK(in_model >= 1);

  // The four criteria at 30 deg; max-stress and Tsai-Hill against the closed forms above.
  const LaminaStrength& st = s.coupon.material.strength;
  for (const char* key : {"max_stress", "tsai_hill", "tsai_wu", "hashin"}) {
    INFO(key);
    REQUIRE(j["theory"].contains(key));
    CHECK(finite_number(j["theory"][key]));
  }
  CHECK(j["theory"]["max_stress"].get<double>() ==
        doctest::Approx(max_stress_by_hand(st, 30 * kDeg)).epsilon(1e-12));
  CHECK(j["theory"]["tsai_hill"].get<double>() ==
        doctest::Approx(tsai_hill_by_hand(st, 30 * kDeg)).epsilon(1e-12));
  // DAMAGE_NOTES §5: at 30 deg the criteria range from about 110 (Tsai-Wu) to 160 MPa.
  CHECK(j["theory"]["tsai_wu"].get<double>() < j["theory"]["max_stress"].get<double>());
}

TEST_CASE("strength test: a laminate's theory is the first-ply failure of CLT") {
  // [0/90]s under sigma_x by hand: the mid-plane strain from A/h, each ply's stress Q-bar eps in
  // its own axes, max-stress on each ply.
  const Material m = eglass();
  const LaminaStrength& st = m.strength;
  const Eigen::Matrix3d a = membrane_by_hand(m, {0, 90, 90, 0});
  const Eigen::Vector3d strain = a.inverse() * Eigen::Vector3d(1, 0, 0);
  double by_hand = std::numeric_limits<double>::infinity();
  for (double deg : {0.0, 90.0}) {
    const Eigen::Vector3d sigma = qbar_by_hand(m, deg * kDeg) * strain;  // coupon axes
    // 0 deg ply: sigma1 = sigma_x, sigma2 = sigma_y; 90 deg: swapped (tau_xy = 0 for both).
    const double s1 = deg == 0 ? sigma(0) : sigma(1), s2 = deg == 0 ? sigma(1) : sigma(0);
    if (s1 > 0) by_hand = std::min(by_hand, st.XT / s1);
    if (s2 > 0) by_hand = std::min(by_hand, st.YT / s2);
    if (s2 < 0) by_hand = std::min(by_hand, st.YC / -s2);
  }
  std::vector<Ply> plies;
  for (double deg : {0.0, 90.0, 90.0, 0.0}) plies.push_back({m, deg * kDeg, 0.2e-3});
  CHECK(first_ply_failure_stress(FailureCriterion::kMaxStress, plies, st) ==
        doctest::Approx(by_hand).epsilon(1e-12));
  // One ply: its off-axis strength.
  CHECK(first_ply_failure_stress(FailureCriterion::kTsaiHill, {{m, 30 * kDeg, 0.2e-3}}, st) ==
        doctest::Approx(tsai_hill_by_hand(st, 30 * kDeg)).epsilon(1e-12));
}

TEST_CASE(
    "strength test: a [0/90]s coupon without scatter first fails at CLT's first-ply failure") {
  // The simulated laminate (interface bonds, uniform grips) to its first break only, against
  // max-stress first-ply failure computed by hand as above: within 2% (measured 76.33 MPa
  // against 77.83 on 2 x 0.5 mm; the calibrated bulk under the plies' CLT stresses, 76.78).
  const Material m = eglass();
  const Eigen::Matrix3d a = membrane_by_hand(m, {0, 90, 90, 0});
  const Eigen::Vector3d strain = a.inverse() * Eigen::Vector3d(1, 0, 0);
  const Eigen::Vector3d sigma90 = qbar_by_hand(m, 90 * kDeg) * strain;
  const Eigen::Vector3d sigma0 = qbar_by_hand(m, 0) * strain;
  // The 90 deg plies crack first, across the fibres (their sigma2 is the coupon's sigma_x).
  const double by_hand = std::min(m.strength.YT / sigma90(0), m.strength.XT / sigma0(0));
  StrengthSettings s = small_coupon(0);
  s.layup = {0, 90 * kDeg, 90 * kDeg, 0};
  s.events.max_events = 1;
  const StrengthResult r = StrengthTest(s).run();
  INFO(fmt::format("DEM first failure {:.2f} MPa, max-stress first-ply failure {:.2f} MPa",
                   r.first_failure_stress * 1e-6, by_hand * 1e-6));
  CHECK(r.first_failure_stress == doctest::Approx(by_hand).epsilon(0.02));
  // The first break is in a 90 deg ply, in tension.
  REQUIRE(r.breaks.size() == 1);
  CHECK(r.breaks.front().mode == BondState::kBrokenTension);
  const int b = r.breaks.front().bond;
  const int ply = r.model->particles.ply(r.model->bonds.first(b));
  CHECK((ply == 1 || ply == 2));
}

// The coupon without scatter, its grips at the bulk's uniform state, first breaks at XT (0 deg)
// and YT (90 deg). At 0 deg that is its strength; at 90 deg the diagonal bonds still bridge a
// crack of the transverse bonds, and the peak comes later, above YT (measured, not asserted).
void check_first_failure_at_targets(double length, double width) {
  for (double angle : {0.0, 90.0}) {
    StrengthSettings s = small_coupon(angle);
    s.coupon.length = length;
    s.coupon.width = width;
    const StrengthResult r = StrengthTest(s).run();
    const LaminaStrength& st = s.coupon.material.strength;
    const double target = angle == 0 ? st.XT : st.YT;
    const std::string line = fmt::format(
        "{:g} x {:g} mm at {:g} deg: first failure {:.5g} MPa, strength {:.5g} MPa at {:.4f}% "
        "strain, target {:.5g} MPa, {} events",
        length * 1e3, width * 1e3, angle, r.first_failure_stress * 1e-6, r.strength * 1e-6,
        r.strain_at_peak * 100, target * 1e-6, r.events);
    MESSAGE(line);
    INFO(line);
    CHECK(r.model_first_failure == doctest::Approx(target).epsilon(1e-6));
    CHECK(r.first_failure_stress == doctest::Approx(target).epsilon(0.01));
    CHECK(r.strength >= r.first_failure_stress);
    if (angle == 0) CHECK(r.strength == doctest::Approx(target).epsilon(0.01));
  }
}

TEST_CASE("strength test: the 0 and 90 deg coupons without scatter first fail at XT and YT") {
  check_first_failure_at_targets(2e-3, 0.5e-3);
}

TEST_CASE("the paper's coupon: 0 and 90 deg first failures within 1% of XT and YT") {
  check_first_failure_at_targets(10e-3, 0.83e-3);
}

TEST_CASE("strength test: the tension test's rigid grips break the coupon next to them") {
  // Rigid along x, they restrain the ply's Poisson contraction
  // (strategies/strength_calibration.hpp): the first failure lies well below XT, at a bond next to
  // a grip.
  StrengthSettings s = small_coupon(0);
  s.grips = StrengthGrips::kFree;
  const StrengthResult r = StrengthTest(s).run();
  MESSAGE(fmt::format("free grips, 0 deg: first failure {:.4g} MPa, strength {:.4g} MPa",
                      r.first_failure_stress * 1e-6, r.strength * 1e-6));
  CHECK(r.first_failure_stress < 0.9 * s.coupon.material.strength.XT);
  const Eigen::Vector3d at = r.breaks.front().position;
  const double x_min = r.model->particles.reference_position.col(0).minCoeff();
  const double x_max = r.model->particles.reference_position.col(0).maxCoeff();
  const double grip = 2 * s.coupon.particle_diameter;
  CHECK(std::min(at.x() - x_min, x_max - at.x()) < 2 * grip);
}

TEST_CASE("strength test: the same seed gives the same strengths, another seed others") {
  StrengthSettings s = small_coupon(90);
  s.weibull_modulus = 10;
  s.seed = 7;
  const StrengthResult a = StrengthTest(s).run();
  const StrengthResult b = StrengthTest(s).run();
  s.seed = 8;
  const StrengthResult c = StrengthTest(s).run();
  CHECK(a.strength == b.strength);
  CHECK(a.stress == b.stress);
  CHECK(a.strength != c.strength);
  CHECK(a.weibull_modulus == 10);
}

TEST_CASE("strength test: clear errors") {
  SUBCASE("a material without strengths") {
    StrengthSettings s = small_coupon(0);
    s.coupon.material.strength = {};
    CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("XT"), Error);
  }
  SUBCASE("a target the strategy cannot reach: the calibration's refusal") {
    StrengthSettings s = small_coupon(0);
    s.strategy = "hex2d";  // cannot give E-glass YT with S12
    CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("YT = 40 MPa is not met"), Error);
  }
  SUBCASE("the random lattice has no unit cell to calibrate strengths on") {
    StrengthSettings s = small_coupon(0);
    s.strategy = "lattice";
    s.coupon.material = mild_ply();
    s.coupon.material.strength = eglass().strength;
    s.coupon.length = 0.6e-3;  // the lattice's stiffness calibration runs on the coupon's packing
    s.coupon.width = 0.3e-3;
    CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("no uniform bond state"), Error);
  }
  SUBCASE("interface strengths without a laminate") {
    StrengthSettings s = small_coupon(0);
    s.interface_strength.normal = 40e6;
    s.interface_strength.shear = 70e6;
    CHECK_THROWS_WITH_AS(StrengthTest{s}, doctest::Contains("need a laminate"), Error);
  }
  SUBCASE("NaN and negative values") {
    StrengthSettings s = small_coupon(0);
    s.weibull_modulus = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH_AS(StrengthTest{s}, doctest::Contains("Weibull modulus"), Error);
    s.weibull_modulus = -2;
    CHECK_THROWS_WITH_AS(StrengthTest{s}, doctest::Contains("Weibull modulus"), Error);
    s.weibull_modulus.reset();
    s.strength_options.friction_coefficient = -0.1;
    CHECK_THROWS_WITH_AS(StrengthTest{s}, doctest::Contains("friction"), Error);
    s.strength_options.friction_coefficient = 0;
    s.layup = {0, 90 * kDeg, 0};
    s.interface_strength.normal = -1;
    CHECK_THROWS_AS(StrengthTest{s}, Error);
  }
  SUBCASE("the explicit method is refused until the strength protocol has one") {
    StrengthSettings s = small_coupon(0);
    s.method = StrengthMethod::kExplicit;
    CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("--method events"), Error);
  }
  CHECK_THROWS_WITH_AS(parse_strength_method("implicit"), doctest::Contains("events or explicit"),
                       Error);
}

namespace {

// `plydem strength --failure-criterion puck`: the sites' stress judged by Puck's criterion, each
// crack opening every bond across it; the square coupon's peak against YT, and the JSON keys that
// say how it failed.
void check_peak_at_yt(double diameter) {
  {
    CAPTURE(diameter);
    StrengthSettings s = small_coupon(90);
    s.coupon.width = 1e-3;
    s.coupon.particle_diameter = diameter;
    s.failure_criterion = PlyFailureModel::kPuck;
    const StrengthResult r = StrengthTest(s).run();
    const nlohmann::json j = strength_json(r, s);
    const double yt = eglass().strength.YT;
    MESSAGE((diameter * 1e3) << " mm: peak " << r.strength / 1e6 << " MPa (YT " << yt / 1e6 << "), "
                             << r.events << " events, " << r.cracked_sites << " sites cracked, "
                             << r.broken_tension << " bonds open");
    // The site at the peak carries YT: the gauge's strain there is YT / E2 (measured: to 1e-12).
    // The peak stress, the reaction over the gauge's estimated cross-section, is 1.3% and 0.08%
    // low: that estimate's own error at ten and twenty rows (2.0112e-7 m^2 for the 3 mm coupon,
    // 1.998e-7 with a shorter gauge, where the coupon has 2e-7).
    CHECK(std::abs(r.strain_at_peak * eglass().E2 / yt - 1) < 1e-6);
    CHECK(std::abs(r.strength / yt - 1) < 0.02);
    CHECK(j["failure_criterion"] == "puck");
    CHECK(j["peak_mode"] == "matrix tension");
    CHECK(j["stop"] == "failed");
    // One crack across the width: a site per row of particles, at most a few more.
    const int rows = static_cast<int>(std::lround(s.coupon.width / diameter));
    CHECK(r.cracked_sites >= rows);
    CHECK(r.cracked_sites <= rows + 2);
  }
}

}  // namespace

// The material point's cases at 0.1 mm particles run everywhere, the sanitizer build included; the
// same at 0.05 mm ("finer particles:", label slow) in the release build.
TEST_CASE("strength test at the material point: a 90 deg ply peaks at YT in one matrix crack") {
  check_peak_at_yt(0.1e-3);
  // Bond by bond, the key says so and no site cracks.
  StrengthSettings bond = small_coupon(90);
  const StrengthResult r = StrengthTest(bond).run();
  CHECK(strength_json(r, bond)["failure_criterion"] == "bond");
  CHECK(strength_json(r, bond)["peak_mode"].is_null());
  CHECK(r.cracked_sites == 0);
}

// Puck's fracture angle in pure transverse compression, written out from Puck & Schuermann (2002)
// independently of core/failure_criteria.cpp: R23A = S12 / (2 p12-) (sqrt(1 + 2 p12- YC / S12) -
// 1), p23- = p12- R23A / S12, cos^2(theta) = 1 / (2 (1 + p23-)).
double puck_angle_in_transverse_compression(const LaminaStrength& st) {
  const double p = st.puck_p12_compression;
  const double r23a = st.S12 / (2 * p) * (std::sqrt(1 + 2 * p * st.YC / st.S12) - 1);
  const double p23 = p * r23a / st.S12;
  return std::acos(std::sqrt(1 / (2 * (1 + p23))));
}

namespace {

// `plydem strength --load compression --failure-criterion puck`: the grips move together; the 0 deg
// coupon fails across its fibres at XC, the 90 deg one along them at YC on Puck's inclined plane
// (about 50 degrees).
struct PeakCase {
  Material material;
  double angle_deg, diameter;
};

void check_compression_peaks(const std::vector<PeakCase>& cases) {
  for (const PeakCase& c : cases) {
    CAPTURE(c.material.name);
    CAPTURE(c.angle_deg);
    CAPTURE(c.diameter);
    StrengthSettings s = small_coupon(c.angle_deg);
    s.coupon.material = c.material;
    s.coupon.length = 3e-3;
    s.coupon.width = 1e-3;
    s.coupon.particle_diameter = c.diameter;
    s.failure_criterion = PlyFailureModel::kPuck;
    s.load = StrengthLoad::kCompression;
    const StrengthResult r = StrengthTest(s).run();
    const nlohmann::json j = strength_json(r, s);
    const LaminaStrength& st = c.material.strength;
    const bool fibre = c.angle_deg == 0;
    const double target = fibre ? st.XC : st.YC;
    const double modulus = fibre ? c.material.E1 : c.material.E2;
    MESSAGE(c.material.name << " " << c.angle_deg << " deg, " << (c.diameter * 1e3) << " mm: peak "
                            << (r.strength / 1e6) << " MPa against " << (target / 1e6) << ", "
                            << r.events << " events, plane at " << (r.peak_fracture_angle / kDeg)
                            << " deg");
    // Along the load, positive in compression: the site at the peak carries the strength, so the
    // gauge strain there is strength / modulus under uniaxial stress; the peak stress is the
    // reaction over the estimated cross-section (1.3% and 0.08% off at 10 and 20 rows, as above).
    CHECK(std::abs(r.strain_at_peak * modulus / target - 1) < 1e-6);
    CHECK(std::abs(r.strength / target - 1) < 0.02);
    CHECK(j["load"] == "compression");
    CHECK(j["peak_mode"] == (fibre ? "fibre compression" : "matrix compression"));
    const double angle = fibre ? 0.0 : puck_angle_in_transverse_compression(st);
    CHECK(j["peak_fracture_angle_deg"].get<double>() ==
          doctest::Approx(angle / kDeg).epsilon(1e-9));
    if (!fibre) CHECK(angle / kDeg > 45);
    // The classical criteria in compression: the 0 and 90 deg strengths are XC and YC.
    for (const CriterionStrength& t : r.theory) {
      CAPTURE(criterion_name(t.criterion));
      REQUIRE(t.strength);
      CHECK(*t.strength == doctest::Approx(target).epsilon(1e-12));
    }
  }
}

}  // namespace

TEST_CASE("strength test in compression at the material point: peaks at XC and YC, YC inclined") {
  check_compression_peaks({{eglass(), 0, 0.1e-3},
                           {eglass(), 90, 0.1e-3},
                           {carbon_ply(), 0, 0.1e-3},
                           {carbon_ply(), 90, 0.1e-3}});
}

namespace {

void check_grips_hold_corners(double diameter) {
  // At the material point the grips' default length is the edge strips' depth plus the longest
  // bond (strength.cpp, default_grip_length): the strips' corners, where the edge balance writes
  // no equilibrium, lie in the grips. Square E-glass, 3 x 1 mm, max-stress against its closed form
  // written out here: measured 0.968-0.981 of it at 60 and 75 deg, 0.1 and 0.05 mm particles; with
  // the two-diameter grips of failure bond by bond, 0.894 and 0.902 at 0.1 mm (the first site to
  // crack sits beside a grip).
  {
    for (double degrees : {60.0, 75.0}) {
      CAPTURE(diameter);
      CAPTURE(degrees);
      StrengthSettings s = small_coupon(degrees);
      s.coupon.length = 3e-3;
      s.coupon.width = 1e-3;
      s.coupon.particle_diameter = diameter;
      s.failure_criterion = PlyFailureModel::kMaxStress;
      const double reference = max_stress_by_hand(eglass().strength, degrees * kDeg);
      const double ratio = StrengthTest(s).run().strength / reference;
      MESSAGE((diameter * 1e3) << " mm, " << degrees << " deg: peak / max-stress " << ratio);
      CHECK(ratio > 0.96);
      CHECK(ratio < 1.01);
      if (diameter > 0.08e-3) {
        s.grip_length = 2 * diameter;  // the grips of failure bond by bond
        CHECK(StrengthTest(s).run().strength / reference < 0.92);
      }
    }
  }
}

}  // namespace

TEST_CASE("strength test at the material point off axis: the grips hold the edge strips' corners") {
  check_grips_hold_corners(0.1e-3);
}

namespace {

// A ply with fracture energies (the built-in ones give none): G_fibre 40 kJ/m^2, G_matrix
// 300 J/m^2, of the order of glass and carbon epoxies' (Pinho et al. 2006).
Material with_fracture_energies(Material m) {
  m.strength.G_fibre = 40e3;
  m.strength.G_matrix = 300;
  return m;
}

// The 3 x 1 mm coupon of the crack-energy cases: `material` with fracture energies at
// `angle_deg`, particles of `diameter`, failure at the material point by Puck's criterion.
StrengthSettings crack_coupon(const Material& material, double angle_deg, double diameter) {
  StrengthSettings s = small_coupon(angle_deg);
  s.coupon.material = with_fracture_energies(material);
  s.coupon.length = 3e-3;
  s.coupon.width = 1e-3;
  s.coupon.particle_diameter = diameter;
  s.failure_criterion = PlyFailureModel::kPuck;
  return s;
}

// `plydem strength --failure-criterion puck --softening`: each site's crack softens so that it
// dissipates G over its share of the crack plane. The reference is G times the area of the crack
// measured on the coupon, independent of the sites' shares: the 0 and 90 deg coupons fail in one
// straight crack across the width w, of area w t; the energy the cracks dissipated is summed over
// the events by the events solver. Measured (square, 3 x 1 mm): 1.0000 of G w t for E-glass and
// T300 at 0 and 90 deg, 0.1 and 0.05 mm particles.
void check_crack_energy(const Material& material, double angle_deg, double diameter) {
  CAPTURE(material.name);
  CAPTURE(angle_deg);
  CAPTURE(diameter);
  StrengthSettings s = crack_coupon(material, angle_deg, diameter);
  s.strength_options.softening = true;
  s.events.stop_fraction = 0;  // to the end: the crack open across the whole width
  const StrengthResult r = StrengthTest(s).run();
  const nlohmann::json j = strength_json(r, s);
  const bool fibre = angle_deg == 0;
  const double area = s.coupon.width * s.coupon.thickness;
  const LaminaStrength& st = s.coupon.material.strength;
  const double g = fibre ? st.G_fibre : st.G_matrix;
  MESSAGE(material.name << " " << angle_deg << " deg, " << (diameter * 1e3)
                        << " mm: dissipated / (G w t) " << r.crack_energy / (g * area)
                        << ", crack area / (w t) " << r.crack_area / area << ", peak "
                        << (r.strength / 1e6) << " MPa, " << r.events << " events, "
                        << r.cracked_sites << " sites");
  CHECK(std::abs(r.crack_energy / (g * area) - 1) < 0.02);
  CHECK(std::abs(r.crack_area / area - 1) < 0.02);
  CHECK(r.crack_fracture_energy == doctest::Approx(g * r.crack_area).epsilon(1e-12));
  // One crack, a site per row; the peak at the strength, as brittle (the first tooth's).
  CHECK(r.cracked_sites == static_cast<int>(std::lround(s.coupon.width / diameter)));
  CHECK(std::abs(r.strength / (fibre ? st.XT : st.YT) - 1) < 0.02);
  CHECK(r.brittle_sites == 0);
  CHECK(r.softening_sites == 0);
  CHECK(j["crack_dissipated_energy"].get<double>() == r.crack_energy);
  CHECK(j["crack_area"].get<double>() == r.crack_area);
  CHECK(j["brittle_sites"] == 0);
}

}  // namespace

namespace {

// The values of the VTU DataArray `name` in `text` (ASCII, as plydem writes it).
std::vector<double> vtu_array(const std::string& text, const std::string& name) {
  const std::size_t at = text.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const std::size_t begin = text.find('>', at) + 1, end = text.find("</DataArray>", begin);
  std::istringstream in(text.substr(begin, end - begin));
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  return values;
}

}  // namespace

TEST_CASE("strength test at the material point: the VTU series shows each site's crack") {
  StrengthSettings s = crack_coupon(eglass(), 90, 0.1e-3);
  s.strength_options.softening = true;
  s.events.stop_fraction = 0;
  const StrengthResult r = StrengthTest(s).run();
  const fs::path out = fresh_directory("strength_site_vtu");
  write_strength_vtu(r, out, "s");
  const std::string text = read(out / "vtu" / "s_0_particles.vtu");
  const std::vector<double> mode = vtu_array(text, "crack_mode");
  const std::vector<double> energy = vtu_array(text, "crack_energy");
  const std::vector<double> normal = vtu_array(text, "crack_normal");
  const std::vector<double> teeth = vtu_array(text, "crack_teeth");
  REQUIRE(mode.size() == static_cast<std::size_t>(r.particles));
  REQUIRE(energy.size() == mode.size());
  REQUIRE(teeth.size() == mode.size());
  REQUIRE(normal.size() == 3 * mode.size());
  double total = 0;
  int cracked = 0;
  for (std::size_t i = 0; i < mode.size(); ++i) {
    total += energy[i];
    if (mode[i] < 0) continue;
    ++cracked;
    CHECK(mode[i] == static_cast<double>(PlyFailureMode::kMatrixTension));
    // A 90 deg ply's matrix crack runs along the fibre, y: its normal is x (either sense).
    CHECK(std::abs(normal[3 * i]) == doctest::Approx(1.0).epsilon(1e-12));
    CHECK(teeth[i] > 1);
  }
  CHECK(cracked == r.cracked_sites);
  CHECK(total == doctest::Approx(r.crack_energy).epsilon(1e-9));
}

TEST_CASE("strength test at the material point: the crack picture draws each site's plane") {
  // A uniform 90 deg coupon: one straight crack across the width, each of its 10 sites a segment
  // one diameter long along y at the same x, beside the bonds it opened.
  const StrengthResult r = StrengthTest(crack_coupon(eglass(), 90, 0.1e-3)).run();
  const fs::path out = fresh_directory("strength_site_png");
  plot_crack_pattern(r, out, "s_cracks", "90 deg");
  std::istringstream data(read(out / "plots" / "s_cracks.dat"));
  std::string line;
  bool in_block = false;
  std::vector<Eigen::Vector4d> segments;
  while (std::getline(data, line)) {
    if (line.rfind('#', 0) == 0) {
      in_block = line == "# site cracks, matrix modes";
      continue;
    }
    std::istringstream row(line);
    Eigen::Vector4d v;
    if (in_block && (row >> v(0) >> v(1) >> v(2) >> v(3))) segments.push_back(v);
  }
  REQUIRE(segments.size() == static_cast<std::size_t>(r.cracked_sites));
  CHECK(r.cracked_sites == 10);
  double covered = 0;
  for (const Eigen::Vector4d& v : segments) {
    CHECK(v(0) == doctest::Approx(segments.front()(0)));  // one x [mm]
    CHECK(v(2) == doctest::Approx(0.0));                  // along y
    covered += std::abs(v(3));
  }
  CHECK(covered == doctest::Approx(1.0));  // the whole 1 mm width
}

TEST_CASE("strength test at the material point: softening cracks dissipate G over their area") {
  // E-glass across the fibres, the carbon ply along them (the other two: the finer case's).
  check_crack_energy(eglass(), 90, 0.1e-3);
  check_crack_energy(carbon_ply(), 0, 0.1e-3);
  // Brittle, the same crack dissipates what its bonds held at the peak: far less than G w t here
  // (the characteristic length E2 G / YT^2 is 3 mm, the sites 0.1 mm).
  const StrengthSettings s = crack_coupon(eglass(), 90, 0.1e-3);
  const StrengthResult brittle = StrengthTest(s).run();
  CHECK(brittle.crack_energy < 0.1 * brittle.crack_fracture_energy);
  CHECK(brittle.brittle_sites == 0);  // counted only where softening was asked
}

TEST_CASE("strength test at the material point: softening sites too large to soften open brittle") {
  // A fracture energy so small that the sites' characteristic length E2 G / YT^2 (0.003 mm) is
  // far below the particles' 0.1 mm: they cannot soften without snap-back, open brittle, and the
  // report says so.
  StrengthSettings s = small_coupon(90);
  s.coupon.material = with_fracture_energies(eglass());
  s.coupon.material.strength.G_matrix = 0.3;
  s.coupon.particle_diameter = 0.1e-3;
  s.failure_criterion = PlyFailureModel::kPuck;
  s.strength_options.softening = true;
  const StrengthResult r = StrengthTest(s).run();
  CHECK(r.brittle_sites == r.cracked_sites);
  CHECK(r.brittle_sites > 0);
  const std::string table = format_strength_table(r, s);
  CHECK(table.find("sites that opened brittle") != std::string::npos);
  CHECK(table.find("too large to soften without snap-back") != std::string::npos);
}

namespace {

// In-plane shear in the frame (--load shear): the peak of a 0 or 90 deg ply is S12, reached at
// the gauge's shear strain S12 / G12 (the material's constants, not the model's), and it is the
// first failure (the frame's coupon only loses load after it). Measured (square, 3 x 1 mm):
// 1.0000 of S12 for E-glass and T300 at 0 and 90 deg, 0.1 and 0.05 mm particles.
void check_shear_peaks(const std::vector<PeakCase>& cases) {
  for (const PeakCase& c : cases) {
    CAPTURE(c.material.name);
    CAPTURE(c.angle_deg);
    CAPTURE(c.diameter);
    StrengthSettings s = crack_coupon(c.material, c.angle_deg, c.diameter);
    s.load = StrengthLoad::kShear;
    const StrengthResult r = StrengthTest(s).run();
    const Material& m = s.coupon.material;
    MESSAGE(m.name << " " << c.angle_deg << " deg, " << (c.diameter * 1e3)
                   << " mm: shear peak / S12 " << (r.strength / m.strength.S12)
                   << ", strain at peak x G12 / S12 "
                   << (r.strain_at_peak * m.G12 / m.strength.S12));
    CHECK(r.strength == doctest::Approx(m.strength.S12).epsilon(0.02));
    CHECK(r.strain_at_peak * m.G12 == doctest::Approx(m.strength.S12).epsilon(0.02));
    CHECK(r.first_failure_stress == doctest::Approx(r.strength).epsilon(1e-9));
    CHECK(r.cracked_sites > 0);
    for (const CriterionStrength& t : r.theory) {
      REQUIRE(t.strength);
      CHECK(*t.strength == doctest::Approx(m.strength.S12).epsilon(1e-12));
    }
  }
}

}  // namespace

TEST_CASE("finer particles: at the material point, YT, XC, YC, S12 and off axis at 0.05 mm") {
  check_peak_at_yt(0.05e-3);
  check_crack_energy(eglass(), 90, 0.05e-3);
  check_crack_energy(eglass(), 0, 0.05e-3);
  check_crack_energy(carbon_ply(), 90, 0.05e-3);
  check_crack_energy(eglass(), 0, 0.1e-3);
  check_crack_energy(carbon_ply(), 90, 0.1e-3);
  // E-glass's 0 deg coupon at 0.1 mm only: at 0.05 mm its splits after the peak take 5 s.
  check_compression_peaks(
      {{eglass(), 90, 0.05e-3}, {carbon_ply(), 0, 0.05e-3}, {carbon_ply(), 90, 0.05e-3}});
  check_grips_hold_corners(0.05e-3);
  check_shear_peaks({{eglass(), 0, 0.05e-3}, {carbon_ply(), 90, 0.05e-3}});
}

TEST_CASE("strength test in shear at the material point: S12 as the peak, at S12 / G12") {
  check_shear_peaks({{eglass(), 0, 0.1e-3},
                     {eglass(), 90, 0.1e-3},
                     {carbon_ply(), 0, 0.1e-3},
                     {carbon_ply(), 90, 0.1e-3}});
}

TEST_CASE("strength test in shear: what it cannot do is a clear error") {
  StrengthSettings s = small_coupon(0);
  s.load = StrengthLoad::kShear;
  CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains("shear (--load shear) needs failure at"),
                       Error);
  s.failure_criterion = PlyFailureModel::kPuck;
  s.grips = StrengthGrips::kFree;
  CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains("--grips free holds only its ends"), Error);
  s.grips = StrengthGrips::kUniform;
  s.hole_diameter = 0.2e-3;
  CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains("with a hole is not modelled"), Error);
  CHECK(parse_strength_load(strength_load_name(StrengthLoad::kShear)) == StrengthLoad::kShear);
}

TEST_CASE("strength test in compression: what it cannot do is a clear error") {
  StrengthSettings s = small_coupon(90);
  s.load = StrengthLoad::kCompression;
  // Bond by bond: the parallel-bond law has no compressive strength.
  CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains("needs failure at the material point"),
                       Error);
  CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("--failure-criterion"), Error);
  // A material without its compressive strengths.
  s.failure_criterion = PlyFailureModel::kPuck;
  s.coupon.material.strength.YC = 0;
  CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("does not give YC"), Error);
  s.coupon.material.strength.XC = 0;
  CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("does not give XC and YC"), Error);
  CHECK_THROWS_WITH_AS(parse_strength_load("torsion"),
                       doctest::Contains("unknown load 'torsion' (tension, compression or shear)"),
                       Error);
  CHECK(parse_strength_load(strength_load_name(StrengthLoad::kCompression)) ==
        StrengthLoad::kCompression);
}

namespace {

// A [0/90/0] plate of 0.5 mm plies (the paper's interface stiffness) at the material point, to
// failure with the experiment's stop_fraction 0.5 and with 0.02: the same peak, the 0 deg plies'
// fibre failure.
void check_crack_through_ply(double length, double width, double diameter) {
  StrengthSettings s = small_coupon(0);
  s.layup = {0, 90 * kDeg, 0};
  s.coupon.length = length;
  s.coupon.width = width;
  s.coupon.thickness = 0.5e-3;
  s.coupon.particle_diameter = diameter;
  s.interface.normal = 1e14;
  s.interface.shear = 1e13;
  s.failure_criterion = PlyFailureModel::kPuck;
  s.events.stop_fraction = 0.5;
  const StrengthResult half = StrengthTest(s).run();
  s.events.stop_fraction = 0.02;
  const StrengthResult to_the_end = StrengthTest(s).run();
  MESSAGE("[0/90/0] at the material point: strength "
          << (half.strength / 1e6) << " MPa (stop 0.5), " << (to_the_end.strength / 1e6)
          << " MPa (stop 0.02), " << half.events << " events, 90 deg ply cracked sites "
          << half.cracked_sites);
  // The dip the stop rule rides through: a critical state before the peak below half the
  // largest reaction so far.
  bool dipped = false;
  double highest = 0;
  for (int k = 1; k <= half.peak + 1; ++k) {
    highest = std::max(highest, half.stress[static_cast<std::size_t>(k)]);
    dipped = dipped || half.stress[static_cast<std::size_t>(k)] < 0.5 * highest;
  }
  CHECK(dipped);
  CHECK(half.strength == to_the_end.strength);
  CHECK(half.peak_mode == "fibre tension");
  CHECK(half.strength > 0.8 * 2.0 / 3.0 * s.coupon.material.strength.XT);
  CHECK(half.stop == "failed");
}

}  // namespace

// The hole_failure experiment's unnotched [0/90/0] plate (its --quick size) at the material
// point: while a 90 deg ply's crack runs across it, the critical states' reaction dips below half
// the peak so far (the next site at the crack's tip fails at a fraction of the load) and
// recovers. With the experiment's stop_fraction 0.5 the run stopped there at 263 MPa; the
// stiffness test lets it go on to the 0 deg plies' fibre failure, the peak of a run to 2%:
// 766.6 MPa, 0.90 of the ply-discount bound (2/3) XT = 853 MPa. In the release build only (label
// slow); a plate of 5 x 3 mm runs the same path in both.
TEST_CASE("finer particles: at the material point a crack running through a ply is not failure") {
  check_crack_through_ply(10e-3, 6e-3, 0.5e-3);
}

TEST_CASE("strength test at the material point: a crack running through a ply is not failure") {
  check_crack_through_ply(5e-3, 3e-3, 0.4e-3);
}

TEST_CASE("strength test at the material point: strength scatter per site, the weakest link") {
  // Each site's strengths times a Weibull factor of modulus m and mean 1: a uniform 90 deg coupon
  // first fails at its weakest of n judged sites, whose expectation is YT n^(-1/m) (the minimum of
  // n Weibull variables: scale n^(-1/m), weakest-link theory). Over 20 seeds the mean first
  // failure lies within 8% of it (its standard error: about 0.12 / sqrt(20) = 2.7% at m = 10),
  // and the same seed gives the same run.
  const double m = 10;
  StrengthSettings s = crack_coupon(eglass(), 90, 0.1e-3);
  s.weibull_modulus = m;
  double sum = 0;
  int judged = 0;
  const int seeds = 20;
  for (int seed = 1; seed <= seeds; ++seed) {
    s.seed = static_cast<std::uint64_t>(seed);
    const StrengthResult r = StrengthTest(s).run();
    sum += r.first_failure_stress / s.coupon.material.strength.YT;
    judged = 0;
    for (int i = 0; i < r.model->particles.size(); ++i)
      judged += r.model->particles.group(i) == static_cast<int>(BoundaryGroup::kFree) ? 1 : 0;
    CHECK(r.strength >= r.first_failure_stress);
  }
  const double expected = std::pow(static_cast<double>(judged), -1.0 / m);
  MESSAGE("first failure / YT over " << seeds << " seeds: " << (sum / seeds) << ", weakest link of "
                                     << judged << " sites " << expected);
  CHECK(sum / seeds == doctest::Approx(expected).epsilon(0.08).scale(0));
  s.seed = 7;
  const StrengthResult a = StrengthTest(s).run(), b = StrengthTest(s).run();
  CHECK(a.stress == b.stress);
  CHECK(a.strength < 0.9 * s.coupon.material.strength.YT);
  // Per crack band (--scatter-per site): the sites of one column along the 90 deg fibres share a
  // factor, so the first crack runs down one column, all of it at that column's strength.
  s.scatter_per_crack_site = true;
  const StrengthResult band = StrengthTest(s).run();
  REQUIRE(!band.path.empty());
  const Particles& p = band.model->particles;
  const double x = p.reference_position(band.path.front().site, 0);
  int in_column = 0;
  for (const EventPoint& e : band.path)
    if (e.site >= 0 && std::abs(p.reference_position(e.site, 0) - x) < 1e-9) ++in_column;
  CHECK(in_column == 10);  // the width's 10 rows
  CHECK(band.first_failure_stress != a.first_failure_stress);
}

TEST_CASE("strength test at the material point: what it does not do yet is a clear error") {
  StrengthSettings s = small_coupon(90);
  s.failure_criterion = PlyFailureModel::kHashin;
  s.layup = {0, 90 * kDeg};
  s.interface_strength.normal = 30e6;
  s.interface_strength.shear = 40e6;
  CHECK_THROWS_WITH_AS(StrengthTest(s).run(), doctest::Contains("breaks no interface yet"), Error);
  // The material's own key asks for it the same way.
  StrengthSettings m = s;
  m.failure_criterion.reset();
  m.coupon.material.failure_criterion = PlyFailureModel::kTsaiWu;
  CHECK_THROWS_WITH_AS(StrengthTest(m).run(), doctest::Contains("\"tsai-wu\""), Error);
  // Softening cracks need the fracture energies (the built-in materials give none).
  StrengthSettings soft = small_coupon(90);
  soft.failure_criterion = PlyFailureModel::kPuck;
  soft.strength_options.softening = true;
  CHECK_THROWS_WITH_AS(StrengthTest(soft).run(), doctest::Contains("G_fibre and G_matrix"), Error);
  soft.coupon.material.strength.G_fibre = 40e3;
  soft.coupon.material.strength.G_matrix = -300;
  CHECK_THROWS_WITH_AS(StrengthTest(soft).run(), doctest::Contains("G_matrix"), Error);
  // Cracks that would not run along a row of sites: a crack along the square lattice's diagonal
  // (measured: a band of 181 cracked sites dissipating 1.2 G w t where a row's crack dissipates
  // G w t), and the hexagonal lattice.
  soft.coupon.material.strength.G_matrix = 300;
  soft.strategy_options = {{"fibre_offset", 45}};
  CHECK_THROWS_WITH_AS(StrengthTest(soft).run(), doctest::Contains("fibre_offset=0"), Error);
  soft.strategy_options.clear();
  soft.strategy = "hex2d";
  CHECK_THROWS_WITH_AS(StrengthTest(soft).run(), doctest::Contains("--strategy square"), Error);
}

TEST_CASE("tiny run: the kind 'strength' writes its table, rows, figures and VTU series") {
  const fs::path out = fresh_directory("strength_tiny");
  RunOptions options;
  options.config = fs::path(PLYDEM_TEST_DATA_DIR) / "tiny_strength.toml";
  options.out_dir = out;
  const RunSummary summary = run_experiment(options);
  const std::string report = read(summary.report);
  CHECK(report.find("## Strength against angle") != std::string::npos);
  CHECK(report.find("| 0° |") != std::string::npos);
  CHECK(report.find("| 90° |") != std::string::npos);
  const std::string csv = read(summary.results);
  for (const char* row :
       {"tiny_strength,0 deg,strength,dem square,", "tiny_strength,90 deg,strength,dem square,",
        "tiny_strength,90 deg,strength,tsai-wu,", "tiny_strength,0 deg,strength,max-stress,",
        "tiny_strength,90 deg,strength,hashin,", "tiny_strength,0 deg,strength,tsai-hill,"}) {
    INFO(std::string(row));
    CHECK(csv.find(row) != std::string::npos);
  }
  // The cracks of each angle: a CSV of them and their count per ply in results.csv.
  CHECK(csv.find("tiny_strength,90 deg,cracks,dem square,") != std::string::npos);
  CHECK(csv.find("tiny_strength,90 deg,cracks ply 1,dem square,") != std::string::npos);
  CHECK(read(out / "tiny_strength_90deg_cracks.csv").rfind("id,kind,ply,x_mm,", 0) == 0);
  CHECK(report.find("broken bonds form") != std::string::npos);
  // The VTU series of each angle: selected events with the bond state as cell data.
  for (const char* angle : {"0deg", "90deg"}) {
    const fs::path pvd = out / "vtu" / fmt::format("tiny_strength_{}.pvd", angle);
    REQUIRE(fs::exists(pvd));
    const std::string text = read(pvd);
    CHECK(text.find("_0_bonds.vtu") != std::string::npos);
    const std::string bonds =
        read(out / "vtu" / fmt::format("tiny_strength_{}_0_bonds.vtu", angle));
    CHECK(bonds.find("Name=\"state\"") != std::string::npos);
    CHECK(bonds.find("Name=\"damage\"") != std::string::npos);
  }
  if (!gnuplot_availability().available) {
    skip("gnuplot is not installed: the figures are not drawn");
    return;
  }
  CHECK(fs::exists(out / "tiny_strength_strength.png"));
  CHECK(fs::exists(out / "tiny_strength_0deg_stress_strain.png"));
  CHECK(fs::exists(out / "tiny_strength_90deg_cracks.png"));
  fs::remove_all(out);
}
