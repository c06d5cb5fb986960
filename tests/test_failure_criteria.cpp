// The closed-form failure criteria (core/failure_criteria.hpp) against values worked out by hand
// from the lamina strengths: off-axis formulas written out for each criterion, and the criteria's
// own polynomials evaluated at the load factor the library returns.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/failure_criteria.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using plydem::test::kDeg;

namespace {

LaminaStrength eglass_strength() {
  return test::eglass().strength;
}

}  // namespace

TEST_CASE("to_ply_axes turns a coupon stress into the ply's axes") {
  // sigma_x = 1 at 30 deg: sigma1 = cos^2 = 3/4, sigma2 = sin^2 = 1/4, tau12 = -sin cos.
  const PlyStress s = to_ply_axes(1.0, 0.0, 0.0, 30 * kDeg);
  CHECK(s.sigma1 == doctest::Approx(0.75).epsilon(1e-14));
  CHECK(s.sigma2 == doctest::Approx(0.25).epsilon(1e-14));
  CHECK(s.tau12 == doctest::Approx(-std::sqrt(3.0) / 4).epsilon(1e-14));
  // Pure shear tau_xy = 1 at 45 deg is sigma1 = 1, sigma2 = -1, tau12 = 0.
  const PlyStress shear = to_ply_axes(0.0, 0.0, 1.0, 45 * kDeg);
  CHECK(shear.sigma1 == doctest::Approx(1.0).epsilon(1e-14));
  CHECK(shear.sigma2 == doctest::Approx(-1.0).epsilon(1e-14));
  CHECK(std::abs(shear.tau12) < 1e-15);
  // Turning back by -theta gives the coupon stress again; the trace is invariant.
  const PlyStress general = to_ply_axes(3.0, -2.0, 1.5, 20 * kDeg);
  const PlyStress back = to_ply_axes(general.sigma1, general.sigma2, general.tau12, -20 * kDeg);
  CHECK(back.sigma1 == doctest::Approx(3.0).epsilon(1e-13));
  CHECK(back.sigma2 == doctest::Approx(-2.0).epsilon(1e-13));
  CHECK(back.tau12 == doctest::Approx(1.5).epsilon(1e-13));
  CHECK(general.sigma1 + general.sigma2 == doctest::Approx(1.0).epsilon(1e-13));
}

TEST_CASE("criterion names and order") {
  const std::vector<FailureCriterion> all = all_criteria();
  REQUIRE(all.size() == 5);
  CHECK(std::string(criterion_name(all[0])) == "max_stress");
  CHECK(std::string(criterion_name(all[1])) == "tsai_hill");
  CHECK(std::string(criterion_name(all[2])) == "tsai_wu");
  CHECK(std::string(criterion_name(all[3])) == "hashin");
  CHECK(std::string(criterion_name(all[4])) == "puck");
}

TEST_CASE("every criterion gives the lamina strengths under uniaxial ply stresses") {
  const LaminaStrength x = eglass_strength();
  const struct {
    PlyStress unit;
    double strength;
  } cases[] = {{{1, 0, 0}, x.XT},  {{-1, 0, 0}, x.XC}, {{0, 1, 0}, x.YT},
               {{0, -1, 0}, x.YC}, {{0, 0, 1}, x.S12}, {{0, 0, -1}, x.S12}};
  for (FailureCriterion c : all_criteria()) {
    for (const auto& k : cases) {
      CAPTURE(std::string(criterion_name(c)));
      CAPTURE(k.unit.sigma1);
      CAPTURE(k.unit.sigma2);
      CAPTURE(k.unit.tau12);
      CHECK(failure_load_factor(c, k.unit, x) == doctest::Approx(k.strength).epsilon(1e-12));
    }
  }
  // The off-axis strength at 0 and 90 deg is XT and YT.
  for (FailureCriterion c : all_criteria()) {
    CHECK(off_axis_strength(c, x, 0.0) == doctest::Approx(x.XT).epsilon(1e-12));
    CHECK(off_axis_strength(c, x, 90 * kDeg) == doctest::Approx(x.YT).epsilon(1e-9));
  }
}

TEST_CASE("off-axis strengths of the E-glass ply by hand") {
  const LaminaStrength x = eglass_strength();
  for (int deg = 0; deg <= 90; deg += 15) {
    CAPTURE(deg);
    const double c = std::cos(deg * kDeg), s = std::sin(deg * kDeg);
    // Max-stress: the least of XT / cos^2, YT / sin^2, S12 / (sin cos).
    double max_stress = x.XT / (c * c);
    if (s > 1e-12) max_stress = std::min(max_stress, x.YT / (s * s));
    if (s * c > 1e-12) max_stress = std::min(max_stress, x.S12 / (s * c));
    CHECK(off_axis_strength(FailureCriterion::kMaxStress, x, deg * kDeg) ==
          doctest::Approx(max_stress).epsilon(1e-12));
    // Tsai-Hill (Jones, Mechanics of Composite Materials, eq. 2.162):
    // 1/sigma^2 = cos^4/X^2 + (1/S^2 - 1/X^2) sin^2 cos^2 + sin^4/Y^2.
    const double X = x.XT, Y = x.YT, S = x.S12;
    const double tsai_hill =
        1.0 / std::sqrt(std::pow(c, 4) / (X * X) + (1 / (S * S) - 1 / (X * X)) * s * s * c * c +
                        std::pow(s, 4) / (Y * Y));
    CHECK(off_axis_strength(FailureCriterion::kTsaiHill, x, deg * kDeg) ==
          doctest::Approx(tsai_hill).epsilon(1e-12));
    // Hashin: fibre tension (c^2/XT)^2 + (sc/S)^2 and matrix tension (s^2/YT)^2 + (sc/S)^2.
    const double fibre = 1 / std::sqrt(std::pow(c * c / X, 2) + std::pow(s * c / S, 2));
    const double matrix = 1 / std::sqrt(std::pow(s * s / Y, 2) + std::pow(s * c / S, 2));
    CHECK(off_axis_strength(FailureCriterion::kHashin, x, deg * kDeg) ==
          doctest::Approx(std::min(fibre, matrix)).epsilon(1e-12));
    // Tsai-Wu: the polynomial at the returned strength is 1.
    const double sigma = off_axis_strength(FailureCriterion::kTsaiWu, x, deg * kDeg);
    const double s1 = sigma * c * c, s2 = sigma * s * s, t = -sigma * s * c;
    const double F11 = 1 / (x.XT * x.XC), F22 = 1 / (x.YT * x.YC);
    const double value = (1 / x.XT - 1 / x.XC) * s1 + (1 / x.YT - 1 / x.YC) * s2 + F11 * s1 * s1 +
                         F22 * s2 * s2 + t * t / (S * S) - std::sqrt(F11 * F22) * s1 * s2;
    CHECK(value == doctest::Approx(1.0).epsilon(1e-12));
  }
  // DAMAGE_NOTES §5: at 30 deg the four range from about 110 MPa (Tsai-Wu) to 160 (max-stress).
  CHECK(off_axis_strength(FailureCriterion::kMaxStress, x, 30 * kDeg) ==
        doctest::Approx(160e6).epsilon(1e-9));  // YT / sin^2(30) = 4 YT
  for (FailureCriterion c : all_criteria()) {
    const double strength = off_axis_strength(c, x, 30 * kDeg);
    CAPTURE(std::string(criterion_name(c)));
    CHECK(strength >= 105e6);
    CHECK(strength <= 160e6 * (1 + 1e-12));
  }
  CHECK(off_axis_strength(FailureCriterion::kTsaiWu, x, 30 * kDeg) ==
        doctest::Approx(110e6).epsilon(0.05));
}

TEST_CASE("compression and combined stresses") {
  const LaminaStrength x = eglass_strength();
  // Tsai-Hill uses XC and YC for compressive sigma1, sigma2: s1 = s2 = -s gives
  // s^2 (1/XC^2 - 1/XC^2 + 1/YC^2) = 1, so s = YC.
  CHECK(failure_load_factor(FailureCriterion::kTsaiHill, {-1, -1, 0}, x) ==
        doctest::Approx(x.YC).epsilon(1e-12));
  // Hashin matrix compression with S23 = YC/2: (s2/YC)^2 + (t/S12)^2 = 1.
  const double hashin = 1 / std::sqrt(std::pow(1 / x.YC, 2) + std::pow(0.5 / x.S12, 2));
  CHECK(failure_load_factor(FailureCriterion::kHashin, {0, -1, 0.5}, x) ==
        doctest::Approx(hashin).epsilon(1e-12));
  // Max-stress takes the mode that fails first.
  CHECK(failure_load_factor(FailureCriterion::kMaxStress, {-1, 0.1, 0}, x) ==
        doctest::Approx(std::min(x.XC, x.YT / 0.1)).epsilon(1e-12));
  // Tsai-Wu under biaxial sigma1 = sigma2 = s: root of a s^2 + b s = 1 by the quadratic formula.
  const double F1 = 1 / x.XT - 1 / x.XC, F2 = 1 / x.YT - 1 / x.YC;
  const double F11 = 1 / (x.XT * x.XC), F22 = 1 / (x.YT * x.YC);
  const double a = F11 + F22 - std::sqrt(F11 * F22), b = F1 + F2;
  const double root = (-b + std::sqrt(b * b + 4 * a)) / (2 * a);
  CHECK(failure_load_factor(FailureCriterion::kTsaiWu, {1, 1, 0}, x) ==
        doctest::Approx(root).epsilon(1e-12));
  // A stress the criterion never reaches: zero.
  for (FailureCriterion c : all_criteria()) {
    CHECK(std::isinf(failure_load_factor(c, {0, 0, 0}, x)));
  }
}

TEST_CASE("a strength the criterion needs and the material lacks is a clear error") {
  LaminaStrength only_xt;
  only_xt.XT = 1e9;
  CHECK(failure_load_factor(FailureCriterion::kMaxStress, {1, 0, 0}, only_xt) ==
        doctest::Approx(1e9));
  CHECK_THROWS_WITH_AS(failure_load_factor(FailureCriterion::kMaxStress, {0, 1, 0}, only_xt),
                       doctest::Contains("YT"), Error);
  CHECK_THROWS_WITH_AS(failure_load_factor(FailureCriterion::kTsaiWu, {1, 0, 0}, only_xt),
                       doctest::Contains("XC"), Error);
  CHECK_THROWS_WITH_AS(failure_load_factor(FailureCriterion::kHashin, {1, 0, 1}, only_xt),
                       doctest::Contains("S12"), Error);
  CHECK_THROWS_WITH_AS(
      failure_load_factor(FailureCriterion::kTsaiHill,
                          {std::numeric_limits<double>::quiet_NaN(), 0, 0}, eglass_strength()),
      doctest::Contains("non-finite stress"), Error);
}

namespace {

// Puck's three-dimensional action-plane criterion (Puck & Schuermann 2002, eqs. (7)-(9)), searched
// over the plane's inclination theta by brute force: the reference for the library's plane-stress
// closed forms of modes A, B and C. A plane at theta to the thickness direction carries
// sigma_n = sigma2 cos^2, tau_nt = -sigma2 sin cos and tau_n1 = tau12 cos; the resistances of the
// action plane are R_perp_perp^A (from YC and p23- by R = YC / (2 (1 + p23-)), p23- = p12- R / S12,
// solved here by fixed-point iteration) and S12, and the inclination parameters are blended by
// cos^2 psi = tau_nt^2 / (tau_nt^2 + tau_n1^2). Returns the largest exposure and its angle.
struct ActionPlane {
  double exposure = 0;
  double angle = 0;
};

ActionPlane puck_action_plane_search(double sigma2, double tau12, const LaminaStrength& x) {
  const double S = x.S12, pt = x.puck_p12_tension, pc = x.puck_p12_compression;
  double R = 0.5 * x.YC;
  for (int i = 0; i < 200; ++i) R = x.YC / (2 * (1 + pc * R / S));
  const double p23 = pc * R / S;
  ActionPlane best;
  auto exposure = [&](double theta) {
    const double c = std::cos(theta), s = std::sin(theta);
    const double sn = sigma2 * c * c, tnt = -sigma2 * s * c, tn1 = tau12 * c;
    const double t2 = tnt * tnt + tn1 * tn1;
    const double cos2psi = t2 > 0 ? tnt * tnt / t2 : 0.0, sin2psi = t2 > 0 ? tn1 * tn1 / t2 : 0.0;
    if (sn >= 0) {
      const double p = p23 / R * cos2psi + pt / S * sin2psi;  // p23+ taken as p23-
      const double a = (1 / x.YT - p) * sn;
      return std::sqrt(a * a + (tnt / R) * (tnt / R) + (tn1 / S) * (tn1 / S)) + p * sn;
    }
    const double p = p23 / R * cos2psi + pc / S * sin2psi;
    return std::sqrt((tnt / R) * (tnt / R) + (tn1 / S) * (tn1 / S) + (p * sn) * (p * sn)) + p * sn;
  };
  // A scan at 0.01 degrees, then golden-section refinement around the best point.
  for (int k = -9000; k <= 9000; ++k) {
    const double theta = k * 0.01 * kDeg;
    const double f = exposure(theta);
    if (f > best.exposure) best = {f, theta};
  }
  double lo = best.angle - 0.01 * kDeg, hi = best.angle + 0.01 * kDeg;
  const double phi = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 100; ++i) {
    const double a = hi - phi * (hi - lo), b = lo + phi * (hi - lo);
    (exposure(a) > exposure(b) ? hi : lo) = exposure(a) > exposure(b) ? b : a;
  }
  const double theta = 0.5 * (lo + hi);
  if (exposure(theta) > best.exposure) best = {exposure(theta), theta};
  return best;
}

}  // namespace

TEST_CASE("Puck's plane-stress modes A, B, C agree with a search of the 3D action plane") {
  // E-glass/MY750 (WWFE-I) and T300/914C-like strengths, with Puck's inclinations for each.
  LaminaStrength glass = eglass_strength();
  LaminaStrength carbon = test::carbon_ply().strength;
  carbon.puck_p12_tension = 0.35;
  carbon.puck_p12_compression = 0.30;
  for (const LaminaStrength& x : {glass, carbon}) {
    for (int k = 0; k < 72; ++k) {
      // Directions all round the (sigma2, tau12) plane, sigma1 = 0 (no fibre failure).
      const double psi = k * 5.0 * kDeg + 0.5 * kDeg;
      const PlyStress unit{0, std::cos(psi), std::sin(psi)};
      CAPTURE(x.YT);
      CAPTURE(psi / kDeg);
      const double factor = failure_load_factor(FailureCriterion::kPuck, unit, x);
      const ActionPlane search = puck_action_plane_search(unit.sigma2, unit.tau12, x);
      CHECK(factor == doctest::Approx(1.0 / search.exposure).epsilon(1e-6));
      const PuckFracturePlane plane = puck_fracture_plane(unit, x);
      CHECK(std::abs(plane.angle - std::abs(search.angle)) < 0.01 * kDeg);
      CHECK((plane.angle > 0) == (plane.mode == PuckMode::kC));
      CHECK((plane.mode == PuckMode::kA) == (unit.sigma2 >= 0));
    }
  }
}

TEST_CASE("Puck's fracture plane in transverse compression is inclined by about 50 degrees") {
  // Pure transverse compression fails in mode C at sigma2 = -YC on a plane whose angle the search
  // finds independently; Puck reports 50-55 degrees for these inclinations (DAMAGE_NOTES §7).
  const LaminaStrength x = eglass_strength();
  const PlyStress compression{0, -1, 0};
  CHECK(failure_load_factor(FailureCriterion::kPuck, compression, x) ==
        doctest::Approx(x.YC).epsilon(1e-12));
  const PuckFracturePlane plane = puck_fracture_plane(compression, x);
  CHECK(plane.mode == PuckMode::kC);
  const ActionPlane search = puck_action_plane_search(-1, 0, x);
  CHECK(plane.angle == doctest::Approx(std::abs(search.angle)).epsilon(1e-4));
  CHECK(plane.angle / kDeg > 49);
  CHECK(plane.angle / kDeg < 56);
  // Transverse tension and in-plane shear break on the plane of the fibres and the thickness.
  CHECK(puck_fracture_plane({0, 1, 0}, x).angle == 0);
  CHECK(puck_fracture_plane({0, -0.1, 1}, x).mode == PuckMode::kB);
  CHECK(puck_fracture_plane({0, 0, 1}, x).angle == 0);
  // Fibre failure: Puck's fibre modes are XT and XC alone.
  CHECK(failure_load_factor(FailureCriterion::kPuck, {1, 0, 0.1}, x) ==
        doctest::Approx(std::min(x.XT, 1.0 / (0.1 / x.S12))).epsilon(1e-12));
}

TEST_CASE("each criterion names the mode that fails: fibre or matrix, tension or compression") {
  const LaminaStrength x = plydem::test::eglass().strength;
  using M = PlyFailureMode;
  for (FailureCriterion c : all_criteria()) {
    CAPTURE(std::string(criterion_name(c)));
    CHECK(ply_failure(c, {1, 0, 0}, x).mode == M::kFibreTension);
    CHECK(ply_failure(c, {-1, 0, 0}, x).mode == M::kFibreCompression);
    CHECK(ply_failure(c, {0, 1, 0}, x).mode == M::kMatrixTension);
    CHECK(ply_failure(c, {0, 0, 1}, x).mode == M::kMatrixTension);
    const PlyFailure crushed = ply_failure(c, {0, -1, 0}, x);
    CHECK(crushed.mode == M::kMatrixCompression);
    // Puck's fracture angle in every criterion's matrix compression (about 50 degrees here).
    CHECK(crushed.fracture_angle == puck_fracture_plane({0, -1, 0}, x).angle);
    CHECK(ply_failure(c, {0, 1, 0}, x).fracture_angle == 0);
    for (const PlyStress& s :
         {PlyStress{1, 0, 0}, PlyStress{0, -1, 0}, PlyStress{0.3, 0.2, -0.4}}) {
      CHECK(ply_failure(c, s, x).load_factor == failure_load_factor(c, s, x));
    }
  }
  // Off-axis tension: max-stress's fibre mode gives way to shear at tan(theta) = S12 / XT (3.3 deg
  // for E-glass/MY750); the interactive Tsai-Wu's fibre part leads only very near 0 deg.
  const double crossover = std::atan(x.S12 / x.XT);
  CHECK(ply_failure(FailureCriterion::kMaxStress, to_ply_axes(1, 0, 0, 0.9 * crossover), x).mode ==
        M::kFibreTension);
  CHECK(ply_failure(FailureCriterion::kMaxStress, to_ply_axes(1, 0, 0, 1.1 * crossover), x).mode ==
        M::kMatrixTension);
  CHECK(ply_failure(FailureCriterion::kTsaiWu, to_ply_axes(1, 0, 0, 0.2 * kDeg), x).mode ==
        M::kFibreTension);
  CHECK(ply_failure(FailureCriterion::kTsaiWu, to_ply_axes(1, 0, 0, 30 * kDeg), x).mode ==
        M::kMatrixTension);
  CHECK(std::string(failure_mode_name(M::kMatrixCompression)) == "matrix compression");
  // The load factor needs only the strengths its criterion uses: max-stress in transverse
  // compression reads YC, without S12 (which Puck's fracture angle of ply_failure also needs).
  LaminaStrength no_shear = x;
  no_shear.S12 = 0;
  CHECK(failure_load_factor(FailureCriterion::kMaxStress, {0, -1, 0}, no_shear) == x.YC);
  CHECK_THROWS_AS(ply_failure(FailureCriterion::kMaxStress, {0, -1, 0}, no_shear), Error);
}
