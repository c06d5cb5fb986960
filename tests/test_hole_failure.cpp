// The notched plate to failure (`plydem run experiments/hole_failure.toml`): the stress
// concentration's closed forms, the first failure of a plate with a hole at the hole's edge
// beside the unnotched first failure over Kt, the quick config end to end, and bad values refused.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/stress_concentration.hpp"
#include "experiments/output/external_tool.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "strategies/laminate.hpp"
#include "support/results_csv.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using namespace plydem::test;
namespace fs = std::filesystem;

namespace {

// Lekhnitskii's Kt_inf times Heywood's finite-width factor, written out here from the [0/90/0]
// laminate's constants, which are computed by hand from the ply's: equal plies, so
// A / h = (2 Q(0°) + Q(90°)) / 3, Q(90°) the 0° ply's with 1 and 2 swapped.
double kt_of_090_plate(const Material& m, double diameter, double width) {
  const double nu21 = m.nu12 * m.E2 / m.E1;
  const double q11 = m.E1 / (1 - m.nu12 * nu21), q22 = m.E2 / (1 - m.nu12 * nu21);
  const double q12 = m.nu12 * q22, q66 = m.G12;
  const double a11 = (2 * q11 + q22) / 3, a22 = (2 * q22 + q11) / 3, a12 = q12, a66 = q66;
  const double ex = (a11 * a22 - a12 * a12) / a22, ey = (a11 * a22 - a12 * a12) / a11;
  const double nuxy = a12 / a22, gxy = a66;
  const double kt_inf = 1 + std::sqrt(2 * (std::sqrt(ex / ey) - nuxy) + ex / gxy);
  const double r = 1 - diameter / width;
  return kt_inf * (2 + r * r * r) / (3 * r);
}

// The [0/90/0] E-glass plate of the square strategy, `width` wide and 5/3 of it long (the paper's
// 60 x 36 mm shape), 0.5 mm plies, a central hole of `diameter`, particles of `particle`; no
// scatter, the paper's interface stiffness; stopped after the first break.
StrengthSettings notched_plate(double width, double diameter, double particle) {
  StrengthSettings s;
  s.coupon.material = load_material("eglass-my750");
  s.coupon.length = width * 5.0 / 3.0;
  s.coupon.width = width;
  s.coupon.thickness = 0.5e-3;
  s.coupon.particle_diameter = particle;
  s.layup = parse_layup("[0/90/0]");
  s.interface = {1e14, 1e13};
  s.weibull_modulus = 0;
  s.hole_diameter = diameter;
  s.events.max_events = 1;
  return s;
}

std::map<std::string, double> rows_of(const fs::path& csv) {
  std::map<std::string, double> rows;
  for (const std::vector<std::string>& f : results_csv_rows(csv))
    rows[fmt::format("{}|{}|{}", f[1], f[2], f[3])] = std::stod(f[4]);
  return rows;
}

fs::path config_path() {
  return fs::path(PLYDEM_TEST_DATA_DIR) / ".." / ".." / "experiments" / "hole_failure.toml";
}

// The whole text of a file the run wrote (its report).
std::string file_text(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), {}};
}

}  // namespace

TEST_CASE("the hole's stress concentration: isotropic 3, Heywood's width factor, bad constants") {
  // An isotropic plate: Ex = Ey, Gxy = E / (2 (1 + nu)) gives 2 (1 - nu) + 2 (1 + nu) = 4 under
  // the root, Kt_inf = 3 for any nu.
  for (double nu : {0.0, 0.25, 0.3, 0.45}) {
    InPlaneConstants iso;
    iso.Ex = iso.Ey = 70e9;
    iso.nu_xy = iso.nu_yx = nu;
    iso.Gxy = 70e9 / (2 * (1 + nu));
    CHECK(orthotropic_hole_stress_concentration(iso) == doctest::Approx(3.0).epsilon(1e-14));
  }
  CHECK(heywood_finite_width_factor(0, 36e-3) == doctest::Approx(1.0).epsilon(1e-15));
  // D/W = 1/2: (2 + 1/8) / (3/2).
  CHECK(heywood_finite_width_factor(18e-3, 36e-3) == doctest::Approx(17.0 / 12.0).epsilon(1e-14));
  InPlaneConstants bad;
  bad.Ex = 40e9;
  bad.Ey = 20e9;
  bad.Gxy = 0;
  CHECK_THROWS_WITH_AS(orthotropic_hole_stress_concentration(bad),
                       doctest::Contains("positive, finite Gxy"), Error);
  CHECK_THROWS_WITH_AS(heywood_finite_width_factor(40e-3, 36e-3),
                       doctest::Contains("narrower than its strip"), Error);
}

TEST_CASE("Whitney and Nuismer's notched strength: its limits and the average of the stress") {
  // The point-stress ratio is 1 / sigma_y(R + d0) of Konish and Whitney's field (written out
  // here); the average-stress ratio is a0 over its integral from R to R + a0 (trapezoids, 20,000
  // of them); both tend to 1 / Kt_inf at the edge and to 1 far from it.
  for (double kt : {3.0, 3.86, 6.0}) {
    CAPTURE(kt);
    const double radius = 1.5e-3;
    auto field = [&](double x) {
      const double xi = radius / x, x2 = xi * xi, x4 = x2 * x2, x6 = x4 * x2, x8 = x4 * x4;
      return 1 + x2 / 2 + 1.5 * x4 - (kt - 3) * (5 * x6 - 7 * x8) / 2;
    };
    for (double distance : {0.2e-3, 1e-3, 3.8e-3}) {
      CAPTURE(distance);
      CHECK(point_stress_notched_ratio(kt, radius, distance) ==
            doctest::Approx(1 / field(radius + distance)).epsilon(1e-12));
      const int n = 20000;
      double integral = 0;
      for (int k = 0; k < n; ++k) {
        const double a = radius + distance * k / n, b = radius + distance * (k + 1) / n;
        integral += 0.5 * (field(a) + field(b)) * (b - a);
      }
      CHECK(average_stress_notched_ratio(kt, radius, distance) ==
            doctest::Approx(distance / integral).epsilon(1e-7));
    }
    CHECK(point_stress_notched_ratio(kt, radius, 1e-12) == doctest::Approx(1 / kt).epsilon(1e-6));
    CHECK(average_stress_notched_ratio(kt, radius, 1e-12) == doctest::Approx(1 / kt).epsilon(1e-6));
    CHECK(point_stress_notched_ratio(kt, radius, 1e3) == doctest::Approx(1).epsilon(1e-6));
    CHECK(average_stress_notched_ratio(kt, radius, 1e3) == doctest::Approx(1).epsilon(1e-5));
  }
  CHECK_THROWS_WITH_AS(point_stress_notched_ratio(3, 1e-3, 0), doctest::Contains("distance"),
                       Error);
  CHECK_THROWS_WITH_AS(average_stress_notched_ratio(0.5, 1e-3, 1e-3),
                       doctest::Contains("Kt_inf >= 1"), Error);
}

namespace {

// The first break of the notched plate of the 30 x 18 mm [0/90/0] plate (0.5 mm plies, the
// paper's interface stiffness) with a 3 mm hole (D/W = 1/6) of `particle` diameters: at the
// hole's edge, in the 90° ply, at a gross stress above the closed form (the particles resolve the
// concentration coarsely) by the relative error it returns.
double first_failure_error(double particle) {
  const Material m = load_material("eglass-my750");
  const double width = 18e-3, diameter = 3e-3, h = 1.5e-3;
  const StrengthSettings s = notched_plate(width, diameter, particle);
  const StrengthResult r = StrengthTest(s).run();
  REQUIRE(!r.breaks.empty());
  const BondBreak& first = r.breaks.front();
  // At the hole's edge: its contact point within 1.5 particle diameters of the circle, and on
  // the ligament side (|y - yc| > |x - xc|): the hoop stress peaks where the hole crosses the y
  // axis.
  const Eigen::Vector2d offset = first.position.head<2>() - r.hole_centre;
  CHECK(offset.norm() - 0.5 * diameter < 1.5 * particle);
  CHECK(std::abs(offset.y()) > std::abs(offset.x()));
  // In the 90° ply, whose transverse strength YT goes first (CLT).
  CHECK(r.model->particles.ply(r.model->bonds.first(first.bond)) == 1);
  // The gross stress of the first break: the grip force over the plate's nominal section; the
  // uniform plate first fails as the calibrated bulk does (no edges, no scatter).
  const double gross = r.stress[1] * r.cross_section / (width * h);
  const double expected = r.model_first_failure / kt_of_090_plate(m, diameter, width);
  const double error = gross / expected - 1;
  MESSAGE(
      fmt::format("{} mm particles: first failure {:.2f} MPa, unnotched / Kt {:.2f} MPa "
                  "({:+.1f}%)",
                  particle * 1e3, gross * 1e-6, expected * 1e-6, 100 * error));
  CHECK(error > 0);  // the discrete hole concentrates less than the continuum
  return error;
}

}  // namespace

// Measured on this plate (docs/experiments.md, "Notched strength"): +74% at 1 mm particles
// (D = 3 d), +44% at 0.5 mm, +28% at 0.375 mm, +8% at 0.25 mm (D = 12 d). The particles resolve
// the hole's stress gradient, which decays over about a radius, coarsely, and the lattice's
// staircase edge carries less than the continuum's peak. The error depends on the particle size,
// not on D/d alone: on a 15 x 9 mm plate with a 1.5 mm hole and the same 0.5 mm plies it stays at
// +24% to +26% from 0.375 to 0.1875 mm particles (the interface's shear-lag length,
// sqrt(E2 t / K_s) ~ 0.9 mm, is not small against that hole). Tolerances: each measured error
// plus about a quarter of it.
TEST_CASE(
    "a notched [0/90/0] plate first breaks at the hole's edge, nearer Kt as particles shrink") {
  const double coarse = first_failure_error(0.5e-3);
  const double fine = first_failure_error(0.375e-3);
  CHECK(coarse < 0.55);
  CHECK(fine < 0.35);
  CHECK(fine < coarse);
}

TEST_CASE("slow: the notched plate at 0.25 mm particles first fails within 10% of unnotched / Kt") {
  CHECK(first_failure_error(0.25e-3) < 0.10);
}

TEST_CASE("plydem run hole_failure.toml --quick: notched below unnotched, Kt, maps, figures") {
  const fs::path dir = fresh_directory("hole_failure_run");
  RunOptions options;
  options.config = config_path();
  options.out_dir = dir;
  options.quick = true;
  run_experiment(options);
  const std::map<std::string, double> rows = rows_of(dir / "results.csv");
  for (const char* key :
       {"notched|strength gross|dem square", "notched|strength net section|dem square",
        "unnotched|strength gross|dem square", "notched|first failure gross stress|dem square",
        "unnotched|first failure gross stress|dem square",
        "notched|first failure gross stress|unnotched dem / Kt", "notched|Kt|lekhnitskii heywood",
        "notched|notched to unnotched strength|dem square", "notched|notched_ratio|dem square",
        "notched|notched_ratio|point stress whitney-nuismer",
        "notched|notched_ratio|average stress whitney-nuismer", "notched|notched_ratio|net section",
        "notched|first failure distance from hole edge|dem square",
        "notched|broken bonds at final|dem square"}) {
    INFO(key);
    REQUIRE(rows.count(key) == 1);
  }
  // The quick plate: 6 mm wide, a 1 mm hole, 0.5 mm particles.
  const double kt = kt_of_090_plate(load_material("eglass-my750"), 1e-3, 6e-3);
  CHECK(rows.at("notched|Kt|lekhnitskii heywood") == doctest::Approx(kt).epsilon(1e-9));
  CHECK(rows.at("notched|first failure gross stress|unnotched dem / Kt") ==
        doctest::Approx(rows.at("unnotched|first failure gross stress|dem square") / kt)
            .epsilon(1e-9));
  const double notched = rows.at("notched|strength gross|dem square");
  const double unnotched = rows.at("unnotched|strength gross|dem square");
  CHECK(notched < unnotched);
  CHECK(rows.at("notched|notched to unnotched strength|dem square") ==
        doctest::Approx(notched / unnotched).epsilon(1e-9));
  CHECK(rows.at("notched|notched_ratio|dem square") ==
        rows.at("notched|notched to unnotched strength|dem square"));
  // The references: Kt_inf = Kt / Heywood's factor, d0 = 1 mm and a0 = 3.8 mm (the defaults).
  const double fwc = heywood_finite_width_factor(1e-3, 6e-3);
  CHECK(rows.at("notched|notched_ratio|point stress whitney-nuismer") ==
        doctest::Approx(point_stress_notched_ratio(kt / fwc, 0.5e-3, 1e-3) / fwc).epsilon(1e-9));
  CHECK(
      rows.at("notched|notched_ratio|average stress whitney-nuismer") ==
      doctest::Approx(average_stress_notched_ratio(kt / fwc, 0.5e-3, 3.8e-3) / fwc).epsilon(1e-9));
  CHECK(rows.at("notched|notched_ratio|net section") == doctest::Approx(5.0 / 6.0).epsilon(1e-9));
  CHECK(rows.at("notched|strength net section|dem square") ==
        doctest::Approx(notched / (1 - 1.0 / 6.0)).epsilon(1e-9));
  // The notch breaks first, at its edge (within 1.5 particles), below the unnotched plate.
  CHECK(rows.at("notched|first failure distance from hole edge|dem square") < 0.75);
  CHECK(rows.at("notched|first failure gross stress|dem square") <
        rows.at("unnotched|first failure gross stress|dem square"));
  // Damage grows along the path: the maps' broken bonds never fall.
  const double half = rows.at("notched|broken bonds at 0.5 of peak|dem square");
  const double peak = rows.at("notched|broken bonds at 1 of peak|dem square");
  const double final_state = rows.at("notched|broken bonds at final|dem square");
  CHECK(half <= peak);
  CHECK(peak < final_state);
  // Both plates followed to final failure (stop_fraction 0.02: the grip force and the plate's
  // stiffness below 2% of theirs), not stopped by max_events nor at half the peak.
  const std::string report = file_text(dir / "report.md");
  std::size_t failed = 0;
  for (std::size_t at = report.find("events (stopped: failed)"); at != std::string::npos;
       at = report.find("events (stopped: failed)", at + 1))
    ++failed;
  CHECK(failed == 2);
  for (const char* plate : {"notched", "unnotched"}) {
    INFO(plate);
    CHECK(rows.at(fmt::format("{}|final stiffness over intact|dem square", plate)) < 0.02);
  }
  for (const char* file :
       {"report.md", "hole_failure_notched_cracks.csv", "vtu/hole_failure_notched.pvd",
        "vtu/hole_failure_unnotched.pvd", "vtu/hole_failure_damage_maps.pvd"}) {
    INFO(file);
    CHECK(fs::exists(dir / file));
  }
  if (!gnuplot_availability().available) {
    skip("gnuplot is not installed: the figures are not drawn");
    return;
  }
  for (const char* file :
       {"hole_failure_load_displacement.png", "hole_failure_damage_0_5_of_peak.png",
        "hole_failure_damage_1_of_peak.png", "hole_failure_damage_final.png"}) {
    INFO(file);
    CHECK(fs::exists(dir / file));
  }
}

namespace {

// `plydem run` of a hole_failure config of the shipped plate (10 x 6 mm [0/90/0], 0.5 mm plies, a
// 1 mm hole, the paper's interface stiffness, stopped below half the peak) failing at the material
// point (Puck) at each of `diameters_mm`; its results.csv rows and report.
struct SizesRun {
  std::map<std::string, double> rows;
  std::string report;
};

SizesRun run_at_sizes(const std::string& diameters_mm, const std::string& label) {
  const fs::path dir = fresh_directory(label);
  std::ofstream(dir / "sizes.toml") << "experiment = \"hole_failure\"\n"
                                       "failure_criterion = \"puck\"\n"
                                       "[coupon]\nlength_mm = 10\nwidth_mm = 6\n"
                                       "hole_diameter_mm = 1\ndiameters_mm = "
                                    << diameters_mm
                                    << "\n[interface]\nnormal = 1e14\nshear = 1e13\n"
                                       "[events]\nstop_fraction = 0.5\n"
                                       "[output]\nvtu_series = false\n";
  RunOptions options;
  options.config = dir / "sizes.toml";
  options.out_dir = dir / "out";
  run_experiment(options);
  return {rows_of(dir / "out" / "results.csv"), file_text(dir / "out" / "report.md")};
}

// The notched ratio of the finest size (source `dem square`) over the coarser one's, less one.
double notched_ratio_change(const SizesRun& run, const std::string& coarser) {
  const double fine = run.rows.at("notched|notched_ratio|dem square");
  return fine / run.rows.at(fmt::format("notched|notched_ratio|dem d={}", coarser)) - 1;
}

}  // namespace

// Both plates at each particle size: the coarser's rows as `dem d=<mm>`, the finest's as the
// report's, the change between them as its own row and in the particle-size table. A coarse pair
// (the hole 1.25 and 1.4 particles across) keeps it quick for the sanitizer build.
TEST_CASE("hole_failure at two particle sizes: rows per size and the particle-size table") {
  const SizesRun run = run_at_sizes("[0.7, 0.8]", "hole_failure_sizes");
  for (const char* key :
       {"notched|notched_ratio|dem d=0.8", "notched|strength gross|dem d=0.8",
        "unnotched|strength gross|dem d=0.8", "notched|particles|dem d=0.8",
        "notched|first failure gross stress|dem d=0.8", "notched|notched_ratio|dem square",
        "notched|notched_ratio change between the two finest|dem"}) {
    INFO(key);
    REQUIRE(run.rows.count(key) == 1);
  }
  CHECK(run.rows.count("notched|notched_ratio|dem d=0.7") == 0);  // the finest: `dem square`
  CHECK(run.rows.at("notched|notched_ratio|dem d=0.8") ==
        doctest::Approx(run.rows.at("notched|strength gross|dem d=0.8") /
                        run.rows.at("unnotched|strength gross|dem d=0.8"))
            .epsilon(1e-9));
  CHECK(run.rows.at("notched|notched_ratio change between the two finest|dem") ==
        doctest::Approx(notched_ratio_change(run, "0.8")).epsilon(1e-9));
  CHECK(run.rows.at("notched|particles|dem d=0.8") < run.rows.at("notched|particles|dem square"));
  CHECK(run.report.find("## Particle size") != std::string::npos);
}

// At the material point the notched strength converges as the particles shrink (issue 33's
// target: less than 10% between the two finest sizes). Measured on this plate: 0.863 at 0.5 mm,
// 0.828 at 0.35 mm (-4.1%), 0.813 at 0.25 mm (-1.8%), beside Whitney and Nuismer's average
// stress 0.863 (a0 = 3.8 mm).
TEST_CASE("slow: hole_failure at the material point: the notched ratio within 10% at 0.5, 0.35") {
  const SizesRun run = run_at_sizes("[0.5, 0.35]", "hole_failure_sizes_slow");
  const double change = notched_ratio_change(run, "0.5");
  MESSAGE(fmt::format("notched ratio {:.3f} at 0.5 mm, {:.3f} at 0.35 mm ({:+.1f}%)",
                      run.rows.at("notched|notched_ratio|dem d=0.5"),
                      run.rows.at("notched|notched_ratio|dem square"), 100 * change));
  CHECK(std::abs(change) < 0.10);
  CHECK(run.report.find("**met**") != std::string::npos);
  // Within 10% of the average-stress criterion (the DEM's fracture process zone is of the
  // particles, Whitney and Nuismer's a0 of their carbon/epoxy plates: agreement, not identity).
  CHECK(run.rows.at("notched|notched_ratio|dem square") ==
        doctest::Approx(run.rows.at("notched|notched_ratio|average stress whitney-nuismer"))
            .epsilon(0.10));
}

TEST_CASE("a hole_failure config with a bad hole or map fraction is refused, naming it") {
  const fs::path dir = fresh_directory("hole_failure_bad");
  auto refused = [&](const std::string& body, const std::string& message) {
    INFO(body);
    std::ofstream(dir / "bad.toml") << "experiment = \"hole_failure\"\n" << body;
    RunOptions options;
    options.config = dir / "bad.toml";
    options.out_dir = dir / "out";
    CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains(message.c_str()), Error);
  };
  refused("[coupon]\nhole_diameter_mm = 0\n", "coupon.hole_diameter_mm must be positive");
  refused("[coupon]\nhole_diameter_mm = 33\n", "the hole must be narrower than 0.9 W (32.4 mm)");
  refused("[coupon]\nhole_diameter_mm = 0.5\n", "narrower than one particle (1.2 mm)");
  refused("[maps]\nload_fractions = [0.5, 1.2]\n", "maps.load_fractions must lie in (0, 1]");
  refused("[coupon]\nhole_diameter = 3\n", "unknown key 'coupon.hole_diameter'");
  refused("[coupon]\ndiameter_mm = 1\ndiameters_mm = [1.2, 1]\n",
          "give coupon.diameters_mm or coupon.diameter_mm, not both");
  refused("[coupon]\ndiameters_mm = [1.2, 1.2]\n", "names a diameter twice");
  refused("[coupon]\ndiameters_mm = [1.2, 6]\n", "particle diameter 6 mm");
}
