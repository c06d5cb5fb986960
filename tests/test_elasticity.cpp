// Elasticity of a ply and a laminate, and the material it starts from.
//
// Every reference here is independent of the code under test: the ERRATA §1 table (recomputed
// outside plydem), textbook closed forms for off-axis engineering constants (Jones, "Mechanics of
// Composite Materials", eqs. 2.97-2.98 and 2.88), and the paper's eqs. (23), (29), (32) written out
// term by term below. Nothing is compared against a value the implementation itself produced.

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/material.hpp"

namespace {

using plydem::Material;

constexpr double kPi = std::numbers::pi;
double degrees(double angle_deg) {
  return angle_deg * kPi / 180.0;
}

// Paper Table 1 as printed (with ERRATA §2: the fifth constant is nu12 = nu13). Written out here
// rather than taken from load_material so the built-in itself is under test.
Material eglass() {
  Material m;
  m.name = "eglass-test";
  m.E1 = 45.6e9;
  m.E2 = 16.2e9;
  m.G12 = 5.83e9;
  m.nu12 = 0.278;
  m.nu23 = 0.4;
  return m;
}

bool close_relative(double value, double reference, double tolerance) {
  return std::abs(value - reference) <= tolerance * std::abs(reference);
}

// The message of the plydem::Error `f` throws; fails the test (and returns "") if it throws
// nothing or something else. doctest 2.4.9 has no substring matcher for CHECK_THROWS_WITH.
template <typename F>
std::string error_message(F&& f) {
  try {
    f();
  } catch (const plydem::Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    FAIL("threw a non-plydem exception: " << e.what());
    return "";
  }
  FAIL("did not throw");
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Off-axis constants from the lamina's engineering constants alone (Jones eqs. 2.97-2.98): no
// matrix inversion, no rotation matrices, nothing shared with core/elasticity.cpp.
struct ClosedForm {
  double Ex, Ey, nu_xy, nu_yx, Gxy, shear_coupling_x;
};

ClosedForm off_axis_closed_form(const Material& m, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  const double c2 = c * c, s2 = s * s, c4 = c2 * c2, s4 = s2 * s2;
  ClosedForm k;
  k.Ex = 1.0 / (c4 / m.E1 + (1.0 / m.G12 - 2.0 * m.nu12 / m.E1) * s2 * c2 + s4 / m.E2);
  k.Ey = 1.0 / (s4 / m.E1 + (1.0 / m.G12 - 2.0 * m.nu12 / m.E1) * s2 * c2 + c4 / m.E2);
  const double minus_s12 =
      m.nu12 / m.E1 * (s4 + c4) - (1.0 / m.E1 + 1.0 / m.E2 - 1.0 / m.G12) * s2 * c2;
  k.nu_xy = k.Ex * minus_s12;
  k.nu_yx = k.Ey * minus_s12;
  k.Gxy = 1.0 / (2.0 * (2.0 / m.E1 + 2.0 / m.E2 + 4.0 * m.nu12 / m.E1 - 1.0 / m.G12) * s2 * c2 +
                 (s4 + c4) / m.G12);
  // Jones eq. 2.88, S-bar16 = (2 S11 - 2 S12 - S66) s c^3 - (2 S22 - 2 S12 - S66) s^3 c.
  const double s16 = (2.0 / m.E1 + 2.0 * m.nu12 / m.E1 - 1.0 / m.G12) * s * c2 * c -
                     (2.0 / m.E2 + 2.0 * m.nu12 / m.E1 - 1.0 / m.G12) * s2 * s * c;
  k.shear_coupling_x = s16 * k.Ex;
  return k;
}

// "0", "[0/90/0]", "[0/30/45]s" -> ply angles in degrees; "s" mirrors the listed half.
std::vector<double> parse_layup(const std::string& text) {
  std::string body = text;
  bool symmetric = false;
  if (!body.empty() && body.back() == 's') {
    symmetric = true;
    body.pop_back();
  }
  if (body.size() >= 2 && body.front() == '[' && body.back() == ']') {
    body = body.substr(1, body.size() - 2);
  }
  std::vector<double> angles;
  std::stringstream stream(body);
  std::string item;
  while (std::getline(stream, item, '/')) angles.push_back(std::stod(item));
  if (symmetric) angles.insert(angles.end(), angles.rbegin(), angles.rend());
  return angles;
}

std::vector<plydem::Ply> equal_thickness_layup(const Material& m, const std::vector<double>& deg,
                                               double thickness = 0.125e-3) {
  std::vector<plydem::Ply> plies;
  for (double angle : deg) plies.push_back({m, degrees(angle), thickness});
  return plies;
}

// A file in the temp directory that removes itself; the random suffix keeps parallel ctest runs
// from trampling each other.
class TempFile {
 public:
  TempFile(const std::string& stem, const std::string& contents) {
    std::random_device random;
    path_ = std::filesystem::temp_directory_path() /
            ("plydem_" + stem + "_" + std::to_string(random()) + ".toml");
    std::ofstream(path_) << contents;
  }
  ~TempFile() {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace

TEST_CASE("in-plane constants reproduce the ERRATA §1 table to its printed digits") {
  std::ifstream file(std::string(PLYDEM_TEST_DATA_DIR) + "/errata_in_plane_constants.csv");
  REQUIRE(file.good());
  std::string line;
  std::getline(file, line);
  REQUIRE(line == "case,Ex_GPa,Ey_GPa,nu_xy,nu_yx,Gxy_GPa");

  int rows = 0;
  while (std::getline(file, line)) {
    if (line.empty()) continue;
    std::stringstream row(line);
    std::string name, field;
    std::getline(row, name, ',');
    std::vector<double> expected;
    while (std::getline(row, field, ',')) expected.push_back(std::stod(field));
    REQUIRE(expected.size() == 5);
    CAPTURE(name);

    // A bare angle is a single ply; the bracketed layups are equal-thickness laminates.
    const auto angles = parse_layup(name);
    const plydem::InPlaneConstants k =
        name.front() == '[' ? plydem::laminate_constants(equal_thickness_layup(eglass(), angles))
                            : plydem::in_plane_constants(plydem::rotate_reduced_stiffness(
                                  plydem::reduced_stiffness(eglass()), degrees(angles.at(0))));

    // Moduli printed to 1e-3 GPa (relative <= 5e-5 at 10 GPa), ratios to 1e-4.
    CHECK(close_relative(k.Ex / 1e9, expected[0], 2e-4));
    CHECK(close_relative(k.Ey / 1e9, expected[1], 2e-4));
    CHECK(std::abs(k.nu_xy - expected[2]) <= 1e-4);
    CHECK(std::abs(k.nu_yx - expected[3]) <= 1e-4);
    CHECK(close_relative(k.Gxy / 1e9, expected[4], 2e-4));
    ++rows;
  }
  CHECK(rows == 9);
}

TEST_CASE("off-axis constants equal the textbook closed forms at many angles") {
  const Material m = eglass();
  const Eigen::Matrix3d Q = plydem::reduced_stiffness(m);
  // Irregular steps so no angle is special, plus the special ones, and both signs.
  std::vector<double> angles_deg;
  for (double a = -180.0; a <= 180.0; a += 3.7) angles_deg.push_back(a);
  for (double a : {0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0, -45.0, 135.0}) angles_deg.push_back(a);

  for (double angle_deg : angles_deg) {
    CAPTURE(angle_deg);
    const auto k =
        plydem::in_plane_constants(plydem::rotate_reduced_stiffness(Q, degrees(angle_deg)));
    const ClosedForm ref = off_axis_closed_form(m, degrees(angle_deg));
    CHECK(close_relative(k.Ex, ref.Ex, 1e-10));
    CHECK(close_relative(k.Ey, ref.Ey, 1e-10));
    CHECK(close_relative(k.nu_xy, ref.nu_xy, 1e-10));
    CHECK(close_relative(k.nu_yx, ref.nu_yx, 1e-10));
    CHECK(close_relative(k.Gxy, ref.Gxy, 1e-10));
    // Dimensionless and zero at 0 and 90 degrees: an absolute tolerance.
    CHECK(std::abs(k.shear_coupling_x - ref.shear_coupling_x) <= 1e-10);
  }
}

TEST_CASE("off-axis shear coupling has the sign of a fibre rotated counter-clockwise") {
  // Pulling along x a ply whose fibre sits at +30 deg: the stretch favours the compliant direction
  // normal to the fibre (120 deg), so the diagonal x = -y lengthens more than x = y and the right
  // angle between x and y opens: gamma_xy < 0 (Jones's sign convention). At -30 deg the mirror.
  const Eigen::Matrix3d Q = plydem::reduced_stiffness(eglass());
  const auto plus = plydem::in_plane_constants(plydem::rotate_reduced_stiffness(Q, degrees(30)));
  const auto minus = plydem::in_plane_constants(plydem::rotate_reduced_stiffness(Q, degrees(-30)));
  CHECK(plus.shear_coupling_x < 0);
  CHECK(minus.shear_coupling_x == doctest::Approx(-plus.shear_coupling_x).epsilon(1e-12));
}

TEST_CASE("reduced stiffness Q equals eq. (29)") {
  const Material m = eglass();
  const double nu21 = m.nu12 * m.E2 / m.E1;
  const double d = 1.0 - m.nu12 * nu21;
  Eigen::Matrix3d eq29;
  eq29 << m.E1 / d, m.nu12 * m.E2 / d, 0.0,  //
      m.nu12 * m.E2 / d, m.E2 / d, 0.0,      //
      0.0, 0.0, m.G12;

  const Eigen::Matrix3d Q = plydem::reduced_stiffness(m);
  CHECK((Q - eq29).cwiseAbs().maxCoeff() <= 1e-12 * eq29.cwiseAbs().maxCoeff());
  CHECK(m.nu21() == doctest::Approx(0.098763).epsilon(1e-5));  // ERRATA §1's quoted nu21
}

TEST_CASE("Q-bar equals eq. (32) written out term by term") {
  const Eigen::Matrix3d Q = plydem::reduced_stiffness(eglass());
  const double C11 = Q(0, 0), C12 = Q(0, 1), C22 = Q(1, 1), C66 = Q(2, 2);
  for (double angle_deg = -90.0; angle_deg <= 90.0; angle_deg += 7.5) {
    CAPTURE(angle_deg);
    const double c = std::cos(degrees(angle_deg)), s = std::sin(degrees(angle_deg));
    const double c2 = c * c, s2 = s * s, c4 = c2 * c2, s4 = s2 * s2;
    const double b11 = C11 * c4 + 2 * (C12 + 2 * C66) * s2 * c2 + C22 * s4;
    const double b22 = C11 * s4 + 2 * (C12 + 2 * C66) * s2 * c2 + C22 * c4;
    const double b12 = (C11 + C22 - 4 * C66) * s2 * c2 + C12 * (s4 + c4);
    const double b16 = (C11 - C12 - 2 * C66) * s * c2 * c + (C12 - C22 + 2 * C66) * s2 * s * c;
    const double b26 = (C11 - C12 - 2 * C66) * s2 * s * c + (C12 - C22 + 2 * C66) * s * c2 * c;
    const double b66 = (C11 + C22 - 2 * C12 - 2 * C66) * s2 * c2 + C66 * (s4 + c4);
    Eigen::Matrix3d eq32;
    eq32 << b11, b12, b16,  //
        b12, b22, b26,      //
        b16, b26, b66;
    const Eigen::Matrix3d Qbar = plydem::rotate_reduced_stiffness(Q, degrees(angle_deg));
    CHECK((Qbar - eq32).cwiseAbs().maxCoeff() <= 1e-12 * C11);
  }
}

TEST_CASE("3D stiffness equals eq. (23) with its C44 and restored C55 rows") {
  const Material m = eglass();
  const double r = m.nu12 * m.nu12 * m.E2 / m.E1;  // nu12^2 E2/E1
  const double delta = 1.0 - m.nu23 - 2.0 * r;     // eq. (23)'s delta
  plydem::Matrix6d eq23 = plydem::Matrix6d::Zero();
  eq23(0, 0) = (1.0 - m.nu23) / delta * m.E1;
  eq23(0, 1) = eq23(1, 0) = m.nu12 / delta * m.E2;
  eq23(0, 2) = eq23(2, 0) = m.nu12 / delta * m.E2;
  eq23(1, 1) = (1.0 - r) / ((1.0 + m.nu23) * delta) * m.E2;
  eq23(2, 2) = eq23(1, 1);
  eq23(1, 2) = eq23(2, 1) = (m.nu23 + r) / ((1.0 + m.nu23) * delta) * m.E2;
  eq23(3, 3) = m.E2 / (2.0 * (1.0 + m.nu23));  // C44 = G23
  eq23(4, 4) = m.G12;                          // C55 = G13 = G12: the row eq. (23) drops
  eq23(5, 5) = m.G12;                          // C66 = G12

  const plydem::Matrix6d C = plydem::stiffness_3d(m);
  CHECK((C - eq23).cwiseAbs().maxCoeff() <= 1e-12 * eq23.cwiseAbs().maxCoeff());
  CHECK(C(4, 4) == doctest::Approx(5.83e9).epsilon(1e-12));
  CHECK(C(3, 3) == doctest::Approx(16.2e9 / 2.8).epsilon(1e-12));
}

TEST_CASE("plane-stress condensation of the 3D stiffness gives Q") {
  // Q = C_pp - C_pz C_zz^-1 C_zp with p = (11, 22, 12), z = (33, 23, 13): an independent route
  // from the 3D stiffness to the reduced stiffness (the code inverts the compliance block).
  const plydem::Matrix6d C = plydem::stiffness_3d(eglass());
  const int p[3] = {0, 1, 5}, z[3] = {2, 3, 4};
  Eigen::Matrix3d Cpp, Cpz, Czz;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Cpp(i, j) = C(p[i], p[j]);
      Cpz(i, j) = C(p[i], z[j]);
      Czz(i, j) = C(z[i], z[j]);
    }
  }
  const Eigen::Matrix3d condensed = Cpp - Cpz * Czz.inverse() * Cpz.transpose();
  const Eigen::Matrix3d Q = plydem::reduced_stiffness(eglass());
  CHECK((condensed - Q).cwiseAbs().maxCoeff() <= 1e-10 * Q.cwiseAbs().maxCoeff());
}

TEST_CASE("compliance_3d holds the engineering constants") {
  const Material m = eglass();
  const plydem::Matrix6d S = plydem::compliance_3d(m);
  CHECK(1.0 / S(0, 0) == doctest::Approx(m.E1));
  CHECK(1.0 / S(2, 2) == doctest::Approx(m.E2));         // E3 = E2
  CHECK(-S(0, 2) / S(0, 0) == doctest::Approx(m.nu12));  // nu13 = nu12 (ERRATA §2)
  CHECK(-S(1, 2) / S(1, 1) == doctest::Approx(m.nu23));
  CHECK(1.0 / S(3, 3) == doctest::Approx(16.2e9 / 2.8));  // G23 = E2 / (2 (1 + nu23))
  CHECK(1.0 / S(4, 4) == doctest::Approx(m.G12));         // G13 = G12
  CHECK((S - S.transpose()).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("reciprocity nu_yx Ex = nu_xy Ey holds for plies and laminates") {
  const Material m = eglass();
  const Eigen::Matrix3d Q = plydem::reduced_stiffness(m);
  for (double angle_deg = -90.0; angle_deg <= 90.0; angle_deg += 11.0) {
    CAPTURE(angle_deg);
    const auto k =
        plydem::in_plane_constants(plydem::rotate_reduced_stiffness(Q, degrees(angle_deg)));
    CHECK(close_relative(k.nu_yx * k.Ex, k.nu_xy * k.Ey, 1e-12));
  }
  for (const char* layup : {"[0/90/0]", "[0/30/45]s", "[15/-40/70/5]"}) {
    CAPTURE(layup);
    const auto k = plydem::laminate_constants(equal_thickness_layup(m, parse_layup(layup)));
    CHECK(close_relative(k.nu_yx * k.Ex, k.nu_xy * k.Ey, 1e-12));
  }
}

TEST_CASE("laminate stiffness is the thickness-weighted sum of the plies' Q-bar") {
  const Material m = eglass();
  const Eigen::Matrix3d Q = plydem::reduced_stiffness(m);
  SUBCASE("one ply is the ply") {
    const auto lam = plydem::laminate_constants({{m, degrees(30), 1e-3}});
    const ClosedForm ref = off_axis_closed_form(m, degrees(30));
    CHECK(close_relative(lam.Ex, ref.Ex, 1e-10));
    CHECK(close_relative(lam.Gxy, ref.Gxy, 1e-10));
  }
  SUBCASE("A is in N/m and scales with thickness; A/h does not") {
    const double t = 0.2e-3;
    const auto thin = equal_thickness_layup(m, {0, 90, 0}, t);
    const auto thick = equal_thickness_layup(m, {0, 90, 0}, 10 * t);
    const Eigen::Matrix3d A = plydem::laminate_extensional_stiffness(thin);
    CHECK(close_relative(A(0, 0), (2 * Q(0, 0) + Q(1, 1)) * t, 1e-12));
    CHECK(close_relative(A(1, 1), (Q(0, 0) + 2 * Q(1, 1)) * t, 1e-12));
    CHECK(close_relative(A(0, 1), 3 * Q(0, 1) * t, 1e-12));
    CHECK(close_relative(plydem::laminate_constants(thick).Ex, plydem::laminate_constants(thin).Ex,
                         1e-12));
  }
  SUBCASE("unequal thicknesses weight the plies") {
    // A 0 ply twice as thick as a 90 ply: Ex from A/h = (2 Q0 + Q90)/3, same as [0/90/0].
    const auto k = plydem::laminate_constants({{m, 0.0, 2e-3}, {m, degrees(90), 1e-3}});
    CHECK(close_relative(k.Ex / 1e9, 36.009, 2e-4));  // ERRATA §1, [0/90/0]
  }
  SUBCASE("a balanced angle-ply does not shear under sigma_x") {
    const auto k = plydem::laminate_constants(equal_thickness_layup(m, {30, -30, -30, 30}));
    CHECK(std::abs(k.shear_coupling_x) <= 1e-12);
  }
  SUBCASE("[0/30/45]s does (ERRATA §1)") {
    const auto k = plydem::laminate_constants(equal_thickness_layup(m, parse_layup("[0/30/45]s")));
    CHECK(std::abs(k.shear_coupling_x) > 0.1);
  }
}

TEST_CASE("laminate input errors") {
  const Material m = eglass();
  CHECK(contains(error_message([] { plydem::laminate_constants({}); }), "no plies"));
  CHECK_THROWS_AS(plydem::laminate_extensional_stiffness({}), plydem::Error);
  for (double bad : {0.0, -1e-3, std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity()}) {
    CAPTURE(bad);
    const std::vector<plydem::Ply> plies = {{m, 0.0, 1e-3}, {m, 0.5, bad}};
    const std::string message = error_message([&] { plydem::laminate_constants(plies); });
    CHECK(contains(message, "ply 1"));
    CHECK(contains(message, "thickness"));
  }
  Material bad = m;
  bad.G12 = 0;
  CHECK_THROWS_AS(plydem::laminate_constants({{bad, 0.0, 1e-3}}), plydem::Error);
}

TEST_CASE("in_plane_constants rejects a stiffness that is not positive definite") {
  Eigen::Matrix3d indefinite;
  indefinite << 1, 2, 0,  //
      2, 1, 0,            //
      0, 0, 1;
  CHECK(contains(error_message([&] { plydem::in_plane_constants(indefinite); }),
                 "positive definite"));
  CHECK_THROWS_AS(plydem::in_plane_constants(Eigen::Matrix3d::Zero()), plydem::Error);
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(plydem::in_plane_constants(nan), plydem::Error);
}

TEST_CASE("is_positive_definite") {
  CHECK(plydem::is_positive_definite(Eigen::MatrixXd::Identity(4, 4)));
  Eigen::MatrixXd semidefinite(2, 2);
  semidefinite << 1, 1, 1, 1;
  CHECK_FALSE(plydem::is_positive_definite(semidefinite));
  CHECK_FALSE(plydem::is_positive_definite(-Eigen::MatrixXd::Identity(3, 3)));
  CHECK_FALSE(plydem::is_positive_definite(Eigen::MatrixXd::Identity(2, 3)));
  CHECK_FALSE(plydem::is_positive_definite(Eigen::MatrixXd(0, 0)));
  Eigen::MatrixXd nonsymmetric(2, 2);
  nonsymmetric << 2, 1, -1, 2;  // x^T M x > 0, but not symmetric: no energy form
  CHECK_FALSE(plydem::is_positive_definite(nonsymmetric));
}

TEST_CASE("validate rejects constants no elastic solid has") {
  SUBCASE("nu12 = 0.9 with E1 = E2 is not positive definite") {
    // nu12^2 < E1/E2 (1 - nu23)/2 = 0.3 is needed, i.e. |nu12| < 0.548.
    Material m = eglass();
    m.name = "bad-ply";
    m.E1 = 16.2e9;
    m.nu12 = 0.9;
    const std::string message = error_message([&] { plydem::validate(m); });
    CHECK(contains(message, "material 'bad-ply'"));
    CHECK(contains(message, "positive definite"));
    CHECK(contains(message, "nu12"));
    CHECK_THROWS_AS(plydem::stiffness_3d(m), plydem::Error);
    CHECK_THROWS_AS(plydem::reduced_stiffness(m), plydem::Error);
  }
  SUBCASE("nu12 = 0.9 with E-glass's other constants is (barely) admissible") {
    // A fact worth knowing: E1/E2 (1 - nu23)/2 = 45.6/16.2 * 0.3 = 0.8444, |nu12| < 0.9189. So a
    // plausibility check on nu12 alone would not catch the E1 = E2 case above, and the PD test
    // must see all the constants together.
    Material m = eglass();
    m.nu12 = 0.9;
    CHECK_NOTHROW(plydem::validate(m));
    m.nu12 = 0.92;
    CHECK(contains(error_message([&] { plydem::validate(m); }), "positive definite"));
    m.nu12 = -0.92;  // the bound is on nu12^2
    CHECK_THROWS_AS(plydem::validate(m), plydem::Error);
  }
  SUBCASE("nu23 outside (-1, 1)") {
    for (double nu23 : {1.0, 1.5, -1.0, -1.5}) {
      CAPTURE(nu23);
      Material m = eglass();
      m.nu23 = nu23;
      const std::string message = error_message([&] { plydem::validate(m); });
      CHECK(contains(message, "positive definite"));
      CHECK(contains(message, "nu23"));
    }
  }
  SUBCASE("non-finite or non-positive constants") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    struct Case {
      const char* key;
      double Material::*field;
      double value;
    };
    for (const Case& c : {Case{"E1", &Material::E1, nan}, Case{"E2", &Material::E2, -16.2e9},
                          Case{"G12", &Material::G12, 0.0}, Case{"E1", &Material::E1, inf},
                          Case{"nu12", &Material::nu12, nan}, Case{"nu23", &Material::nu23, inf},
                          Case{"density", &Material::density, 0.0}}) {
      CAPTURE(c.key);
      CAPTURE(c.value);
      Material m = eglass();
      m.*c.field = c.value;
      const std::string message = error_message([&] { plydem::validate(m); });
      CHECK(contains(message, "material 'eglass-test'"));
      CHECK(contains(message, std::string(c.key) + " must be finite"));
    }
  }
  SUBCASE("negative Poisson's ratios inside the bounds are fine") {
    Material m = eglass();
    m.nu12 = -0.2;
    m.nu23 = -0.5;
    CHECK_NOTHROW(plydem::validate(m));
  }
}

TEST_CASE("built-in carbon plies are WWFE-I's T300/914C and AS4/3501-6") {
  const Material t300 = plydem::load_material("t300-914c");
  CHECK(t300.E1 == 138e9);
  CHECK(t300.E2 == 11e9);
  CHECK(t300.G12 == 5.5e9);
  CHECK(t300.strength.YT == 27e6);
  const Material as4 = plydem::load_material("as4-3501-6");
  CHECK(as4.E1 == 126e9);
  CHECK(as4.G12 == 6.6e9);
  CHECK(as4.strength.XT == 1950e6);
  // Both are stiff-fibre plies: E1/E2 above 11, G12 near E2/2.
  CHECK(t300.E1 / t300.E2 > 11);
  CHECK(as4.G12 / as4.E2 == doctest::Approx(0.6));
}

TEST_CASE("built-in material eglass-my750 is paper Table 1") {
  const auto names = plydem::builtin_material_names();
  REQUIRE(names.size() == 3);
  CHECK(names[0] == "eglass-my750");
  const Material m = plydem::load_material("eglass-my750");
  CHECK(m.name == "eglass-my750");
  CHECK(m.E1 == 45.6e9);
  CHECK(m.E2 == 16.2e9);
  CHECK(m.G12 == 5.83e9);
  CHECK(m.nu12 == 0.278);
  CHECK(m.nu23 == 0.4);
  CHECK(m.density == 2000.0);
  // WWFE-I (Soden, Hinton & Kaddour 1998; DAMAGE_NOTES §1).
  CHECK(m.strength.XT == 1280e6);
  CHECK(m.strength.XC == 800e6);
  CHECK(m.strength.YT == 40e6);
  CHECK(m.strength.YC == 145e6);
  CHECK(m.strength.S12 == 73e6);
  CHECK(m.strength.tensile_and_shear());
  CHECK_FALSE(m.strength.fracture_energies());
  CHECK_NOTHROW(plydem::require_strengths(m, "a test"));
  CHECK(contains(error_message([&] { plydem::require_strengths(m, "softening", true); }),
                 "has no G_fibre, G_matrix: softening needs them"));
}

TEST_CASE("material files with strengths") {
  const std::string elastic =
      "name = \"g\"\nE1 = 45.6e9\nE2 = 16.2e9\nG12 = 5.83e9\nnu12 = 0.278\nnu23 = 0.4\n";
  SUBCASE("strengths, fracture energies and scatter are read in SI units") {
    TempFile file("strengths", elastic +
                                   "XT = 1280e6\nXC = 800e6\nYT = 40e6\nYC = 145e6\nS12 = 73e6\n"
                                   "G_fibre = 40000\nG_matrix = 250\nweibull_modulus = 12\n");
    const Material m = plydem::load_material(file.path());
    CHECK(m.strength.XT == 1280e6);
    CHECK(m.strength.XC == 800e6);
    CHECK(m.strength.YT == 40e6);
    CHECK(m.strength.YC == 145e6);
    CHECK(m.strength.S12 == 73e6);
    CHECK(m.strength.G_fibre == 40000);
    CHECK(m.strength.G_matrix == 250);
    CHECK(m.strength.weibull_modulus == 12);
    CHECK(m.strength.fracture_energies());
  }
  SUBCASE("no strengths: elastic work is fine, a test to failure names what is missing") {
    TempFile file("no_strengths", elastic + "XT = 1280e6\n");
    const Material m = plydem::load_material(file.path());
    CHECK_FALSE(m.strength.tensile_and_shear());
    CHECK(contains(error_message([&] { plydem::require_strengths(m, "plydem strength"); }),
                   "material 'g' has no YT, S12: plydem strength needs them"));
  }
  SUBCASE("a negative, zero or NaN strength is an error naming the key") {
    for (const std::string bad : {"YT = -40e6\n", "S12 = 0\n", "XT = nan\n", "G_matrix = -1\n"}) {
      CAPTURE(bad);
      TempFile file("bad_strength", elastic + bad);
      const std::string message = error_message([&] { plydem::load_material(file.path()); });
      CHECK(contains(message, bad.substr(0, bad.find(' ')) + " must be finite and positive"));
      CHECK(contains(message, file.path()));
    }
  }
  SUBCASE("validate() checks strengths set in code") {
    Material m = plydem::load_material("eglass-my750");
    m.strength.YT = std::nan("");
    CHECK(contains(error_message([&] { plydem::validate(m); }), "YT must be finite"));
  }
}

TEST_CASE("material TOML files") {
  SUBCASE("a valid file; integers are numbers too; density optional") {
    TempFile file("valid",
                  "# E-glass with rounder numbers\n"
                  "name = \"my-glass\"\n"
                  "E1 = 45600000000\n"
                  "E2 = 16.2e9\n"
                  "G12 = 5.83e9\n"
                  "nu12 = 0.278\n"
                  "nu23 = 0.4\n"
                  "density = 2550\n");
    const Material m = plydem::load_material(file.path());
    CHECK(m.name == "my-glass");
    CHECK(m.E1 == 45.6e9);
    CHECK(m.E2 == 16.2e9);
    CHECK(m.G12 == 5.83e9);
    CHECK(m.nu12 == 0.278);
    CHECK(m.nu23 == 0.4);
    CHECK(m.density == 2550.0);

    TempFile no_density("no_density",
                        "name = \"g\"\nE1 = 45.6e9\nE2 = 16.2e9\nG12 = 5.83e9\n"
                        "nu12 = 0.278\nnu23 = 0.4\n");
    CHECK(plydem::load_material(no_density.path()).density == 2000.0);
  }
  SUBCASE("a missing key names the key and the file") {
    TempFile file("missing", "name = \"g\"\nE1 = 45.6e9\nE2 = 16.2e9\nnu12 = 0.278\nnu23 = 0.4\n");
    const std::string message = error_message([&] { plydem::load_material(file.path()); });
    CHECK(contains(message, "missing key 'G12'"));
    CHECK(contains(message, file.path()));
  }
  SUBCASE("a key of the wrong type") {
    TempFile file("wrong_type",
                  "name = \"g\"\nE1 = \"abc\"\nE2 = 16.2e9\nG12 = 5.83e9\n"
                  "nu12 = 0.278\nnu23 = 0.4\n");
    const std::string message = error_message([&] { plydem::load_material(file.path()); });
    CHECK(contains(message, "'E1'"));
    CHECK(contains(message, "must be a number"));
    TempFile name_type("name_type",
                       "name = 3\nE1 = 45.6e9\nE2 = 16.2e9\nG12 = 5.83e9\n"
                       "nu12 = 0.278\nnu23 = 0.4\n");
    CHECK(contains(error_message([&] { plydem::load_material(name_type.path()); }),
                   "'name' must be a string"));
  }
  SUBCASE("an unknown key catches a typo") {
    TempFile file("unknown_key",
                  "name = \"g\"\nE1 = 45.6e9\nE2 = 16.2e9\nG12 = 5.83e9\n"
                  "nu21 = 0.278\nnu23 = 0.4\n");
    const std::string message = error_message([&] { plydem::load_material(file.path()); });
    CHECK(contains(message, "unknown key 'nu21'"));
  }
  SUBCASE("a TOML syntax error gives file, line and toml++'s description") {
    TempFile file("syntax", "name = \"g\"\nE1 = 45.6e9\nE2 = = 16.2e9\n");
    const std::string message = error_message([&] { plydem::load_material(file.path()); });
    CHECK(contains(message, file.path()));
    CHECK(contains(message, "line 3"));
    CHECK(contains(message, "syntax error"));
  }
  SUBCASE("a file with inadmissible constants is validated") {
    TempFile file("not_pd",
                  "name = \"bad\"\nE1 = 16.2e9\nE2 = 16.2e9\nG12 = 5.83e9\n"
                  "nu12 = 0.9\nnu23 = 0.4\n");
    const std::string message = error_message([&] { plydem::load_material(file.path()); });
    CHECK(contains(message, file.path()));
    CHECK(contains(message, "material 'bad'"));
    CHECK(contains(message, "positive definite"));
    TempFile nan_file("nan",
                      "name = \"bad\"\nE1 = nan\nE2 = 16.2e9\nG12 = 5.83e9\n"
                      "nu12 = 0.278\nnu23 = 0.4\n");
    CHECK(contains(error_message([&] { plydem::load_material(nan_file.path()); }),
                   "E1 must be finite"));
  }
  SUBCASE("neither a built-in nor a file") {
    CHECK_THROWS_WITH_AS(plydem::load_material("xyz"),
                         "unknown material 'xyz': not a built-in (eglass-my750, t300-914c, "
                         "as4-3501-6) and no such file",
                         plydem::Error);
  }
}
