#pragma once
// What several test files share: the hand-written classical lamination theory they check the
// library against, a fresh scratch folder, and the way a case says it skipped for want of an
// external tool (ccx, gnuplot, python3 with VTK).
//
// The CLT here is written out from the engineering constants (paper eqs. 29 and 32; Jones,
// Mechanics of Composite Materials, eqs. 2.84 and 4.28) and must stay independent of
// core/elasticity.cpp: it is what the library's own CLT is checked against, so it includes no
// plydem header but the Material struct.
#include <doctest/doctest.h>
#include <fmt/format.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "core/material.hpp"

namespace plydem::test {

inline constexpr double kDeg = std::numbers::pi / 180.0;

/// A ply the random lattice can reach (E1 20, E2 15, G12 6.5 GPa, nu12 = nu23 = 0.25): E-glass's
/// G12 is out of its reach.
inline Material mild_ply() {
  Material mild;
  mild.name = "mild";
  mild.E1 = 20e9;
  mild.E2 = 15e9;
  mild.G12 = 6.5e9;
  mild.nu12 = 0.25;
  mild.nu23 = 0.25;
  return mild;
}

inline Material eglass() {
  return load_material("eglass-my750");
}

/// The built-in T300/914C carbon/epoxy ply (WWFE-I: E1 138, E2 11, G12 5.5 GPa, nu12 0.28, nu23
/// 0.4; XT 1500, YT 27, S12 80 MPa; XC 900, YC 200 MPa): a strongly orthotropic ply for the
/// strength tests, far from E-glass in XT / YT and S12 / YT.
inline Material carbon_ply() {
  return load_material("t300-914c");
}

// Plane-stress Q-bar of a transversely isotropic ply whose fibre is turned `theta`
// counter-clockwise from x: Q from E1, E2, nu12, G12 (eq. 29), turned by eq. (32) written out.
inline Eigen::Matrix3d qbar_by_hand(const Material& m, double theta) {
  const double nu21 = m.nu12 * m.E2 / m.E1, den = 1 - m.nu12 * nu21;
  const double q11 = m.E1 / den, q22 = m.E2 / den, q12 = m.nu12 * m.E2 / den, q66 = m.G12;
  const double c = std::cos(theta), s = std::sin(theta);
  const double c2 = c * c, s2 = s * s;
  Eigen::Matrix3d q;
  q(0, 0) = q11 * c2 * c2 + 2 * (q12 + 2 * q66) * s2 * c2 + q22 * s2 * s2;
  q(1, 1) = q11 * s2 * s2 + 2 * (q12 + 2 * q66) * s2 * c2 + q22 * c2 * c2;
  q(0, 1) = (q11 + q22 - 4 * q66) * s2 * c2 + q12 * (s2 * s2 + c2 * c2);
  q(0, 2) = (q11 - q12 - 2 * q66) * s * c2 * c + (q12 - q22 + 2 * q66) * s2 * s * c;
  q(1, 2) = (q11 - q12 - 2 * q66) * s2 * s * c + (q12 - q22 + 2 * q66) * s * c2 * c;
  q(2, 2) = (q11 + q22 - 2 * q12 - 2 * q66) * s2 * c2 + q66 * (s2 * s2 + c2 * c2);
  q(1, 0) = q(0, 1);
  q(2, 0) = q(0, 2);
  q(2, 1) = q(1, 2);
  return q;
}

// A/h of a symmetric laminate of equal-thickness plies of one material, angles in degrees: the
// mean Q-bar (B = 0 for a symmetric stack, so the membrane response is A alone).
inline Eigen::Matrix3d membrane_by_hand(const Material& m, const std::vector<double>& degrees) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  for (double deg : degrees) a += qbar_by_hand(m, deg * kDeg);
  return a / static_cast<double>(degrees.size());
}

// In-plane engineering constants of a membrane stiffness (a ply's Q-bar or a laminate's A/h),
// from its compliance a = stiffness^-1: Ex = 1/a11, Ey = 1/a22, nu_xy = -a12/a11,
// nu_yx = -a12/a22, Gxy = 1/a66, and the shear coupling gamma_xy/eps_x under sigma_x = a16/a11.
struct ConstantsByHand {
  double Ex, Ey, nu_xy, nu_yx, Gxy, shear_coupling_x;
};
inline ConstantsByHand constants_by_hand(const Eigen::Matrix3d& stiffness) {
  const Eigen::Matrix3d a = stiffness.inverse();
  return {1 / a(0, 0),        1 / a(1, 1), -a(0, 1) / a(0, 0),
          -a(0, 1) / a(1, 1), 1 / a(2, 2), a(0, 2) / a(0, 0)};
}

// An empty folder under the system's temporary directory, named for the test and the process.
inline std::filesystem::path fresh_directory(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / fmt::format("plydem_{}_{}", name, ::getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Cases that need an external tool call skip(why) when it is missing and return: the message is
// printed, and the test binary (tests/test_main.cpp) exits with kSkipReturnCode if nothing failed,
// which ctest reports as skipped (tests/CMakeLists.txt gives such cases their own ctest entry).
inline constexpr int kSkipReturnCode = 77;
inline int& skipped_cases() {
  static int count = 0;
  return count;
}
inline void skip(const std::string& why) {
  ++skipped_cases();
  MESSAGE("SKIPPED: ", why);
}

}  // namespace plydem::test
