// HCP lamina: coordination, the affine homogenizer against a lattice sum written out here (each
// bond once, true lengths: ERRATA §2), corrected eq. (26), the relaxed calibration at every angle,
// plane stress of the free lamina, a static tension test against CLT, and the refusals.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <set>
#include <utility>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/homogenizer.hpp"
#include "experiments/protocols/tension.hpp"
#include "packings/hcp_lamina.hpp"
#include "strategies/hcp.hpp"
#include "strategies/registry.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using namespace plydem::test;

namespace {

// A neighbour of one particle: the branch vector to it and its bond family.
struct Neighbour {
  Eigen::Vector3d branch;
  int family;
};

Eigen::Vector3d at_angle(double length, double degrees, double z) {
  return {length * std::cos(degrees * kDeg), length * std::sin(degrees * kDeg), z};
}

// The neighbours of one particle of a layer stack with spacing l and layer distance c, written out
// from the geometry of Fig. 8: six in the plane (family = direction mod 180 deg / 60 deg), and
// three in each adjacent layer present, l/sqrt(3) off in the plane. Seen from A, B lies at
// projections 30, 150, 270 deg; seen from B, A (below and above alike) at 90, 210, 330 deg.
// Inclined families by projection axis: 30 -> 3, 90 -> 4, 150 -> 5.
std::vector<Neighbour> neighbours(bool is_b, bool below, bool above, double l, double c) {
  std::vector<Neighbour> list;
  for (int k = 0; k < 6; ++k) list.push_back({at_angle(l, 60.0 * k, 0.0), k % 3});
  const std::pair<double, int> from_a[3] = {{30, 3}, {150, 5}, {270, 4}};
  const std::pair<double, int> from_b[3] = {{90, 4}, {210, 3}, {330, 5}};
  for (const auto& [angle, family] : is_b ? from_b : from_a) {
    if (below) list.push_back({at_angle(l / std::sqrt(3.0), angle, -c), family});
    if (above) list.push_back({at_angle(l / std::sqrt(3.0), angle, c), family});
  }
  return list;
}

// Eq. (5) with ERRATA §2's counting: C = 1/(2V) sum over every particle's neighbours of
// |l|^2 [k_N N (x) N + k_T T^T T], i.e. each bond once, with the eq. (9) projector whose
// n_i n_j n_k n_l term sits inside the k_T factor. Voigt (11, 22, 33, 23, 13, 12).
Matrix6d lattice_sum(const std::vector<std::vector<Neighbour>>& particles,
                     const std::vector<FamilyStiffness>& k, double volume) {
  const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
  auto delta = [](int a, int b) { return a == b ? 1.0 : 0.0; };
  Matrix6d c = Matrix6d::Zero();
  for (const auto& list : particles) {
    for (const Neighbour& nb : list) {
      const double l2 = nb.branch.squaredNorm();
      const Eigen::Vector3d n = nb.branch.normalized();
      for (int I = 0; I < 6; ++I) {
        for (int J = 0; J < 6; ++J) {
          const int i = pair[I][0], j = pair[I][1], kk = pair[J][0], ll = pair[J][1];
          const double nnnn = n(i) * n(j) * n(kk) * n(ll);
          const double tt = 0.25 * (n(j) * n(kk) * delta(i, ll) + n(j) * n(ll) * delta(i, kk) +
                                    n(i) * n(kk) * delta(j, ll) + n(i) * n(ll) * delta(j, kk)) -
                            nnnn;
          c(I, J) += l2 * (k[nb.family].normal * nnnn + k[nb.family].shear * tt) / (2 * volume);
        }
      }
    }
  }
  return c;
}

std::vector<FamilyStiffness> six_families() {
  // Distinct (k_n, k_s) per family so that a family mix-up shows.
  std::vector<FamilyStiffness> k;
  for (int f = 0; f < 6; ++f) k.push_back({3.0 + f, 0.2 + 0.15 * f, 0.0, 0.0});
  return k;
}

std::vector<int> coordination_of(const Model& model) {
  std::vector<int> count(model.particles.size(), 0);
  for (int b = 0; b < model.bonds.size(); ++b) {
    ++count[model.bonds.first(b)];
    ++count[model.bonds.second(b)];
  }
  return count;
}

}  // namespace

TEST_CASE("HCP cells: 12 neighbours in the crystal; 12 in the lamina's middle layer, 9 outside") {
  const double l = 1.0;
  for (double c : {HcpLamina::close_packed_layer_spacing(l), 1.1 * l}) {
    CAPTURE(c);
    const HcpLamina lamina(l, c, 0.3);
    const UnitCell bulk = lamina.bulk_unit_cell();
    std::vector<int> count(bulk.basis.size(), 0);
    for (const auto& bond : bulk.bonds) {
      ++count[bond.first];
      ++count[bond.second];
    }
    CHECK(count == std::vector<int>{12, 12});
    const UnitCell cell = lamina.unit_cell(0.2e-3);
    count.assign(cell.basis.size(), 0);
    for (int b = 0; b < static_cast<int>(cell.bonds.size()); ++b) {
      ++count[cell.bonds[b].first];
      ++count[cell.bonds[b].second];
      const double length = cell.branch(b).norm();
      const bool inclined = cell.bonds[b].first != cell.bonds[b].second;
      // ERRATA §2: the inclined bond is sqrt(l^2/3 + c^2) long, l only when close packed.
      CHECK(length == doctest::Approx(inclined ? std::sqrt(l * l / 3 + c * c) : l));
      CHECK(HcpLamina::is_inclined(cell.bonds[b].family) == inclined);
    }
    CHECK(count == std::vector<int>{9, 12, 9});
  }
  CHECK(HcpLamina::close_packed_layer_spacing(2.0) == doctest::Approx(2 * std::sqrt(2.0 / 3.0)));
}

TEST_CASE("HCP coupon: interior coordination 9 / 12 / 9, no self or duplicate bonds") {
  CouponSpec spec;
  spec.material = eglass();
  spec.length = 1.2e-3;
  spec.width = 0.6e-3;
  for (double deg : {0.0, 30.0, 45.0, 90.0}) {
    CAPTURE(deg);
    spec.ply_angle = deg * kDeg;
    const Model model = HcpStrategy().build(spec).model;
    model.check_consistency();
    std::set<std::pair<int, int>> seen;
    for (int b = 0; b < model.bonds.size(); ++b) {
      const int i = model.bonds.first(b), j = model.bonds.second(b);
      CHECK(i != j);
      CHECK(seen.insert({std::min(i, j), std::max(i, j)}).second);
    }
    const std::vector<int> coordination = coordination_of(model);
    const double d = spec.particle_diameter;
    const double c = HcpLamina::close_packed_layer_spacing(d);
    int interior[3] = {0, 0, 0};
    for (int i = 0; i < model.particles.size(); ++i) {
      const double x = model.particles.reference_position(i, 0);
      const double y = model.particles.reference_position(i, 1);
      const int layer = static_cast<int>(std::lround(model.particles.reference_position(i, 2) / c));
      REQUIRE(std::abs(model.particles.reference_position(i, 2) - layer * c) < 1e-12);
      if (x > 2 * d && x < spec.length - 2 * d && y > 2 * d && y < spec.width - 2 * d) {
        CHECK(coordination[i] == (layer == 1 ? 12 : 9));
        ++interior[layer];
      }
    }
    for (int n : interior) CHECK(n > 20);
    // The three layers stand for the ply thickness.
    const double cell_area = std::sqrt(3.0) / 2 * d * d;
    CHECK(model.particles.volume(0) == doctest::Approx(cell_area * spec.thickness / 3));
  }
}

TEST_CASE("affine homogenizer = the corrected lattice sum (each bond once, true lengths)") {
  const double l = 1.0;
  const std::vector<FamilyStiffness> k = six_families();
  for (double c : {HcpLamina::close_packed_layer_spacing(l), 1.2 * l}) {
    CAPTURE(c);
    const HcpLamina lamina(l, c, 0.0);
    // Crystal: A and B with 12 neighbours each, V = 2 sqrt(3) R^2 c per particle.
    const double v_particle = 2 * std::sqrt(3.0) * 0.25 * l * l * c;
    const Matrix6d bulk_sum =
        lattice_sum({neighbours(false, true, true, l, c), neighbours(true, true, true, l, c)}, k,
                    2 * v_particle);
    const Matrix6d bulk = affine_stiffness(lamina.bulk_unit_cell(), k);
    CHECK(relative_difference(bulk, bulk_sum) < 1e-12);
    // Lamina A B A': faces free, V = cell area x delta for the three particles.
    const double delta = 0.37;
    const Matrix6d layer_sum =
        lattice_sum({neighbours(false, false, true, l, c), neighbours(true, true, true, l, c),
                     neighbours(false, true, false, l, c)},
                    k, std::sqrt(3.0) / 2 * l * l * delta);
    CHECK(relative_difference(affine_stiffness(lamina.unit_cell(delta), k), layer_sum) < 1e-12);
  }
}

TEST_CASE("corrected eq. (26) = the lattice sum of the crystal at any layer spacing") {
  const double R = 0.5, l = 2 * R;
  for (double c : {HcpLamina::close_packed_layer_spacing(l), 0.7 * l, 1.4 * l}) {
    CAPTURE(c);
    const double v = 2 * std::sqrt(3.0) * R * R * c;
    const Eigen::Matrix<double, 5, 4> m = hcp_eq26_matrix(R, c, v);
    // eq. (24): the two in-plane bonds along the fibre get k^1, the ten others k^2.
    const FamilyStiffness k1{2.5, 0.4, 0, 0}, k2{1.1, 0.3, 0, 0};
    const std::vector<FamilyStiffness> k = {k1, k2, k2, k2, k2, k2};
    const Matrix6d sum = lattice_sum(
        {neighbours(false, true, true, l, c), neighbours(true, true, true, l, c)}, k, 2 * v);
    Eigen::Matrix<double, 5, 1> expected;
    expected << sum(0, 0), sum(0, 1), sum(1, 1), sum(1, 2), sum(5, 5);
    const Eigen::Vector4d springs(k1.normal, k1.shear, k2.normal, k2.shear);
    CHECK(((m * springs - expected).norm() / expected.norm()) < 1e-12);
  }
  // ERRATA §2's C1212 coefficient of k_T2 over 12 equally long bonds, 1/4 + 3/2 s^2 - 3/4 s^4
  // (times |l|^2 / (2V)), holds at the close-packed spacing, where every bond is 2R long.
  const double c = HcpLamina::close_packed_layer_spacing(l), s2 = 1.0 / 3.0;
  const double v = 2 * std::sqrt(3.0) * R * R * c;
  CHECK(hcp_eq26_matrix(R, c, v)(4, 3) ==
        doctest::Approx(l * l / (2 * v) * (0.25 + 1.5 * s2 - 0.75 * s2 * s2)));
}

TEST_CASE("hcp: the relaxed lamina has E-glass's Q-bar at 0..90 deg, plane stress, springs >= 0") {
  const Material m = eglass();
  const auto strategy = default_registry().create("hcp");
  const double thickness = 0.2e-3;
  for (int deg = 0; deg <= 90; deg += 15) {
    CAPTURE(deg);
    const Calibration cal = strategy->calibrate(m, deg * kDeg, thickness);
    CHECK(relative_difference(cal.target, qbar_by_hand(m, deg * kDeg)) < 1e-12);
    CHECK(cal.relaxed_error < 1e-10);
    REQUIRE(cal.families.size() == 6);
    CHECK(cal.families[0].direction == doctest::Approx(deg * kDeg));  // family 1 on the fibre
    std::vector<FamilyStiffness> k;
    for (const auto& f : cal.families) {
      CHECK(f.stiffness.normal > 0);
      CHECK(f.stiffness.shear >= 0);
      k.push_back(f.stiffness);
    }
    // Independently: the six-family lamina in the specimen frame, relaxed with these springs.
    const UnitCell cell =
        HcpLamina(1.0, HcpLamina::close_packed_layer_spacing(1.0), deg * kDeg).unit_cell(thickness);
    const Matrix6d relaxed = relaxed_stiffness(cell, k);
    CHECK(relative_difference(in_plane_block(relaxed), qbar_by_hand(m, deg * kDeg)) < 1e-10);
    // Free faces: sigma_zz, sigma_yz, sigma_xz vanish under every strain (plane stress), so the
    // in-plane block is the plane-stress stiffness.
    for (int row : {2, 3, 4}) CHECK(relaxed.row(row).norm() < 1e-10 * relaxed.norm());
    // The two-particle basis relaxes: the affine sum of the same springs is stiffer than Q-bar.
    CHECK(relative_difference(cal.affine, cal.target) > 1e-3);
  }
}

TEST_CASE("hcp: option c, validated, changes the inclined bonds and still calibrates exactly") {
  HcpStrategy strategy;
  const auto options = strategy.options();
  REQUIRE(options.size() == 1);
  CHECK(options[0].name == "c");
  CHECK(options[0].value == doctest::Approx(2 * std::sqrt(2.0 / 3.0)));
  CHECK(options[0].description.find("radii") != std::string::npos);
  CHECK_THROWS_WITH_AS(strategy.set_option("c", 0.5), doctest::Contains("layer spacing c"), Error);
  CHECK_THROWS_WITH_AS(strategy.set_option("c", 4.0), doctest::Contains("layer spacing c"), Error);
  CHECK_THROWS_AS(strategy.set_option("c", std::nan("")), Error);
  CHECK_THROWS_WITH_AS(strategy.set_option("spacing", 2.0), doctest::Contains("its options: c"),
                       Error);
  CHECK(strategy.layer_spacing_radii() == doctest::Approx(2 * std::sqrt(2.0 / 3.0)));

  strategy.set_option("c", 2.2);
  CHECK(strategy.options()[0].value == 2.2);
  const Calibration cal = strategy.calibrate(eglass(), 30 * kDeg, 0.2e-3);
  CHECK(cal.relaxed_error < 1e-10);
  CouponSpec spec;
  spec.material = eglass();
  spec.length = 0.8e-3;
  spec.width = 0.4e-3;
  const Model model = strategy.build(spec).model;
  const double r = 0.5 * spec.particle_diameter, c = 2.2 * r;
  for (int b = 0; b < model.bonds.size(); ++b) {
    const bool inclined = HcpLamina::is_inclined(model.bonds.family(b));
    CHECK(model.bonds.length(b) ==
          doctest::Approx(inclined ? std::sqrt(4 * r * r / 3 + c * c) : 2 * r));
  }
}

TEST_CASE("static tension test of a small hcp coupon at 0 deg: Ex and nu_xy against CLT") {
  TensionSettings settings;
  settings.strategy = "hcp";
  settings.solver = TensionSolver::kStatic;
  settings.coupon.material = eglass();
  settings.coupon.length = 3e-3;
  settings.coupon.width = 0.8e-3;
  // Twice the default particle size keeps the 3D sparse factorization fast (under ASan too).
  settings.coupon.particle_diameter = 0.1e-3;
  const auto strategy = default_registry().create("hcp");
  const PullResult pull = TensionTest(settings).pull(*strategy, 0.0);
  // CLT at 0 deg: Ex = E1, nu_xy = nu12.
  CHECK(std::abs(pull.modulus / 45.6e9 - 1) < 0.02);
  CHECK(std::abs(pull.poisson - 0.278) < 0.015);
  CHECK(std::abs(pull.shear_coupling) < 0.005);
}

TEST_CASE("boundary-cell completion by class: the bonds present carry the missing share") {
  // Three particles in a row: the middle one has both bonds of its class, the ends one each.
  Model model;
  model.particles.resize(3);
  model.particles.radius.setConstant(0.5);
  model.particles.mass.setConstant(1);
  model.particles.moment_of_inertia.setConstant(1);
  for (int i = 0; i < 3; ++i) model.particles.reference_position(i, 0) = i;
  model.bonds.resize(2);
  for (int b = 0; b < 2; ++b) {
    model.bonds.first(b) = b;
    model.bonds.second(b) = b + 1;
    model.bonds.normal_stiffness(b) = 4;
    model.bonds.shear_stiffness(b) = 2;
    set_bond_geometry(model.particles, model.bonds, b);
  }
  // Class 0 with 2 bonds per particle in the bulk: 1/2 (2/1 + 2/2) = 1.5.
  CHECK(complete_boundary_cells_by_class(model.particles, model.bonds, {0, 0}, {2}) == 2);
  CHECK(model.bonds.normal_stiffness(0) == doctest::Approx(6));
  CHECK(model.bonds.shear_stiffness(1) == doctest::Approx(3));
  // Each bond its own class with one bond per particle: nothing is missing.
  CHECK(complete_boundary_cells_by_class(model.particles, model.bonds, {0, 1}, {1, 1}) == 0);
  CHECK_THROWS_AS(complete_boundary_cells_by_class(model.particles, model.bonds, {0, 2}, {1, 1}),
                  Error);
}

TEST_CASE("hcp refuses a ply it cannot represent, naming the constant and the nearest stiffness") {
  Material m = eglass();
  m.name = "soft-shear";
  m.G12 = 4.5e9;  // the lamina's non-negative springs give at least ~5.4 GPa in shear
  CHECK_THROWS_WITH_AS(HcpStrategy().calibrate(m, 0.0, 0.2e-3),
                       doctest::Contains("C66 cannot be reached"), Error);
  CHECK_THROWS_WITH_AS(HcpStrategy().calibrate(m, 0.0, 0.2e-3), doctest::Contains("soft-shear"),
                       Error);
}

TEST_CASE("hcp-eq26: no non-negative solution for E-glass, with the limits computed") {
  const auto strategy = default_registry().create("hcp-eq26");
  std::string message;
  try {
    strategy->calibrate(eglass(), 0.0, 0.2e-3);
  } catch (const Error& e) {
    message = e.what();
  }
  REQUIRE(!message.empty());
  // The ratio C2233/C1122 the crystal's lattice sum allows when close packed (k_N2 = 1, others 0).
  const double l = 1.0, c = HcpLamina::close_packed_layer_spacing(l);
  const std::vector<FamilyStiffness> k = {{0, 0, 0, 0}, {1, 0, 0, 0}, {1, 0, 0, 0},
                                          {1, 0, 0, 0}, {1, 0, 0, 0}, {1, 0, 0, 0}};
  const Matrix6d sum = lattice_sum(
      {neighbours(false, true, true, l, c), neighbours(true, true, true, l, c)}, k, 1.0);
  CHECK(message.find(fmt::format("{:.3f} at this c", sum(1, 2) / sum(0, 1))) != std::string::npos);
  // Eq. (26) as printed: C2233/C1122 = 4 x (1 - x) / (1 + x^2), x = sin^2(theta); its maximum by
  // scanning x.
  double printed_max = 0;
  for (int i = 0; i <= 100000; ++i) {
    const double x = i / 100000.0;
    printed_max = std::max(printed_max, 4 * x * (1 - x) / (1 + x * x));
  }
  CHECK(message.find(fmt::format("at most {:.3f}", printed_max)) != std::string::npos);
  const Matrix6d c3 = stiffness_3d(eglass());
  CHECK(message.find(fmt::format("against {:.3f}", c3(1, 2) / c3(0, 1))) != std::string::npos);
  CHECK(message.find("C1212 >= C1122") != std::string::npos);
}

TEST_CASE("hcp-eq26 reports the relaxed stiffness the lamina really has") {
  // A ply for which eq. (26) has non-negative springs.
  Material m = eglass();
  m.name = "stiff-shear";
  m.G12 = 7e9;
  m.nu12 = 0.2;
  m.nu23 = 0.2;
  const double thickness = 0.2e-3, deg = 30;
  const Calibration cal = HcpEq26Strategy().calibrate(m, deg * kDeg, thickness);
  std::vector<FamilyStiffness> k;
  for (const auto& f : cal.families) {
    CHECK(f.stiffness.normal > 0);
    CHECK(f.stiffness.shear >= 0);
    k.push_back(f.stiffness);
  }
  const UnitCell cell =
      HcpLamina(1.0, HcpLamina::close_packed_layer_spacing(1.0), deg * kDeg).unit_cell(thickness);
  const Eigen::Matrix3d relaxed = in_plane_block(relaxed_stiffness(cell, k));
  CHECK(relative_difference(cal.relaxed, relaxed) < 1e-12);
  CHECK(cal.relaxed_error ==
        doctest::Approx(relative_difference(relaxed, qbar_by_hand(m, deg * kDeg))));
  CHECK(cal.relaxed_error > 0.01);  // it does not claim the target
  // The springs are the least-squares solution of eq. (26) on the crystal's sum (with each
  // particle standing for a third of the ply's column): the residual is orthogonal to the
  // sum's derivatives with respect to the four springs.
  const double l = 1.0, c = HcpLamina::close_packed_layer_spacing(l);
  const double v_particle = std::sqrt(3.0) / 2 * l * l * thickness / 3;
  const Matrix6d c3 = stiffness_3d(m);
  auto five = [&](const std::vector<FamilyStiffness>& families) {
    const Matrix6d s =
        lattice_sum({neighbours(false, true, true, l, c), neighbours(true, true, true, l, c)},
                    families, 2 * v_particle);
    Eigen::Matrix<double, 5, 1> v;
    v << s(0, 0), s(0, 1), s(1, 1), s(1, 2), s(5, 5);
    return v;
  };
  Eigen::Matrix<double, 5, 1> goal;
  goal << c3(0, 0), c3(0, 1), c3(1, 1), c3(1, 2), c3(5, 5);
  const Eigen::Matrix<double, 5, 1> residual = five(k) - goal;
  CHECK(residual.norm() > 1e-3 * goal.norm());
  for (int unknown = 0; unknown < 4; ++unknown) {
    std::vector<FamilyStiffness> unit(6, FamilyStiffness{});
    for (int f = 0; f < 6; ++f) {
      const bool fibre = f == 0;
      if ((unknown == 0 && fibre) || (unknown == 2 && !fibre)) unit[f].normal = 1;
      if ((unknown == 1 && fibre) || (unknown == 3 && !fibre)) unit[f].shear = 1;
    }
    const Eigen::Matrix<double, 5, 1> column = five(unit);
    CHECK(std::abs(column.dot(residual)) < 1e-9 * column.norm() * goal.norm());
  }
}

TEST_CASE("hcp and hcp-eq26 are registered") {
  CHECK(default_registry().contains("hcp"));
  CHECK(default_registry().contains("hcp-eq26"));
}
