// Cure stresses (issue 33, strategies/cure_stress.hpp): a laminate cooled by delta_T, its bonds'
// free offsets solved as a load by the static solver, beside lamination theory's thermal ply
// stresses of the same laminate, at two particle sizes.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "core/units.hpp"
#include "solvers/bond_events.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/cure_stress.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"

using namespace plydem;

namespace {

constexpr double kCooling = -100;  // [K]

LaminateSpec crossply_spec(const std::string& layup, double diameter, double size) {
  LaminateSpec spec;
  spec.coupon.material = load_material("eglass-my750");
  spec.coupon.length = size;
  spec.coupon.width = size;
  spec.coupon.thickness = 0.2e-3;
  spec.coupon.particle_diameter = diameter;
  spec.ply_angles = parse_layup(layup);
  spec.interface.transverse_shear = true;
  return spec;
}

// The free laminate after cure, and its plies' stresses within `half` of the centre.
std::vector<Eigen::Vector3d> cured_ply_stresses(const LaminateSpec& spec, double half,
                                                Model* out = nullptr) {
  const std::unique_ptr<Strategy> s = default_registry().create("square");
  Model model = build_laminate(*s, spec).model;
  std::vector<Eigen::Vector3d> stresses = solve_cure(model, laminate_plies(spec), kCooling, half);
  if (out) *out = std::move(model);
  return stresses;
}

}  // namespace

TEST_CASE("a ply alone shrinks free of stress as it cools") {
  const LaminateSpec spec = crossply_spec("[30]", 0.1e-3, 1e-3);
  Model model;
  cured_ply_stresses(spec, 1e-3, &model);
  const Eigen::Matrix3d strain = ply_thermal_strain(laminate_plies(spec).front(), kCooling);
  double largest = 0;
  for (const Eigen::Matrix3d& s : particle_stresses(model.particles, model.bonds))
    largest = std::max(largest, s.cwiseAbs().maxCoeff());
  // Against the stress the shrinkage would cause if held: E2 alpha2 delta_T.
  CHECK(largest < 1e-9 * spec.coupon.material.E2 * std::abs(strain(1, 1)));
  // Every distance between particles shrinks by the thermal strain (the pins of the rigid-body
  // modes may turn the whole, which changes no distance): the stretch of dx is dx.eps dx / |dx|^2.
  const Particles& p = model.particles;
  for (int i = 1; i < p.size(); i += 7) {
    const Eigen::Vector3d dx =
        (p.reference_position.row(i) - p.reference_position.row(0)).transpose().matrix();
    const Eigen::Vector3d du = (p.displacement.row(i) - p.displacement.row(0)).transpose().matrix();
    const double stretch = dx.dot(du) / dx.squaredNorm(),
                 thermal = dx.dot(strain * dx) / dx.squaredNorm();
    CHECK(std::abs(stretch - thermal) < 1e-9 * strain.norm());
  }
}

TEST_CASE("cure stresses of cross-plies beside lamination theory, at two particle sizes") {
  struct Case {
    std::string layup;
    double diameter, size;
  };
  for (const Case& c : {Case{"[0/90]s", 0.1e-3, 8e-3}, Case{"[0/90]s", 0.05e-3, 4e-3},
                        Case{"[0/90_2]s", 0.1e-3, 8e-3}}) {
    const LaminateSpec spec = crossply_spec(c.layup, c.diameter, c.size);
    const std::vector<Ply> plies = laminate_plies(spec);
    const std::vector<Eigen::Vector3d> clt = clt_thermal_ply_stresses(plies, kCooling);
    const std::vector<Eigen::Vector3d> dem = cured_ply_stresses(spec, 0.1 * c.size);
    for (std::size_t k = 0; k < plies.size(); ++k) {
      // sigma_x and sigma_y in the coupon's axes; tau_xy is zero in both.
      const double scale = clt[k].head<2>().cwiseAbs().maxCoeff();
      MESSAGE(c.layup << " d = " << c.diameter * 1e3 << " mm, ply " << k << ": DEM ("
                      << dem[k](0) * 1e-6 << ", " << dem[k](1) * 1e-6 << ") MPa, CLT ("
                      << clt[k](0) * 1e-6 << ", " << clt[k](1) * 1e-6 << ")");
      CHECK(std::abs(dem[k](0) - clt[k](0)) < 0.02 * scale);
      CHECK(std::abs(dem[k](1) - clt[k](1)) < 0.02 * scale);
      CHECK(std::abs(dem[k](2)) < 0.02 * scale);
    }
  }
}

TEST_CASE("a small cross-ply's cure stresses: the slow case's path on a 2 mm coupon") {
  // A coupon 2.5 laminate thicknesses wide: its free edges reach the centre, within 5% of CLT
  // there, and the plies' stresses balance (a free laminate carries no net force).
  const LaminateSpec spec = crossply_spec("[0/90]s", 0.1e-3, 2e-3);
  const std::vector<Ply> plies = laminate_plies(spec);
  const std::vector<Eigen::Vector3d> clt = clt_thermal_ply_stresses(plies, kCooling);
  const std::vector<Eigen::Vector3d> dem = cured_ply_stresses(spec, 0.2e-3);
  Eigen::Vector3d net = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < plies.size(); ++k) {
    CHECK((dem[k] - clt[k]).norm() < 0.05 * clt[k].norm());
    net += dem[k];
  }
  CHECK(net.norm() < 0.05 * clt.front().norm());
}

TEST_CASE("cure stresses refuse what they cannot take, naming it") {
  LaminateSpec spec = crossply_spec("[0/90]s", 0.1e-3, 1e-3);
  const std::unique_ptr<Strategy> s = default_registry().create("square");
  Model model = build_laminate(*s, spec).model;
  std::vector<Ply> plies = laminate_plies(spec);
  CHECK_THROWS_WITH_AS(set_cure_offsets(model, plies, NAN), doctest::Contains("finite"), Error);
  CHECK_THROWS_WITH_AS(set_cure_offsets(model, {plies.front()}, kCooling),
                       doctest::Contains("plies were given"), Error);
  for (Ply& ply : plies) ply.material.thermal_expansion_given = false;
  CHECK_THROWS_WITH_AS(set_cure_offsets(model, plies, kCooling),
                       doctest::Contains("no thermal expansion"), Error);
  set_cure_offsets(model, laminate_plies(spec), kCooling);
  CHECK(model.bonds.has_free_offsets());
  set_cure_offsets(model, laminate_plies(spec), 0);
  CHECK(!model.bonds.has_free_offsets());
}

TEST_CASE("solvers that do not take free offsets refuse a cured model, naming it") {
  const LaminateSpec spec = crossply_spec("[0/90]s", 0.1e-3, 1e-3);
  const std::unique_ptr<Strategy> s = default_registry().create("square");
  Model model = build_laminate(*s, spec).model;
  set_cure_offsets(model, laminate_plies(spec), kCooling);
  const int n = model.particles.size();
  CHECK_THROWS_WITH_AS(
      run_events(model, DofConstraints(n), DofFlags::Constant(n, kDofsPerParticle, false), {}),
      doctest::Contains("free offsets"), Error);
  std::vector<int> order(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  CHECK_THROWS_WITH_AS(GatherBonds(model.bonds, order, {}), doctest::Contains("reference backend"),
                       Error);
}

TEST_CASE("a material file's thermal expansion: both coefficients or neither, of a solid's size") {
  const std::string base =
      "name = \"ply\"\nE1 = 45.6e9\nE2 = 16.2e9\nG12 = 5.83e9\nnu12 = 0.278\nnu23 = 0.4\n";
  const Material m = parse_material(base + "alpha1 = -1e-6\nalpha2 = 26e-6\n", "t.toml");
  CHECK(m.thermal_expansion_given);
  CHECK(m.alpha1 == -1e-6);
  CHECK(m.alpha2 == 26e-6);
  CHECK(!parse_material(base, "t.toml").thermal_expansion_given);
  CHECK_THROWS_WITH_AS(parse_material(base + "alpha1 = 1e-6\n", "t.toml"),
                       doctest::Contains("both alpha1 and alpha2"), Error);
  CHECK_THROWS_WITH_AS(parse_material(base + "alpha1 = 1e-6\nalpha2 = 0.01\n", "t.toml"),
                       doctest::Contains("alpha2 must be a finite thermal expansion"), Error);
  CHECK_THROWS_WITH_AS(parse_material(base + "alpha1 = nan\nalpha2 = 1e-6\n", "t.toml"),
                       doctest::Contains("alpha1"), Error);
}
