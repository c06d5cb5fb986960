// Strength calibration as simulated (strategies/strength_calibration.hpp): the relaxed motion of a
// unit cell, the strategies' cells against their coupons, the calibrated family strengths against
// hand-worked bond forces, the refusal of unreachable targets, and the key check: the built,
// relaxed coupon, solved statically by the engine, first breaks at XT, YT and S12.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>

#include "contacts/bond_kernel.hpp"
#include "core/bond_failure.hpp"
#include "core/error.hpp"
#include "core/failure_criteria.hpp"
#include "core/homogenizer.hpp"
#include "core/measurements.hpp"
#include "packings/hcp_lamina.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"
#include "strategies/strength_calibration.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using plydem::test::kDeg;

namespace {

constexpr double kThickness = 0.2e-3;  // CouponSpec's default ply thickness

std::unique_ptr<Strategy> strategy(const std::string& name) {
  return default_registry().create(name);
}

StrengthCalibration strengths_of(const Strategy& s, const Material& m, double angle,
                                 const StrengthOptions& options = {}) {
  return calibrate_strengths(s, s.calibrate(m, angle, kThickness), m, angle, kThickness, options);
}

// The message of the Error `f` throws ("" if none).
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// A coupon with its strengths assigned, and what loading it needs.
struct Coupon {
  const Strategy* strategy = nullptr;
  CouponSpec spec;
  Specimen specimen;
  StrengthCalibration strengths;
};

// A 2 x 0.6 mm square coupon of E-glass at `angle`, built, and its ply's strength calibration
// (no strengths assigned yet).
struct SmallCoupon {
  CouponSpec spec;
  Specimen built;
  StrengthCalibration strengths;
};

SmallCoupon small_square_coupon(double angle) {
  const auto s = strategy("square");
  SmallCoupon c;
  c.spec.material = test::eglass();
  c.spec.length = 2e-3;
  c.spec.width = 0.6e-3;
  c.spec.ply_angle = angle;
  c.built = s->build(c.spec);
  c.strengths = calibrate_strengths(*s, c.built.ply_calibrations.front(), c.spec.material, angle,
                                    c.spec.thickness);
  return c;
}

Coupon strong_coupon(const Strategy& s, const Material& material, double angle,
                     double diameter = CouponSpec{}.particle_diameter) {
  Coupon c;
  c.strategy = &s;
  c.spec.material = material;
  c.spec.ply_angle = angle;
  c.spec.particle_diameter = diameter;
  c.specimen = s.build(c.spec);
  c.strengths = calibrate_strengths(s, c.specimen.ply_calibrations.front(), material, angle,
                                    c.spec.thickness);
  assign_bond_strengths(c.specimen, {c.strengths});
  return c;
}

// How the coupon is loaded to a uniform in-plane stress.
enum class Boundary {
  // Grips (particles within two diameters of either end) held at the uniform solution: the
  // displacement of the relaxed bulk's strain and its spin; the long edges are free.
  kUniformGrips,
  // Every particle within three diameters of any edge held at the uniform solution (the
  // stiffness test's affine frame, with the bulk's spin). Three, not two: a free particle then
  // bonds only to particles with all their neighbours, whose bonds boundary completion left at
  // weight 1, so the uniform state is the interior's equilibrium at any lattice angle.
  kAffineFrame,
};

// The largest utilisation of the solved coupon over the bonds that count.
struct FirstBreak {
  double stress = 0;  // the applied stress at which the first bond reaches U = 1 [Pa]
  int bond = -1;
  BondState mode = BondState::kIntact;
};

// Loads the coupon to the specimen stress `direction` (x, y, xy) [1 MPa], solves it statically and
// scales to its first failure. Bonds with both ends held (inside a grip or the frame) do not count:
// they carry the imposed state, not the coupon's response.
FirstBreak first_break(const Coupon& c, const Eigen::Vector3d& direction, Boundary boundary) {
  Model model = c.specimen.model;
  const Particles& p = model.particles;
  const Calibration& cal = c.specimen.ply_calibrations.front();
  const double d = c.spec.particle_diameter;
  const Eigen::Vector3d low = p.reference_position.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = p.reference_position.colwise().maxCoeff().transpose();
  const Eigen::Vector3d centre = 0.5 * (low + high);
  const double applied = 1e6;
  // The strain of the relaxed model (the calibration's stiffness) and its bulk spin.
  const Eigen::Vector3d strain = cal.relaxed.inverse() * (applied * direction);
  Eigen::Matrix3d e = Eigen::Matrix3d::Zero();
  e(0, 0) = strain(0);
  e(1, 1) = strain(1);
  e(0, 1) = e(1, 0) = 0.5 * strain(2);
  const UnitCell cell = *c.strategy->unit_cell(cal, c.spec.thickness);
  REQUIRE(cell.basis.size() == 1);  // one particle per cell: one spin
  std::vector<FamilyStiffness> k;
  for (const FamilyCalibration& f : cal.families) k.push_back(f.stiffness);
  Vector6d voigt;
  voigt << strain(0), strain(1), 0, 0, 0, strain(2);
  const double spin = relaxed_motion(cell, k, voigt).rotation[0].z();

  DofConstraints constraints(p.size());
  std::vector<bool> held(p.size(), false);
  const double band = (boundary == Boundary::kAffineFrame ? 3 : 2) * d;
  for (int i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d x = p.reference_position.row(i).transpose();
    const bool at_end = x.x() <= low.x() + band || x.x() >= high.x() - band;
    const bool at_side = x.y() <= low.y() + band || x.y() >= high.y() - band;
    if (!(at_end || (boundary == Boundary::kAffineFrame && at_side))) continue;
    held[i] = true;
    const Eigen::Vector3d u = e * (x - centre);
    constraints.fix(i, Dof::kUx, u.x());
    constraints.fix(i, Dof::kUy, u.y());
    constraints.fix(i, Dof::kThetaZ, spin);
  }
  StaticSettings settings;
  settings.pin_rigid_modes = true;  // the layer's out-of-plane motion
  solve_static(model, constraints, settings);

  const Bonds& bonds = model.bonds;
  FirstBreak out;
  double worst = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    const int i = bonds.first(b), j = bonds.second(b);
    if (held[i] && held[j]) continue;
    const BondStresses s =
        bond_stresses(bond_parameters(bonds, b), bonds.strength_radius(b),
                      p.displacement.row(i).transpose(), p.rotation.row(i).transpose(),
                      p.displacement.row(j).transpose(), p.rotation.row(j).transpose());
    const BondUtilisation u = utilisation(s, bond_strength(bonds, b));
    if (u.ratio > worst) {
      worst = u.ratio;
      out.bond = b;
    }
  }
  REQUIRE(worst > 0);
  out.stress = applied / worst;
  // The mode it breaks in, at the first-failure load.
  const int b = out.bond, i = bonds.first(b), j = bonds.second(b);
  const BondStresses s =
      bond_stresses(bond_parameters(bonds, b), bonds.strength_radius(b),
                    p.displacement.row(i).transpose(), p.rotation.row(i).transpose(),
                    p.displacement.row(j).transpose(), p.rotation.row(j).transpose());
  const double over = (1 + 1e-9) / worst;  // just past U = 1
  out.mode =
      utilisation({s.axial * over, s.normal * over, s.shear * over}, bond_strength(bonds, b)).mode;
  return out;
}

// The relative difference a / b - 1.
double off(double a, double b) {
  return a / b - 1.0;
}

// E-glass with S12 lowered to the value hex2d's refusal names as consistent with YT, a little
// below it (the message rounds to 4 digits).
// The number after the last "with S12 = " in a refusal (MPa), without std::regex (GCC 12 warns
// inside <regex> in the sanitizer build).
double alternative_s12(const std::string& message) {
  const std::string key = "with S12 = ";
  const std::size_t at = message.rfind(key);
  REQUIRE_MESSAGE(at != std::string::npos, message);
  REQUIRE_MESSAGE(message.find(" MPa", at + key.size()) != std::string::npos, message);
  return std::stod(message.substr(at + key.size()));
}

Material eglass_for_hex2d() {
  Material m = test::eglass();
  const std::string message = error_of([&] { strengths_of(*strategy("hex2d"), m, 0.0); });
  REQUIRE_MESSAGE(message.find("or YT = ") != std::string::npos, message);
  m.strength.S12 = alternative_s12(message) * 1e6 * (1 - 1e-3);
  return m;
}

}  // namespace

TEST_CASE("relaxed_motion: the condensed spins and shifts, in equilibrium, carrying the stress") {
  // The three-particle HCP lamina cell (layer shifts and spins both relax) with springs that are
  // not calibrated to anything: the check is the motion itself.
  const UnitCell cell = HcpLamina(1.0, 0.8, 0.3).unit_cell(0.5);
  std::vector<FamilyStiffness> k(cell.family_count);
  for (int f = 0; f < cell.family_count; ++f) {
    const double kn = 1.0 + 0.3 * f, ks = 0.2 + 0.1 * f;
    k[f] = {kn, ks, kn * 0.0625 * (1 + 0.1 * f), ks * 0.125};
  }
  Vector6d strain;
  strain << 1e-3, -4e-4, 0, 0, 0, 6e-4;
  const CellMotion motion = relaxed_motion(cell, k, strain);
  REQUIRE(motion.fluctuation.size() == 3);
  CHECK(motion.fluctuation[0].norm() == 0);
  // Not affine: something relaxed.
  double relaxed = 0;
  for (int i = 0; i < 3; ++i) relaxed += motion.fluctuation[i].norm() + motion.rotation[i].norm();
  CHECK(relaxed > 1e-6);
  // Every basis particle is in equilibrium, and the virial stress (1/V) sum F . (E_k branch) is
  // the relaxed stiffness times the strain.
  std::vector<Eigen::Vector3d> force(3, Eigen::Vector3d::Zero()),
      torque(3, Eigen::Vector3d::Zero());
  Vector6d stress = Vector6d::Zero();
  double largest_force = 0;
  for (int b = 0; b < static_cast<int>(cell.bonds.size()); ++b) {
    const UnitCell::Bond& bond = cell.bonds[b];
    const BondParameters p = cell_bond(cell, b, k[bond.family]);
    const BondResponse r = parallel_bond_response(
        p, motion.displacement(cell, bond.first, Eigen::Vector3i::Zero()),
        motion.rotation[bond.first], motion.displacement(cell, bond.second, bond.image),
        motion.rotation[bond.second]);
    force[bond.first] += r.force_on_first;
    force[bond.second] -= r.force_on_first;
    torque[bond.first] += r.torque_on_first;
    torque[bond.second] += r.torque_on_second;
    largest_force = std::max(largest_force, r.force_on_first.norm());
    for (int s = 0; s < 6; ++s)
      stress(s) += r.force_on_first.dot(voigt_unit_strain(s) * cell.branch(b)) / cell.volume;
  }
  for (int i = 0; i < 3; ++i) {
    CHECK(force[i].norm() < 1e-10 * largest_force);
    CHECK(torque[i].norm() < 1e-10 * largest_force);
  }
  const Vector6d expected = relaxed_stiffness(cell, k) * strain;
  CHECK((stress - expected).norm() < 1e-10 * expected.norm());
}

TEST_CASE("unit cells are those calibrated on, their families numbered as the coupons'") {
  const Material m = test::eglass();
  for (const char* name : {"hex2d", "square", "hcp"}) {
    for (double deg : {0.0, 30.0, 45.0}) {
      CAPTURE(name);
      CAPTURE(deg);
      const auto s = strategy(name);
      CouponSpec spec;
      spec.material = m;
      spec.ply_angle = deg * kDeg;
      spec.length = 1e-3;
      spec.width = 0.4e-3;
      const Specimen built = s->build(spec);
      const Calibration& cal = built.ply_calibrations.front();
      const std::optional<UnitCell> cell = s->unit_cell(cal, spec.thickness);
      REQUIRE(cell);
      std::vector<FamilyStiffness> k;
      for (const FamilyCalibration& f : cal.families) k.push_back(f.stiffness);
      CHECK(relative_difference(in_plane_block(relaxed_stiffness(*cell, k)), cal.relaxed) < 1e-9);
      // Every coupon bond lies along a cell bond of its own family.
      const Bonds& bonds = built.model.bonds;
      int mismatched = 0;
      for (int b = 0; b < bonds.size(); ++b) {
        const Eigen::Vector3d n = bonds.normal.row(b).transpose();
        double best = 0;
        for (int c = 0; c < static_cast<int>(cell->bonds.size()); ++c) {
          if (cell->bonds[c].family != bonds.family(b)) continue;
          best = std::max(best, std::abs(n.dot(cell->branch(c).normalized())));
        }
        if (best < 1 - 1e-9) ++mismatched;
      }
      CHECK(mismatched == 0);
    }
  }
  // The random lattice has no unit cell, and the calibration says so.
  const auto lattice = strategy("lattice");
  CHECK(!lattice->unit_cell(Calibration{}, kThickness));
  const Material mild = [] {
    Material x = test::mild_ply();
    x.strength.XT = 500e6;
    x.strength.YT = 50e6;
    x.strength.S12 = 40e6;
    return x;
  }();
  CHECK_THROWS_WITH_AS(calibrate_strengths(*lattice, Calibration{}, mild, 0, kThickness),
                       doctest::Contains("has none"), Error);
}

TEST_CASE("square's family strengths are the bond stresses of the targets, by hand") {
  // At 0 deg the square lattice is orthotropic and nothing spins under sigma1 or sigma2: under
  // sigma1 = XT the x bonds stretch by XT/E1 l, under sigma2 = YT the y bonds by YT/E2 l (plane
  // stress, the calibration reaches Q), and a bond's normal stress is k_n du / (pi R^2).
  for (const Material& m : {test::eglass(), test::carbon_ply()}) {
    CAPTURE(m.name);
    const auto s = strategy("square");
    const Calibration cal = s->calibrate(m, 0.0, kThickness);
    const StrengthCalibration sc = calibrate_strengths(*s, cal, m, 0.0, kThickness);
    const double l = CouponSpec{}.particle_diameter, R = 0.5 * l;
    const double area = std::numbers::pi * R * R;
    REQUIRE(sc.families.size() == 4);
    CHECK(sc.families[0].tensile ==
          doctest::Approx(cal.families[0].stiffness.normal * m.strength.XT / m.E1 * l / area)
              .epsilon(1e-8));
    CHECK(sc.families[0].tensile_set_by == "XT");
    CHECK(sc.families[1].tensile ==
          doctest::Approx(cal.families[1].stiffness.normal * m.strength.YT / m.E2 * l / area)
              .epsilon(1e-8));
    CHECK(sc.families[1].tensile_set_by == "YT");
    CHECK(sc.families[0].radius == doctest::Approx(R));
    // All three targets met exactly, reported with the compression the model has.
    REQUIRE(sc.targets.size() == 5);
    for (int t = 0; t < 3; ++t) {
      CAPTURE(sc.targets[t].name);
      CHECK(sc.targets[t].calibrated);
      CHECK(sc.targets[t].model == doctest::Approx(sc.targets[t].target).epsilon(1e-9));
    }
    CHECK(sc.targets[0].name == "XT");
    CHECK(sc.targets[3].name == "XC");
    CHECK(!sc.targets[3].calibrated);
    CHECK(!sc.targets[4].calibrated);
    // Fibre compression splits the y bonds by Poisson expansion: sigma1 = -YT E1 / (nu12 E2)
    // stretches them by YT/E2 l, as sigma2 = YT does.
    CHECK(sc.targets[3].model ==
          doctest::Approx(m.strength.YT * m.E1 / (m.nu12 * m.E2)).epsilon(1e-6));
    CHECK(sc.targets[3].mode == "tension");
    // first_failure_factor is the same surface.
    CHECK(sc.first_failure_factor({m.strength.XT, 0, 0}) == doctest::Approx(1.0).epsilon(1e-9));
    CHECK(sc.first_failure_factor({0, 2 * m.strength.YT, 0}) == doctest::Approx(0.5).epsilon(1e-9));
    CHECK(sc.first_failure_factor({0, 0, -m.strength.S12}) == doctest::Approx(1.0).epsilon(1e-9));
  }
}

TEST_CASE("square meets XT, YT and S12 at any angle, for E-glass and a carbon ply") {
  for (const Material& m : {test::eglass(), test::carbon_ply()}) {
    for (double deg : {0.0, 15.0, 30.0, 45.0, 60.0, 90.0}) {
      CAPTURE(m.name);
      CAPTURE(deg);
      const StrengthCalibration sc = strengths_of(*strategy("square"), m, deg * kDeg);
      CHECK(sc.first_failure_factor({m.strength.XT, 0, 0}) == doctest::Approx(1).epsilon(1e-9));
      CHECK(sc.first_failure_factor({0, m.strength.YT, 0}) == doctest::Approx(1).epsilon(1e-9));
      CHECK(sc.first_failure_factor({0, 0, m.strength.S12}) == doctest::Approx(1).epsilon(1e-9));
    }
  }
}

TEST_CASE("strengths are stated for a particle size and scale as 1/R") {
  const Material m = test::eglass();
  const auto s = strategy("square");
  StrengthOptions coarse;
  coarse.particle_diameter = 0.1e-3;
  const StrengthCalibration fine = strengths_of(*s, m, 0.0);
  const StrengthCalibration twice = strengths_of(*s, m, 0.0, coarse);
  for (std::size_t f = 0; f < fine.families.size(); ++f) {
    CHECK(twice.families[f].radius == doctest::Approx(2 * fine.families[f].radius));
    CHECK(twice.families[f].tensile == doctest::Approx(0.5 * fine.families[f].tensile));
    CHECK(twice.families[f].cohesion == doctest::Approx(0.5 * fine.families[f].cohesion));
  }
  // The same first-failure surface.
  for (const PlyStress& stress : {PlyStress{1, 0, 0}, PlyStress{0.3, 1, 0.5}})
    CHECK(twice.first_failure_factor(stress) ==
          doctest::Approx(fine.first_failure_factor(stress)).epsilon(1e-9));
}

TEST_CASE("hex2d cannot give E-glass YT with S12 and says what it can, and who can") {
  const Material m = test::eglass();
  const std::string message = error_of([&] { strengths_of(*strategy("hex2d"), m, 0.0); });
  MESSAGE(message);
  CHECK(message.find("hex2d") != std::string::npos);
  CHECK(message.find("YT = 40 MPa is not met") != std::string::npos);
  CHECK(message.find("the model first breaks at") != std::string::npos);
  CHECK(message.find("or YT = 40 MPa with S12 = ") != std::string::npos);
  CHECK(message.find("strategies that meet XT, YT and S12 for this ply: square") !=
        std::string::npos);
  // XT and S12 are met: only YT is named.
  CHECK(message.find("XT = 1280 MPa is not met") == std::string::npos);
  CHECK(message.find("S12 = 73 MPa is not met") == std::string::npos);
  // The alternative it names is consistent: with S12 there, hex2d meets all three.
  const Material lowered = eglass_for_hex2d();
  const StrengthCalibration sc = strengths_of(*strategy("hex2d"), lowered, 0.0);
  for (int t = 0; t < 3; ++t)
    CHECK(sc.targets[t].model == doctest::Approx(sc.targets[t].target).epsilon(1e-9));
  // So is hcp's (its cell has three particles whose layers shift and spin).
  const std::string hcp = error_of([&] { strengths_of(*strategy("hcp"), m, 0.0); });
  Material for_hcp = m;
  for_hcp.strength.S12 = alternative_s12(hcp) * 1e6 * (1 - 1e-3);
  const StrengthCalibration h = strengths_of(*strategy("hcp"), for_hcp, 30 * kDeg);
  CHECK(h.first_failure_factor({0, for_hcp.strength.YT, 0}) == doctest::Approx(1).epsilon(1e-9));
  CHECK(h.first_failure_factor({0, 0, for_hcp.strength.S12}) == doctest::Approx(1).epsilon(1e-9));
}

TEST_CASE("missing or bad strength input is a clear error") {
  Material m = test::eglass();
  m.strength.YT = 0;
  const auto s = strategy("square");
  const Calibration cal = s->calibrate(m, 0.0, kThickness);
  CHECK_THROWS_WITH_AS(calibrate_strengths(*s, cal, m, 0.0, kThickness), doctest::Contains("YT"),
                       Error);
  StrengthOptions softening;
  softening.softening = true;
  CHECK_THROWS_WITH_AS(calibrate_strengths(*s, cal, test::eglass(), 0.0, kThickness, softening),
                       doctest::Contains("G_fibre"), Error);
  StrengthOptions bad;
  bad.friction_coefficient = -0.1;
  CHECK_THROWS_WITH_AS(calibrate_strengths(*s, cal, test::eglass(), 0.0, kThickness, bad),
                       doctest::Contains("friction"), Error);
  // A calibration the strategy did not make (another ply angle's) is refused.
  const Calibration other = s->calibrate(test::eglass(), 30 * kDeg, kThickness);
  CHECK_THROWS_WITH_AS(calibrate_strengths(*s, other, test::eglass(), 0.0, kThickness),
                       doctest::Contains("another ply"), Error);
  const Calibration hex = strategy("hex2d")->calibrate(test::eglass(), 0.0, kThickness);
  CHECK_THROWS_WITH_AS(calibrate_strengths(*s, hex, test::eglass(), 0.0, kThickness),
                       doctest::Contains("4 bond families, its calibration 3"), Error);
  InterfaceStrength one;
  one.normal = 30e6;
  CHECK_THROWS_WITH_AS(one.validate(), doctest::Contains("both"), Error);
  InterfaceStrength negative{-1, 1, 0, 0};
  CHECK_THROWS_WITH_AS(negative.validate(), doctest::Contains("normal strength"), Error);
  InterfaceStrength nan{30e6, std::numeric_limits<double>::quiet_NaN(), 0, 0};
  CHECK_THROWS_WITH_AS(nan.validate(), doctest::Contains("shear strength"), Error);
  CHECK_NOTHROW(InterfaceStrength{30e6, 60e6, 300, 900}.validate());
}

TEST_CASE("friction: tension lowers the shear capacity, so S12 is out of square's reach") {
  // PFC's shear strength c - sigma tan(phi) falls in tension: at XT the fibre bonds carry about
  // 5.8 GPa, so with tan(phi) = 0.5 their cohesion must exceed 2.9 GPa and S12 no longer sets it.
  const Material m = test::eglass();
  StrengthOptions options;
  options.friction_coefficient = 0.5;
  const std::string message = error_of([&] { strengths_of(*strategy("square"), m, 0.0, options); });
  CHECK(message.find("S12 = 73 MPa is not met") != std::string::npos);
  CHECK(message.find("no registered strategy meets") != std::string::npos);
  // A friction small against YT / XT's bond stresses keeps every target.
  options.friction_coefficient = 1e-4;
  const StrengthCalibration with = strengths_of(*strategy("square"), m, 0.0, options);
  for (int t = 0; t < 3; ++t)
    CHECK(with.targets[t].model == doctest::Approx(with.targets[t].target).epsilon(1e-9));
  CHECK(with.families[0].friction == 1e-4);
  // The diagonals' tensile strength and cohesion are both set by XT, where they carry no moment:
  // c = tau + sigma tan(phi) = c(without friction) + sigma_c tan(phi).
  const StrengthCalibration without = strengths_of(*strategy("square"), m, 0.0);
  REQUIRE(without.families[2].tensile_set_by == "XT");
  REQUIRE(without.families[2].cohesion_set_by == "XT");
  CHECK(with.families[2].cohesion ==
        doctest::Approx(without.families[2].cohesion + 1e-4 * without.families[2].tensile)
            .epsilon(1e-12));
}

TEST_CASE("the built coupons first break at XT, YT and S12 as the engine simulates them") {
  // The paper's coupon (CouponSpec defaults), strengths assigned, solved statically with grips
  // that hold the relaxed bulk's uniform state (its displacement and spin) and free long edges,
  // scaled to the first bond that reaches its strength; shear through the affine frame. Bonds
  // with both ends held do not count.
  // hex2d (E-glass with its consistent S12) is pulled through the affine frame: at 90 deg its
  // long edges are zig-zag rows, not lattice lines, where boundary completion is not exact and
  // the free edge first breaks early (measured below, not asserted).
  struct Case {
    const char* strategy;
    Material material;
    Boundary pull;
  };
  const Case cases[] = {{"square", test::eglass(), Boundary::kUniformGrips},
                        {"square", test::carbon_ply(), Boundary::kUniformGrips},
                        {"hex2d", eglass_for_hex2d(), Boundary::kAffineFrame}};
  for (const Case& k : cases) {
    const auto s = strategy(k.strategy);
    const LaminaStrength& x = k.material.strength;
    for (double deg : {0.0, 90.0}) {
      CAPTURE(k.strategy);
      CAPTURE(k.material.name);
      CAPTURE(deg);
      const Coupon c = strong_coupon(*s, k.material, deg * kDeg);
      const FirstBreak pull = first_break(c, {1, 0, 0}, k.pull);
      const double target = deg == 0 ? x.XT : x.YT;
      if (k.pull != Boundary::kUniformGrips) {
        const FirstBreak free = first_break(c, {1, 0, 0}, Boundary::kUniformGrips);
        MESSAGE(fmt::format("{} {} deg with free long edges: first break {:.6g} MPa ({:+.2e})",
                            k.strategy, deg, free.stress * 1e-6, off(free.stress, target)));
      }
      MESSAGE(fmt::format("{} {} {} deg: first break {:.6g} MPa against {} = {:.6g} ({:+.2e})",
                          k.strategy, k.material.name, deg, pull.stress * 1e-6,
                          deg == 0 ? "XT" : "YT", target * 1e-6, off(pull.stress, target)));
      CHECK(std::abs(off(pull.stress, target)) < 1e-6);  // the issue asks 1%
      CHECK(pull.mode != BondState::kIntact);
      const FirstBreak shear = first_break(c, {0, 0, 1}, Boundary::kAffineFrame);
      MESSAGE(fmt::format("  shear: first break {:.6g} MPa against S12 = {:.6g} ({:+.2e})",
                          shear.stress * 1e-6, x.S12 * 1e-6, off(shear.stress, x.S12)));
      CHECK(std::abs(off(shear.stress, x.S12)) < 1e-6);
    }
  }
}

TEST_CASE("a coupon of other particles keeps the strengths (the 1/R rescaling)") {
  // Strengths stated for 0.05 mm particles, assigned to a coupon of 0.1 mm ones.
  const auto s = strategy("square");
  const Coupon c = strong_coupon(*s, test::eglass(), 0.0, 0.1e-3);
  CHECK(c.strengths.families[0].radius == doctest::Approx(0.025e-3));
  CHECK(c.specimen.model.bonds.strength_radius(0) == doctest::Approx(0.05e-3));
  const FirstBreak pull = first_break(c, {1, 0, 0}, Boundary::kUniformGrips);
  CHECK(pull.stress == doctest::Approx(test::eglass().strength.XT).epsilon(1e-6));
}

TEST_CASE("first_failure_factor is the off-axis coupon's first failure") {
  const Material m = test::eglass();
  const auto s = strategy("square");
  for (double deg : {30.0, 45.0}) {
    CAPTURE(deg);
    const Coupon c = strong_coupon(*s, m, deg * kDeg);
    const FirstBreak pull = first_break(c, {1, 0, 0}, Boundary::kAffineFrame);
    const double model = c.strengths.first_failure_factor(to_ply_axes(1, 0, 0, deg * kDeg));
    CHECK(pull.stress == doctest::Approx(model).epsilon(1e-6));
  }
}

TEST_CASE("the model's off-axis first failure beside the four criteria (E-glass, square)") {
  const Material m = test::eglass();
  const auto s = strategy("square");
  std::string table = "angle  DEM  max-stress  Tsai-Hill  Tsai-Wu  Hashin [MPa]\n";
  for (int deg = 0; deg <= 90; deg += 15) {
    const StrengthCalibration sc = strengths_of(*s, m, deg * kDeg);
    const double model = sc.first_failure_factor(to_ply_axes(1, 0, 0, deg * kDeg));
    table += fmt::format("{:5d} {:7.1f}", deg, model * 1e-6);
    for (FailureCriterion c : all_criteria())
      table += fmt::format(" {:7.1f}", off_axis_strength(c, m.strength, deg * kDeg) * 1e-6);
    table += "\n";
    if (deg == 0) CHECK(model == doctest::Approx(m.strength.XT).epsilon(1e-9));
    if (deg == 90) CHECK(model == doctest::Approx(m.strength.YT).epsilon(1e-9));
  }
  MESSAGE(table);
}

TEST_CASE("softening: ductility from the fracture energy over the bond's share of crack area") {
  Material m = test::eglass();
  m.strength.G_fibre = 40e3;
  m.strength.G_matrix = 300;
  StrengthOptions options;
  options.softening = true;
  const auto s = strategy("square");
  const Calibration cal = s->calibrate(m, 0.0, kThickness);
  const StrengthCalibration sc = calibrate_strengths(*s, cal, m, 0.0, kThickness, options);
  // A crack normal to x cuts per unit area the x bonds (l |1|), and both diagonals (l sqrt(2) /
  // sqrt(2) each) of density 1 / (l^2 delta): A_crack = l delta / 3; the same normal to y.
  const double l = CouponSpec{}.particle_diameter;
  const double area = l * kThickness / 3;
  CHECK(sc.families[0].crack_area == doctest::Approx(area).epsilon(1e-12));
  CHECK(sc.families[1].crack_area == doctest::Approx(area).epsilon(1e-12));
  CHECK(sc.families[0].fracture_energy == m.strength.G_fibre);
  CHECK(sc.families[1].fracture_energy == m.strength.G_matrix);
  CHECK(sc.families[2].fracture_energy == m.strength.G_matrix);  // 45 deg from the fibre
  // The x bond at XT holds 1/2 k_n (XT/E1 l)^2, the y bond at YT 1/2 k_n (YT/E2 l)^2.
  const double kx = cal.families[0].stiffness.normal, ky = cal.families[1].stiffness.normal;
  const double ex = 0.5 * kx * std::pow(m.strength.XT / m.E1 * l, 2);
  const double ey = 0.5 * ky * std::pow(m.strength.YT / m.E2 * l, 2);
  CHECK(sc.families[0].peak_energy == doctest::Approx(ex).epsilon(1e-8));
  CHECK(sc.families[0].ductility ==
        doctest::Approx(std::max(1.0, m.strength.G_fibre * area / ex)).epsilon(1e-8));
  CHECK(sc.families[0].ductility > 1);
  CHECK(sc.families[1].ductility ==
        doctest::Approx(std::max(1.0, m.strength.G_matrix * area / ey)).epsilon(1e-8));
  // Without softening every bond is brittle.
  for (const FamilyStrength& f : strengths_of(*s, m, 0.0).families) CHECK(f.ductility == 1);

  // Assigned: a bulk bond gets the family's ductility; one of twice the radius half of its excess.
  CouponSpec spec;
  spec.material = m;
  spec.length = 1e-3;
  spec.width = 0.5e-3;
  Specimen specimen = s->build(spec);
  assign_bond_strengths(specimen, {sc});
  const Bonds& bonds = specimen.model.bonds;
  int bulk = -1;
  for (int b = 0; b < bonds.size() && bulk < 0; ++b)
    if (bonds.family(b) == 0 && bonds.normal_stiffness(b) == kx) bulk = b;
  REQUIRE(bulk >= 0);
  CHECK(bonds.ductility(bulk) == doctest::Approx(sc.families[0].ductility).epsilon(1e-12));
}

TEST_CASE("assign_bond_strengths per crack site: the bonds across one band share their factor") {
  // At 90°, rows of particles along the fibre, y.
  const SmallCoupon coupon = small_square_coupon(std::numbers::pi / 2);
  const Specimen& built = coupon.built;
  const Calibration& cal = built.ply_calibrations.front();
  const StrengthCalibration& sc = coupon.strengths;
  const double modulus = 10;
  for (const bool per_site : {true, false}) {
    CAPTURE(per_site);
    Specimen a = built;
    assign_bond_strengths(a, {sc}, {}, modulus, 3, {}, per_site);
    const Bonds& bonds = a.model.bonds;
    const Particles& p = a.model.particles;
    // Each bond's factor: its strength over the family's, over its stiffness weight. Bonds that
    // cross a gap between columns (ends at different x) grouped by the gap.
    std::map<long, std::vector<double>> gaps;
    const double x0 = p.reference_position.col(0).minCoeff();
    for (int b = 0; b < bonds.size(); ++b) {
      const int i = bonds.first(b), j = bonds.second(b);
      const double xi = p.reference_position(i, 0), xj = p.reference_position(j, 0);
      if (std::abs(xi - xj) < 1e-12) continue;
      const int f = bonds.family(b);
      const double weight = bonds.normal_stiffness(b) / cal.families[f].stiffness.normal;
      const double d = p.radius(i) + p.radius(j);
      gaps[std::lround((xi + xj - 2 * x0) / d)].push_back(bonds.tensile_strength(b) /
                                                          (sc.families[f].tensile * weight));
    }
    REQUIRE(gaps.size() > 10);
    int shared = 0;
    std::vector<double> first_of_gap;
    for (const auto& [gap, factors] : gaps) {
      REQUIRE(factors.size() > 3);
      const auto [lo, hi] = std::minmax_element(factors.begin(), factors.end());
      shared += *hi - *lo < 1e-12 * *hi;
      first_of_gap.push_back(factors.front());
    }
    // Per site every gap's bonds share one factor and the gaps differ; per bond neither.
    CHECK((shared == static_cast<int>(gaps.size())) == per_site);
    const auto [lo, hi] = std::minmax_element(first_of_gap.begin(), first_of_gap.end());
    CHECK(*hi / *lo > 1.05);
  }
}

TEST_CASE("assign_bond_strengths: stiffness weights, scatter, interfaces, mismatches") {
  const Material m = test::eglass();
  const auto s = strategy("square");
  const SmallCoupon coupon = small_square_coupon(0.0);
  const CouponSpec& spec = coupon.spec;
  const Specimen& built = coupon.built;
  const Calibration& cal = built.ply_calibrations.front();
  const StrengthCalibration& sc = coupon.strengths;

  // Without scatter: strength = family strength x k_n / bulk k_n (edge bonds carry their missing
  // partners' share and are as utilised as the bulk under the same strain).
  Specimen a = built;
  assign_bond_strengths(a, {sc});
  const Bonds& bonds = a.model.bonds;
  int weighted = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    const int f = bonds.family(b);
    const double weight = bonds.normal_stiffness(b) / cal.families[f].stiffness.normal;
    if (std::abs(weight - 1) > 1e-12) ++weighted;
    REQUIRE(bonds.tensile_strength(b) ==
            doctest::Approx(sc.families[f].tensile * weight).epsilon(1e-12));
    REQUIRE(bonds.cohesion(b) == doctest::Approx(sc.families[f].cohesion * weight).epsilon(1e-12));
    REQUIRE(bonds.strength_radius(b) == doctest::Approx(0.5 * spec.particle_diameter));
  }
  CHECK(weighted > 0);
  CHECK(bonds.breakable());

  // Weibull scatter: reproducible by seed, mean 1, median (ln 2)^(1/m) / Gamma(1 + 1/m).
  const double modulus = 8;
  Specimen w1 = built, w2 = built, w3 = built;
  assign_bond_strengths(w1, {sc}, {}, modulus, 7);
  assign_bond_strengths(w2, {sc}, {}, modulus, 7);
  assign_bond_strengths(w3, {sc}, {}, modulus, 8);
  CHECK((w1.model.bonds.tensile_strength == w2.model.bonds.tensile_strength).all());
  CHECK(!(w1.model.bonds.tensile_strength == w3.model.bonds.tensile_strength).all());
  const Eigen::ArrayXd factor = w1.model.bonds.tensile_strength / bonds.tensile_strength;
  CHECK((w1.model.bonds.cohesion / bonds.cohesion - factor).abs().maxCoeff() < 1e-12);
  const double n = static_cast<double>(factor.size());
  CHECK(factor.mean() == doctest::Approx(1.0).epsilon(3 * 0.15 / std::sqrt(n) + 1e-3));
  const double median = std::pow(std::log(2.0), 1 / modulus) / std::tgamma(1 + 1 / modulus);
  const double below = (factor < median).cast<double>().mean();
  CHECK(below == doctest::Approx(0.5).epsilon(3 * 0.5 / std::sqrt(n) / 0.5));

  // Mismatches and bad input.
  Specimen b = built;
  CHECK_THROWS_WITH_AS(assign_bond_strengths(b, {sc, sc}), doctest::Contains("plies"), Error);
  CHECK_THROWS_WITH_AS(assign_bond_strengths(b, {sc}, {}, -1), doctest::Contains("Weibull"), Error);
  StrengthCalibration fewer = sc;
  fewer.families.pop_back();
  CHECK_THROWS_WITH_AS(assign_bond_strengths(b, {fewer}), doctest::Contains("families"), Error);
  b.model.bonds.damage(3) = 0.5;
  CHECK_THROWS_WITH_AS(assign_bond_strengths(b, {sc}), doctest::Contains("damaged"), Error);
}

TEST_CASE("interface bonds break at the interface tractions, or never") {
  const Material m = test::eglass();
  const auto s = strategy("square");
  LaminateSpec spec;
  spec.coupon.material = m;
  spec.coupon.length = 1e-3;
  spec.coupon.width = 0.4e-3;
  spec.ply_angles = {0.0, 90 * kDeg};
  const Specimen built = build_laminate(*s, spec);
  std::vector<StrengthCalibration> plies;
  for (std::size_t k = 0; k < built.ply_calibrations.size(); ++k) {
    plies.push_back(calibrate_strengths(*s, built.ply_calibrations[k], m, spec.ply_angles[k],
                                        spec.coupon.thickness));
  }
  Specimen none = built;
  assign_bond_strengths(none, plies);
  Specimen given = built;
  const InterfaceStrength interface { 30e6, 60e6, 0, 0 };
  assign_bond_strengths(given, plies, interface);
  // A bond of interface area a has k_n = K_n a (strategies/laminate.hpp): it must break at
  // F_n = 30 MPa a, i.e. at a section stress 30 MPa a / (pi R^2).
  const InterfaceStiffness k = spec.interface.resolved(m, spec.coupon.thickness);
  const Bonds& bonds = given.model.bonds;
  int interface_bonds = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    if (!bonds.is_interface(b)) {
      CHECK(bonds.tensile_strength(b) == none.model.bonds.tensile_strength(b));
      continue;
    }
    ++interface_bonds;
    CHECK(std::isinf(none.model.bonds.tensile_strength(b)));
    CHECK(std::isinf(none.model.bonds.cohesion(b)));
    const double a = bonds.normal_stiffness(b) / k.normal;
    const double section = std::numbers::pi * std::pow(bonds.strength_radius(b), 2);
    CHECK(bonds.tensile_strength(b) * section == doctest::Approx(30e6 * a).epsilon(1e-12));
    CHECK(bonds.cohesion(b) * section == doctest::Approx(60e6 * a).epsilon(1e-12));
  }
  CHECK(interface_bonds > 0);
}
