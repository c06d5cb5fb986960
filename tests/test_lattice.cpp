// The lattice strategy (paper Sec. 3.1): the random packing, the microplane law of eq. (15), the
// paper's uncorrected lattice (a negative control: far too soft), and the automatic correction,
// which either meets the target on the built packing or refuses naming the component.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "solvers/periodic_homogenization.hpp"
#include "strategies/lattice.hpp"
#include "support/test_support.hpp"

using namespace plydem;

namespace {

RandomPackingSpec small_box(bool periodic, std::uint64_t seed) {
  RandomPackingSpec spec;
  spec.box = Eigen::Vector3d(8, 7, 4);
  spec.periodic = {periodic, periodic, false};
  spec.diameter = 1;
  spec.packing_fraction = 0.29;
  spec.seed = seed;
  return spec;
}

std::set<std::pair<int, int>> pair_set(const PackingBonds& bonds) {
  return {bonds.pairs.begin(), bonds.pairs.end()};
}

}  // namespace

TEST_CASE("random sequential addition is reproducible, hard-sphere and fills the box") {
  const RandomPacking a = random_sequential_addition(small_box(false, 7));
  const RandomPacking b = random_sequential_addition(small_box(false, 7));
  const RandomPacking c = random_sequential_addition(small_box(false, 8));
  REQUIRE(a.position.rows() == small_box(false, 7).count());
  CHECK((a.position == b.position).all());  // bit for bit
  CHECK_FALSE((a.position == c.position).all());
  // Expected count: 0.29 of the box volume over the sphere volume pi/6.
  CHECK(a.position.rows() == std::lround(0.29 * 8 * 7 * 4 / (M_PI / 6)));
  double closest = 1e9;
  for (int i = 0; i < a.position.rows(); ++i) {
    for (int j = i + 1; j < a.position.rows(); ++j) {
      closest = std::min(closest, (a.position.row(i) - a.position.row(j)).matrix().norm());
    }
  }
  CHECK(closest >= 1.0);
  CHECK((a.position.colwise().minCoeff() >= 0).all());
  CHECK((a.position.col(0) <= 8).all());
}

TEST_CASE("bonds within the contact radius equal the brute-force search, periodic or not") {
  for (bool periodic : {false, true}) {
    const RandomPacking packing = random_sequential_addition(small_box(periodic, 3));
    const PackingBonds fast = bonds_within(packing, 1.8);
    const PackingBonds brute = bonds_within_brute_force(packing, 1.8);
    CHECK(pair_set(fast) == pair_set(brute));
    CHECK(fast.size() > 0);
    for (int k = 0; k < fast.size(); ++k) {
      const auto [i, j] = fast.pairs[k];
      const Eigen::Vector3d branch =
          (packing.position.row(j) - packing.position.row(i)).transpose().matrix() +
          packing.box.cwiseProduct(fast.image.row(k).transpose().cast<double>().matrix());
      CHECK(branch.norm() <= 1.8 + 1e-12);
      if (!periodic) CHECK((fast.image.row(k) == 0).all());
    }
  }
  CHECK_THROWS_AS(bonds_within(random_sequential_addition(small_box(false, 3)), 0), Error);
}

TEST_CASE("eq. (15): the microplane integral gives the paper's 1/35 matrix (corrected eq. 14)") {
  // Printed in the paper; ERRATA §2: it holds with E_T = sin^2 E_T^a + cos^2 E_T^b.
  Eigen::Matrix4d printed;
  printed << 36, 6, 20, 8, 12, 30, 16, 12, 8, 6, -8, -6, 12, 2, -12, -2;
  printed /= 35;
  const Eigen::Matrix<double, 5, 4> computed = microplane_matrix();
  CHECK((computed.topRows<4>() - printed).cwiseAbs().maxCoeff() < 1e-12);
  // ERRATA §2: for E-glass eq. (15) needs E_T^a < 0.
  const MicroplaneFit fit = fit_microplane_moduli(load_material("eglass-my750"));
  CHECK(fit.paper.shear_transverse < 0);
  CHECK(fit.moduli.shear_transverse == 0);
}

TEST_CASE("lattice-paper: the paper's lattice is far softer than its target (negative control)") {
  LatticeStrategy paper(false);
  const Material eglass = load_material("eglass-my750");
  const LatticeCalibration cal = paper.calibrate_lattice(eglass, 0, 0.2e-3, 0.05e-3);
  const InPlaneConstants relaxed = in_plane_constants(cal.calibration.relaxed);
  const InPlaneConstants affine = in_plane_constants(cal.affine_uncorrected);
  // The paper's law misses the target (it found 3.8x too soft in PFC; ERRATA §2: its E_T^a < 0
  // is clipped and its G12 is far off), and its affine sum (what eq. 15 promises) is not what
  // the network does once it relaxes (ERRATA §3).
  MESSAGE("lattice-paper relaxed Ex ", relaxed.Ex, " Ey ", relaxed.Ey, " Gxy ", relaxed.Gxy,
          " affine Ex ", affine.Ex, " error ", cal.calibration.relaxed_error);
  CHECK(cal.calibration.relaxed_error > 0.05);
  CHECK(std::abs(relaxed.Gxy / 5.83e9 - 1) > 0.1);
  CHECK(relative_difference(cal.affine_uncorrected, cal.calibration.relaxed) > 0.05);
  // The reported relaxed stiffness is the real one: an independent periodic homogenization of
  // the same sample with the same law.
  const PeriodicModel sample =
      paper.calibration_sample(cal.moduli, 0, 0.2e-3, 0.05e-3, eglass.density);
  const Eigen::Matrix3d measured = in_plane_block(homogenize_periodic(sample).relaxed);
  CHECK(relative_difference(measured, cal.calibration.relaxed) < 1e-9);
}

TEST_CASE("lattice: the correction meets a reachable target on its sample, exactly as simulated") {
  const Material mild = test::mild_ply();
  LatticeStrategy lattice(true);
  const LatticeCalibration cal = lattice.calibrate_lattice(mild, 0, 0.2e-3, 0.05e-3);
  const InPlaneConstants reached = in_plane_constants(cal.calibration.relaxed);
  CHECK(cal.calibration.relaxed_error < 1e-8);
  CHECK(reached.Ex == doctest::Approx(20e9).epsilon(0.02));
  CHECK(reached.Ey == doctest::Approx(15e9).epsilon(0.02));
  CHECK(reached.Gxy == doctest::Approx(6.5e9).epsilon(0.02));
  CHECK(reached.nu_xy == doctest::Approx(0.25).epsilon(0.02).scale(0));
  const PeriodicModel sample =
      lattice.calibration_sample(cal.moduli, 0, 0.2e-3, 0.05e-3, mild.density);
  CHECK(relative_difference(in_plane_block(homogenize_periodic(sample).relaxed),
                            cal.calibration.relaxed) < 1e-9);
  CHECK_NOTHROW(lattice.calibrate(mild, 0, 0.2e-3));

  // A coupon: its own packing, corrected, with the periodic bonds cut; no loose particle.
  CouponSpec coupon;
  coupon.material = mild;
  coupon.length = 1.0e-3;
  coupon.width = 0.8e-3;
  const Model model = lattice.build(coupon).model;
  CHECK_NOTHROW(model.check_consistency());
  std::vector<int> count(model.particles.size(), 0);
  for (int b = 0; b < model.bonds.size(); ++b) {
    ++count[model.bonds.first(b)];
    ++count[model.bonds.second(b)];
    CHECK(model.bonds.normal_stiffness(b) >= 0);
    CHECK(model.bonds.shear_stiffness(b) > 0);
    CHECK(model.bonds.length(b) <= 1.8 * 0.05e-3 * (1 + 1e-12));
  }
  CHECK(*std::min_element(count.begin(), count.end()) >= 1);
  CHECK(2.0 * model.bonds.size() / model.particles.size() > 6);
}

TEST_CASE("lattice: E-glass's G12 is out of the random network's reach, and it says so") {
  LatticeStrategy lattice(true);
  CHECK_THROWS_WITH_AS(lattice.calibrate(load_material("eglass-my750"), 0, 0.2e-3),
                       doctest::Contains("Gxy"), Error);
  CHECK_THROWS_WITH_AS(lattice.set_option("contact_radius", 0.5),
                       doctest::Contains("contact radius"), Error);
  CHECK_THROWS_AS(lattice.set_option("max_error", -1), Error);
}

// The correction and the refusal on the smallest sample the strategy accepts (8 x 8 diameters,
// 140 spheres instead of 570): the same code as the two cases above, small enough for the
// sanitizer build, which leaves those out (label slow). This sample happens to reach E-glass
// within max_error, so the refusal is asked of a ply with a still lower G12.
TEST_CASE(
    "small lattice sample: the correction meets a reachable target, a softer G12 is refused") {
  const Material mild = test::mild_ply();
  LatticeStrategy lattice(true);
  lattice.set_option("sample_diameters", 8);
  const LatticeCalibration cal = lattice.calibrate_lattice(mild, 0, 0.2e-3, 0.05e-3);
  MESSAGE("small sample: ", cal.sample_particles, " spheres, ", cal.sample_bonds, " bonds");
  CHECK(cal.sample_particles < 200);
  CHECK(cal.calibration.relaxed_error < 1e-8);
  const InPlaneConstants reached = in_plane_constants(cal.calibration.relaxed);
  CHECK(reached.Ex == doctest::Approx(20e9).epsilon(0.02));
  CHECK(reached.Gxy == doctest::Approx(6.5e9).epsilon(0.02));
  const PeriodicModel sample =
      lattice.calibration_sample(cal.moduli, 0, 0.2e-3, 0.05e-3, mild.density);
  CHECK(relative_difference(in_plane_block(homogenize_periodic(sample).relaxed),
                            cal.calibration.relaxed) < 1e-9);
  Material soft_shear = load_material("eglass-my750");
  soft_shear.G12 = 3.5e9;
  CHECK_THROWS_WITH_AS(lattice.calibrate(soft_shear, 0, 0.2e-3), doctest::Contains("Gxy"), Error);
}
