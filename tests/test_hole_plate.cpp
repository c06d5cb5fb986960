// The hole-in-plate experiment (experiments/runner/hole_plate.hpp): hole cutting, the quick run of
// the registered kind with its files, and the DEM field against CalculiX with a check that a wrong
// field fails the bound.
#include <doctest/doctest.h>
#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/output/external_tool.hpp"
#include "experiments/runner/hole_plate.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using namespace plydem::test;
namespace fs = std::filesystem;

namespace {

const fs::path kHoleToml =
    fs::path(PLYDEM_TEST_DATA_DIR) / ".." / ".." / "experiments" / "hole.toml";

// Measured on the quick settings (1 mm particles, interface 1e13 / 1e12 N/m^3, C3D8I with the
// default mesh): ux 1.0%, uy 4.0% over the plate's grid, with margin for round-off and meshing.
// That this comparison fails for a wrong field is shown on the small plate (last test).
constexpr double kUxBound = 0.02;
constexpr double kUyBound = 0.06;
// The same for the small plate of the last test (0.3 mm particles, 1.5 mm hole, 12 x 6 mm):
// measured ux 1.0%, uy 7.7%; its 90 deg ply left at 0 deg gives uy 44%.
constexpr double kSmallUxBound = 0.02;
constexpr double kSmallUyBound = 0.12;

// A small [0/90/0] laminate of hex2d plies, 6 x 3 mm, 0.25 mm particles.
Model small_plate() {
  LaminateSpec spec;
  spec.coupon.material = load_material("eglass-my750");
  spec.coupon.length = 6e-3;
  spec.coupon.width = 3e-3;
  spec.coupon.thickness = 0.5e-3;
  spec.coupon.particle_diameter = 0.25e-3;
  spec.ply_angles = parse_layup("[0/90/0]");
  return build_laminate(*default_registry().create("hex2d"), spec).model;
}

bool has_png_signature(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  in.read(head, 8);
  const unsigned char expected[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return in && std::equal(head, head + 8, reinterpret_cast<const char*>(expected));
}

}  // namespace

TEST_CASE("remove_hole takes out exactly the particles inside the circle and their bonds") {
  Model plate = small_plate();
  const Model before = plate;
  const double cx = 3e-3, cy = 1.5e-3, d = 1.2e-3;
  int inside = 0;
  for (int i = 0; i < before.particles.size(); ++i) {
    const double dx = before.particles.reference_position(i, 0) - cx;
    const double dy = before.particles.reference_position(i, 1) - cy;
    inside += std::hypot(dx, dy) < 0.5 * d;
  }
  REQUIRE(inside > 3);
  const HoleRemoval removal = remove_hole(plate, cx, cy, d);
  CHECK(removal.particles == inside);
  CHECK(plate.particles.size() == before.particles.size() - inside);
  CHECK(plate.bonds.size() == before.bonds.size() - removal.bonds);
  CHECK(removal.bonds > 0);
  for (int i = 0; i < plate.particles.size(); ++i) {
    const double dx = plate.particles.reference_position(i, 0) - cx;
    const double dy = plate.particles.reference_position(i, 1) - cy;
    CHECK(std::hypot(dx, dy) >= 0.5 * d);
  }
  // Every bond still joins two particles at its reference length.
  for (int b = 0; b < plate.bonds.size(); ++b) {
    const Eigen::Vector3d branch = (plate.particles.reference_position.row(plate.bonds.second(b)) -
                                    plate.particles.reference_position.row(plate.bonds.first(b)))
                                       .matrix()
                                       .transpose();
    CHECK(branch.norm() == doctest::Approx(plate.bonds.length(b)).epsilon(1e-12));
  }
}

TEST_CASE("remove_hole refuses a hole as wide as the plate, or one that cuts nothing") {
  Model plate = small_plate();
  const int n = plate.particles.size();
  CHECK_THROWS_WITH_AS(remove_hole(plate, 3e-3, 1.5e-3, 3e-3), doctest::Contains("separate pieces"),
                       Error);
  CHECK(plate.particles.size() == n);  // left unchanged
  CHECK_THROWS_WITH_AS(remove_hole(plate, 3e-3, 1.5e-3, 0.01e-3),
                       doctest::Contains("holds no particle"), Error);
  CHECK_THROWS_WITH_AS(remove_hole(plate, 3e-3, 1.5e-3, 20e-3),
                       doctest::Contains("removes every particle"), Error);
}

TEST_CASE("a hole config with an unknown key or a hole wider than the plate is an error") {
  const ExperimentConfig misspelt = ExperimentConfig::parse(
      "experiment = \"hole\"\nhole_diameter_mm = 3\n[dem]\nparticle_diameter = 0.3\n", "bad.toml");
  CHECK_THROWS_WITH_AS(hole_plate_settings(misspelt, false),
                       doctest::Contains("unknown key 'dem.particle_diameter'"), Error);
  const ExperimentConfig wide =
      ExperimentConfig::parse("experiment = \"hole\"\nhole_diameter_mm = 40\n", "wide.toml");
  CHECK_THROWS_WITH_AS(hole_plate_settings(wide, false), doctest::Contains("does not fit"), Error);
  const ExperimentConfig element =
      ExperimentConfig::parse("experiment = \"hole\"\n[fem]\nelement = \"C3D4\"\n", "el.toml");
  CHECK_THROWS_WITH_AS(hole_plate_settings(element, false), doctest::Contains("C3D8I"), Error);
  // The shipped config spells out the defaults.
  const HolePlateSettings shipped = hole_plate_settings(ExperimentConfig::load(kHoleToml), false);
  const HolePlateSettings defaults;
  CHECK(shipped.length == doctest::Approx(defaults.length));
  CHECK(shipped.hole_diameter == doctest::Approx(defaults.hole_diameter));
  CHECK(shipped.particle_diameter == doctest::Approx(defaults.particle_diameter));
  CHECK(shipped.grid_spacing == doctest::Approx(defaults.grid_spacing));
}

TEST_CASE("quick run of the kind 'hole': report, rows, VTU files and PNG maps") {
  REQUIRE(default_experiment_registry().contains("hole"));
  const ExperimentConfig config = ExperimentConfig::load(kHoleToml);
  REQUIRE(config.kind() == "hole");
  ExperimentContext context;
  context.out_dir = fresh_directory("hole_kind");
  context.quick = true;
  const ExperimentOutput out = default_experiment_registry().create("hole")->run(config, context);
  CHECK(out.report_markdown.find("Quick run") != std::string::npos);
  for (const fs::path& file : out.files) CHECK_MESSAGE(fs::exists(context.out_dir / file), file);
  CHECK(fs::file_size(context.out_dir / "hole_particles.vtu") > 1000);
  CHECK(fs::file_size(context.out_dir / "hole_bonds.vtu") > 1000);
  auto value = [&](const std::string& quantity, const std::string& source) {
    for (const ResultRow& r : out.rows)
      if (r.quantity == quantity && r.source == source) return r.value;
    FAIL("no row ", quantity, " from ", source);
    return 0.0;
  };
  CHECK(value("particles", "dem hex2d") > 5000);
  const double dem_stiffness = value("plate stiffness", "dem hex2d");
  const double clt_stiffness = value("plate stiffness", "clt, plate without hole");
  // CLT by hand for [0/90/0] E-glass (ERRATA §1): Ex = 36.009 GPa; 36 x 1.5 mm section, 60 mm.
  CHECK(clt_stiffness == doctest::Approx(36.009e9 * 36e-3 * 1.5e-3 / 60e-3 * 1e-6).epsilon(1e-4));
  // A 3 mm hole in a 36 mm wide plate softens it by a few percent at most.
  CHECK(dem_stiffness < clt_stiffness);
  CHECK(dem_stiffness > 0.95 * clt_stiffness);

  const CalculixAvailability calculix = calculix_availability();
  const bool ccx = calculix.available;
  if (!ccx) {
    CHECK(out.report_markdown.find("FEM column not run") != std::string::npos);
    skip(calculix.message);
  } else {
    CHECK(value("ux L2 error", "dem hex2d vs calculix") < 100 * kUxBound);
    CHECK(value("uy L2 error", "dem hex2d vs calculix") < 100 * kUyBound);
    CHECK(value("plate stiffness", "calculix") == doctest::Approx(dem_stiffness).epsilon(0.02));
  }
  if (const GnuplotAvailability gnuplot = gnuplot_availability(); !gnuplot.available) {
    skip(gnuplot.message);
  } else {
    std::vector<std::string> pngs = {"hole_ux.png", "hole_uy.png"};
    if (ccx) pngs.push_back("hole_difference.png");
    for (const std::string& png : pngs) {
      CHECK_MESSAGE(has_png_signature(context.out_dir / png), png);
      CHECK(out.report_markdown.find(png) != std::string::npos);
    }
  }
  fs::remove_all(context.out_dir);
}

// A 12 x 6 mm plate with a 1.5 mm hole, small enough for the sanitizer build: the whole pipeline
// (cut, grips, solve, CalculiX, grid); the comparison of the FEM field with itself, scaled, and
// against a DEM with the 90 deg ply left at 0 deg.
TEST_CASE(
    "small plate: DEM against CalculiX; scaled fields and the 90 deg ply left at 0 deg fail") {
  if (const CalculixAvailability ccx = calculix_availability(); !ccx.available) {
    skip(ccx.message);
    return;
  }
  HolePlateSettings s;
  s.length = 12e-3;
  s.width = 6e-3;
  s.hole_diameter = 1.5e-3;
  s.grip_travel = 0.02e-3;
  s.particle_diameter = 0.3e-3;
  s.interface = {1e14, 1e13};
  s.grid_spacing = 0.25e-3;
  const HolePlateDem dem = solve_hole_plate_dem(s);
  const FemSolution fem = solve_hole_plate_fem(s);
  REQUIRE(fem.available);
  const ComparisonGrid grid{0, s.length, 0, s.width, s.grid_spacing};
  auto compare = [&](const Model& model) {
    return compare_on_grid(fem.displacement, model, 3, grid, 0.5 * s.length, 0.5 * s.width,
                           s.hole_diameter, 1.5 * s.particle_diameter);
  };
  const GridComparison right = compare(dem.model);
  MESSAGE("small plate: ux ", right.ux_error, ", uy ", right.uy_error, "; stiffness DEM ",
          dem.stiffness, " FEM ", fem.reaction_force / fem.end_displacement, " N/m");
  CHECK(right.ux_error < kSmallUxBound);
  CHECK(right.uy_error < kSmallUyBound);
  CHECK(dem.stiffness == doctest::Approx(fem.reaction_force / fem.end_displacement).epsilon(0.05));
  // A particle model that carries the FEM field itself (sampled at each particle on its ply's
  // mid-surface): the comparison then measures only its own interpolation.
  Model exact = dem.model;
  const double t = s.thickness / 3;
  for (int i = 0; i < exact.particles.size(); ++i) {
    const std::optional<Eigen::Vector3d> u = fem.displacement.at(
        exact.particles.reference_position(i, 0), exact.particles.reference_position(i, 1),
        exact.particles.reference_position(i, 2) - t);
    REQUIRE(u.has_value());
    exact.particles.displacement.row(i) = u->transpose().array();
  }
  const GridComparison self = compare(exact);
  MESSAGE("FEM against itself through the particles: ux ", self.ux_error, ", uy ", self.uy_error);
  CHECK(self.ux_error < 0.2 * kSmallUxBound);
  CHECK(self.uy_error < 0.2 * kSmallUyBound);
  CHECK(self.points > 0.9 * self.nx * self.ny * 3);
  // 5% too much ux (grips 5% further apart) and 20% too much contraction fail the bounds.
  Model scaled = exact;
  scaled.particles.displacement.col(0) *= 1.05;
  CHECK(compare(scaled).ux_error > kSmallUxBound);
  scaled = exact;
  scaled.particles.displacement.col(1) *= 1.2;
  CHECK(compare(scaled).uy_error > kSmallUyBound);

  // The DEM with its 90 deg ply left at 0 deg: it contracts like a 0 deg ply.
  HolePlateSettings wrong = s;
  wrong.layup = "[0/0/0]";
  const GridComparison wrong_cmp = compare(solve_hole_plate_dem(wrong).model);
  MESSAGE("small plate, [0/0/0] DEM against the [0/90/0] FEM: ux ", wrong_cmp.ux_error, ", uy ",
          wrong_cmp.uy_error);
  CHECK(wrong_cmp.uy_error > kSmallUyBound);
}

TEST_CASE("without CalculiX the kind says so plainly and still runs the DEM") {
  const ExperimentConfig config = ExperimentConfig::parse(
      "experiment = \"hole\"\nlength_mm = 12\nwidth_mm = 6\nhole_diameter_mm = 1.5\n"
      "grip_travel_mm = 0.02\n[dem]\nparticle_diameter_mm = 0.4\n[compare]\n"
      "grid_spacing_mm = 0.5\n",
      "small.toml");
  ExperimentContext context;
  context.out_dir = fresh_directory("hole_no_ccx");
  context.calculix = "/nonexistent/ccx";
  const ExperimentOutput out = default_experiment_registry().create("hole")->run(config, context);
  CHECK(out.report_markdown.find("FEM column not run") != std::string::npos);
  CHECK(out.report_markdown.find("/nonexistent/ccx") != std::string::npos);
  bool has_error_row = false, has_dem_stiffness = false;
  for (const ResultRow& r : out.rows) {
    has_error_row = has_error_row || r.quantity.find("L2 error") != std::string::npos;
    has_dem_stiffness =
        has_dem_stiffness || (r.quantity == "plate stiffness" && r.source == "dem hex2d");
  }
  CHECK_FALSE(has_error_row);
  CHECK(has_dem_stiffness);
  CHECK(fs::exists(context.out_dir / "small_particles.vtu"));  // named after the config
  if (const GnuplotAvailability gnuplot = gnuplot_availability(); !gnuplot.available) {
    skip(gnuplot.message);
  } else {
    CHECK(has_png_signature(context.out_dir / "small_ux.png"));
    CHECK_FALSE(fs::exists(context.out_dir / "small_difference.png"));
  }
  fs::remove_all(context.out_dir);
}
