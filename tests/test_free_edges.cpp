// Free edges consistent with the bulk (strategies/boundary_cells.hpp, issue 14): single plies on
// the paper's 10 x 0.83 mm coupon (0.05 mm particles), static solves, against CLT computed here
// from the engineering constants by rotating the ply's compliance, never through plydem's own
// stiffness path. With edge equilibrium (the default) every ply at 0..90 deg lands within 0.3% on
// Ex, Ey, Gxy and 0.003 on nu_xy, nu_yx (measured: within 0.10% and 0.0005); with the count
// completion (the negative control) turned lattices come out 1.4-2.4% low.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/homogenizer.hpp"
#include "core/material.hpp"
#include "experiments/protocols/tension.hpp"
#include "packings/hexagonal_layer.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/hex2d.hpp"
#include "strategies/registry.hpp"

using namespace plydem;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

// The moduli CLT gives a single ply at `angle` under uniaxial stress (in-plane compliance rotated
// by the standard transformation; Jones, Mechanics of Composite Materials, eq. 2.95).
struct Moduli {
  double Ex, Ey, Gxy, nu_xy, nu_yx;
};

Moduli clt_moduli(const Material& m, double angle) {
  const double s11 = 1 / m.E1, s22 = 1 / m.E2, s12 = -m.nu12 / m.E1, s66 = 1 / m.G12;
  const double c = std::cos(angle), s = std::sin(angle);
  const double c2 = c * c, s2 = s * s, c4 = c2 * c2, s4 = s2 * s2;
  const double xx = s11 * c4 + (2 * s12 + s66) * s2 * c2 + s22 * s4;
  const double yy = s11 * s4 + (2 * s12 + s66) * s2 * c2 + s22 * c4;
  const double xy = s12 * (s4 + c4) + (s11 + s22 - s66) * s2 * c2;
  const double ss = 2 * (2 * s11 + 2 * s22 - 4 * s12 - s66) * s2 * c2 + s66 * (s4 + c4);
  return {1 / xx, 1 / yy, 1 / ss, -xy / xx, -xy / yy};
}

// The largest relative modulus error and absolute Poisson's-ratio error of one static run.
struct Errors {
  double modulus = 0, poisson = 0;
};

Errors tension_errors(const std::string& strategy, const std::string& material, double angle,
                      double edge_equilibrium, double length = 10e-3, double width = 0.83e-3) {
  TensionSettings s;
  s.strategy = strategy;
  s.strategy_options = {{"edge_equilibrium", edge_equilibrium}};
  s.coupon.material = load_material(material);
  s.coupon.ply_angle = angle;
  s.coupon.length = length;
  s.coupon.width = width;
  s.solver = TensionSolver::kStatic;
  const TensionResult r = TensionTest(s).run();
  const Moduli clt = clt_moduli(s.coupon.material, angle);
  Errors e;
  for (const auto& [dem, theory] :
       {std::pair{r.dem.Ex, clt.Ex}, std::pair{r.dem.Ey, clt.Ey}, std::pair{r.dem.Gxy, clt.Gxy}}) {
    e.modulus = std::max(e.modulus, std::abs(dem / theory - 1));
  }
  e.poisson = std::max(std::abs(r.dem.nu_xy - clt.nu_xy), std::abs(r.dem.nu_yx - clt.nu_yx));
  MESSAGE(
      fmt::format("{} {} {:2.0f} deg, edge_equilibrium={:.0f}: Ex {:+.3f}%, Ey {:+.3f}%, "
                  "Gxy {:+.3f}%, nu_xy {:+.4f}, nu_yx {:+.4f}",
                  strategy, material, angle / kDeg, edge_equilibrium, 100 * (r.dem.Ex / clt.Ex - 1),
                  100 * (r.dem.Ey / clt.Ey - 1), 100 * (r.dem.Gxy / clt.Gxy - 1),
                  r.dem.nu_xy - clt.nu_xy, r.dem.nu_yx - clt.nu_yx));
  return e;
}

// The (strategy, material) pairs of the sweep. hex2d with a carbon ply ("t300-914c") is one line
// to add once hex2d calibrates carbon plies (issue 14 item 2).
struct Case {
  const char* strategy;
  const char* material;
};
const std::vector<Case> kCases = {
    {"hex2d", "eglass-my750"}, {"square", "eglass-my750"}, {"square", "t300-914c"}};

}  // namespace

TEST_CASE("the CLT reference of this file: the 0 and 90 deg plies give E1, E2, nu12, G12 back") {
  const Material m = load_material("t300-914c");
  const Moduli at0 = clt_moduli(m, 0), at90 = clt_moduli(m, 90 * kDeg);
  CHECK(at0.Ex == doctest::Approx(m.E1).epsilon(1e-14));
  CHECK(at0.Ey == doctest::Approx(m.E2).epsilon(1e-14));
  CHECK(at0.Gxy == doctest::Approx(m.G12).epsilon(1e-14));
  CHECK(at0.nu_xy == doctest::Approx(m.nu12).epsilon(1e-14));
  CHECK(at90.Ex == doctest::Approx(m.E2).epsilon(1e-12));
  CHECK(at90.nu_yx == doctest::Approx(m.nu12).epsilon(1e-12));
  // Reciprocity at an off-axis angle.
  const Moduli at30 = clt_moduli(m, 30 * kDeg);
  CHECK(at30.nu_xy / at30.Ex == doctest::Approx(at30.nu_yx / at30.Ey).epsilon(1e-12));
}

TEST_CASE(
    "the paper's coupon, 0-90 deg every 15: within 0.3% and 0.003 of CLT, the count "
    "completion 1% off") {
  for (const Case& c : kCases) {
    for (int degrees = 0; degrees <= 90; degrees += 15) {
      CAPTURE(c.strategy);
      CAPTURE(c.material);
      CAPTURE(degrees);
      const Errors e = tension_errors(c.strategy, c.material, degrees * kDeg, 1);
      CHECK(e.modulus < 0.003);
      CHECK(e.poisson < 0.003);
    }
  }
  // The negative control: the count completion misses where an edge cuts the turned lattice
  // (measured 2.4%, 2.1%, 1.9%).
  // (Named variables, not a structured binding: Clang 14 cannot capture one in CAPTURE's lambda.)
  for (const auto& row :
       {std::tuple{"hex2d", "eglass-my750", 75}, std::tuple{"square", "eglass-my750", 15},
        std::tuple{"square", "t300-914c", 15}}) {
    const char* const strategy = std::get<0>(row);
    const char* const material = std::get<1>(row);
    const int degrees = std::get<2>(row);
    CAPTURE(strategy);
    CAPTURE(degrees);
    CHECK(tension_errors(strategy, material, degrees * kDeg, 0).modulus > 0.01);
  }
}

TEST_CASE("a small coupon, the same path: edge equilibrium hits, the count completion misses") {
  // 4 x 0.6 mm (80 x 12 particles): the sanitizer build's case of the sweep above.
  const Errors hex_new = tension_errors("hex2d", "eglass-my750", 75 * kDeg, 1, 4e-3, 0.6e-3);
  const Errors hex_old = tension_errors("hex2d", "eglass-my750", 75 * kDeg, 0, 4e-3, 0.6e-3);
  const Errors square_new = tension_errors("square", "t300-914c", 15 * kDeg, 1, 4e-3, 0.6e-3);
  const Errors square_old = tension_errors("square", "t300-914c", 15 * kDeg, 0, 4e-3, 0.6e-3);
  CHECK(hex_new.modulus < 0.003);
  CHECK(hex_new.poisson < 0.003);
  CHECK(square_new.modulus < 0.003);
  CHECK(square_new.poisson < 0.003);
  CHECK(hex_old.modulus > 0.01);
  CHECK(square_old.modulus > 0.01);
}

TEST_CASE(
    "edge equilibrium: the unbalanced forces of the relaxed uniform state drop, weights > 0") {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = 75 * kDeg;
  spec.length = 3e-3;
  spec.width = 0.6e-3;
  spec.complete_boundary_cells = false;  // the bonds as calibrated, weight 1
  const Hex2dStrategy hex2d;
  const Calibration cal = hex2d.calibrate(spec.material, spec.ply_angle, spec.thickness);
  Model model = hex2d.assemble(spec, cal);
  const UnitCell cell = *hex2d.unit_cell(cal, spec.thickness);
  std::vector<FamilyStiffness> families;
  for (const FamilyCalibration& f : cal.families) families.push_back(f.stiffness);
  const Eigen::Matrix3d bulk = in_plane_block(relaxed_stiffness(cell, families));
  const double depth = kEdgeStripDiameters * spec.particle_diameter;
  CHECK_FALSE(free_edges_balanced(model.particles, model.bonds, cell, families, bulk, depth));
  const EdgeBalance r =
      balance_free_edges(model.particles, model.bonds, cell, families, bulk, depth);
  MESSAGE(fmt::format("{} bonds, {} equations, weights {:.3f}..{:.3f}, imbalance {:.3g} -> {:.3g}",
                      r.bonds_changed, r.equations, r.min_weight, r.max_weight, r.imbalance_before,
                      r.max_imbalance));
  CHECK(r.bonds_changed > 0);
  CHECK(r.min_weight > 0);
  CHECK(r.max_imbalance < 0.1 * r.imbalance_before);
  model.check_consistency();
}

TEST_CASE("edge equilibrium: bad input is refused by name") {
  CHECK_THROWS_WITH_AS(default_registry().create("hex2d")->set_option("edge_equilibrium", 2),
                       doctest::Contains("edge_equilibrium must be 1"), Error);
  CHECK_THROWS_WITH_AS(default_registry().create("square")->set_option("edge_equilibrium", 0.5),
                       doctest::Contains("square: edge_equilibrium must be 1"), Error);
  UnitCell two;
  two.basis = {Eigen::Vector3d::Zero(), Eigen::Vector3d(0.5, 0, 0)};
  Particles p;
  Bonds b;
  CHECK_THROWS_WITH_AS(balance_free_edges(p, b, two, {}, Eigen::Matrix3d::Identity(), 1e-4),
                       doctest::Contains("one-particle unit cell"), Error);
  const UnitCell one = HexagonalLayer(1.0, 0.0).unit_cell(0.2e-3);
  CHECK_THROWS_WITH_AS(balance_free_edges(p, b, one, {}, -Eigen::Matrix3d::Identity(), 1e-4),
                       doctest::Contains("positive-definite"), Error);
  CHECK_THROWS_WITH_AS(balance_free_edges(p, b, one, {}, Eigen::Matrix3d::Identity(), -1),
                       doctest::Contains("depth must be positive"), Error);
}
