// `plydem run experiments/crossply.toml --quick`: a cross-ply pulled to failure with strength
// scatter writes its table, the closed forms beside the DEM, the cracks and the stiffness figure.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/transverse_cracking.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "strategies/laminate.hpp"
#include "support/results_csv.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using namespace plydem::test;
namespace fs = std::filesystem;

namespace {

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// results.csv as "case|quantity|source" -> value.
std::map<std::string, double> rows_of(const fs::path& csv) {
  std::map<std::string, double> rows;
  for (const std::vector<std::string>& f : results_csv_rows(csv))
    rows[fmt::format("{}|{}|{}", f[1], f[2], f[3])] = std::stod(f[4]);
  return rows;
}

// The start of a crossply config failing at the material point with strength scatter: E-glass,
// square, Puck, Weibull m = 10, seed 1.
const char* const kMaterialPointConfig =
    "experiment = \"crossply\"\nmaterial = \"eglass-my750\"\nstrategy = \"square\"\n"
    "failure_criterion = \"puck\"\nweibull_modulus = 10\nseed = 1\n";

}  // namespace

TEST_CASE("plydem run crossply.toml --quick: first-ply failure, cracks and stiffness") {
  const fs::path dir = fresh_directory("crossply");
  RunOptions options;
  options.config = fs::path(PLYDEM_TEST_DATA_DIR) / ".." / ".." / "experiments" / "crossply.toml";
  options.out_dir = dir;
  options.quick = true;
  run_experiment(options);
  const std::map<std::string, double> rows = rows_of(dir / "results.csv");
  const Material m = load_material("eglass-my750");
  // The closed forms as the run states them, computed here: ply discount of [0/90]s (b = d = t).
  REQUIRE(rows.count("[0/90]s|stiffness ratio|ply discount") == 1);
  CHECK(rows.at("[0/90]s|stiffness ratio|ply discount") ==
        doctest::Approx(m.E1 / (m.E1 + m.E2)).epsilon(1e-9));
  REQUIRE(rows.count("[0/90]s|crack density 90 at peak|dem square") == 1);
  const double density = rows.at("[0/90]s|crack density 90 at peak|dem square");
  CHECK(rows.at("[0/90]s|stiffness ratio at peak|shear lag") ==
        doctest::Approx(shear_lag_stiffness_ratio(m, 0.2e-3, 0.2e-3, density * 1e3)).epsilon(1e-9));
  // Hashin's variational bound at the same density, between the ply discount and the intact.
  REQUIRE(rows.count("[0/90]s|stiffness ratio at peak|hashin variational") == 1);
  const double hashin = rows.at("[0/90]s|stiffness ratio at peak|hashin variational");
  CHECK(hashin ==
        doctest::Approx(hashin_stiffness_ratio(m, 0.2e-3, 0.2e-3, density * 1e3)).epsilon(1e-9));
  CHECK(hashin >= m.E1 / (m.E1 + m.E2));
  CHECK(hashin < 1.0);
  // The cracked laminate is softer than the intact one and stiffer than its 0° plies alone.
  const double ratio = rows.at("[0/90]s|stiffness ratio at peak|dem square");
  CHECK(ratio < 1.0);
  CHECK(ratio > m.E1 / (m.E1 + m.E2) - 0.05);
  CHECK(rows.count("[0/90]s|first ply failure stress|clt max-stress") == 1);
  CHECK(rows.count("[0/90]s|cracks ply 2|dem square") == 1);  // the 90° plies crack
  // Issue 33's names. The 90° plies' stress per unit laminate stress, written out for [0/90]s of
  // equal plies (a11 = (Q11 + Q22) / 2, a12 = Q12 per unit thickness; the 90° ply's x stiffness
  // is Q22): k90 = (Q22 a11 - Q12 a12) / (a11^2 - a12^2).
  const double q = 1 / (1 - m.nu12 * m.nu21());
  const double q11 = m.E1 * q, q22 = m.E2 * q, q12 = m.nu12 * q22;
  const double a11 = (q11 + q22) / 2, a12 = q12;
  const double k90 = (q22 * a11 - q12 * a12) / (a11 * a11 - a12 * a12);
  CHECK(rows.at("[0/90]s|onset_stress|clt yt") * 1e6 ==
        doctest::Approx(m.strength.YT / k90).epsilon(1e-9));
  // The in-situ strength of the embedded 0.4 mm 90° layer with G_Ic = 200 J/m^2 (the config's
  // references.G_Ic_J_m2): thin, sqrt(8 G / (pi t Lambda22)).
  const double lambda22 = 2 * (1 / m.E2 - m.nu21() * m.nu21() / m.E1);
  const double in_situ = std::sqrt(8 * 200 / (std::numbers::pi * 0.4e-3 * lambda22));
  CHECK(in_situ > 1.12 * std::sqrt(2.0) * m.strength.YT);
  CHECK(rows.at("[0/90]s|onset_stress|in-situ camanho") * 1e6 ==
        doctest::Approx(in_situ / k90).epsilon(1e-9));
  const double ex = 1 / (a11 / (a11 * a11 - a12 * a12));
  CHECK(rows.at("[0/90]s|onset_strain|in-situ camanho") / 100 ==
        doctest::Approx(in_situ / k90 / ex).epsilon(1e-9));
  REQUIRE(rows.count("[0/90]s|onset_stress|energy isolated crack") == 1);
  // The crack-multiplication band at the DEM's strength: 2/L* is twice 1/L*.
  CHECK(rows.at("[0/90]s|saturation_crack_density|crack multiplication 2/L*") ==
        doctest::Approx(2 * rows.at("[0/90]s|saturation_crack_density|crack multiplication 1/L*")));
  CHECK(rows.at("[0/90]s|saturation_crack_density|dem") == doctest::Approx(density));
  CHECK(rows.at("[0/90]s|strength|dem") == rows.at("[0/90]s|strength|dem square"));
  CHECK(rows.at("[0/90]s|strength|fibre failure bound") * 1e6 ==
        doctest::Approx(m.strength.XT / 2).epsilon(1e-12));
  // Cure stresses (thermal.delta_T = -100 K): CLT's written out for [0/90]s of equal plies. By
  // symmetry eps0_x = eps0_y = e, with (a11 + a12) e = ((Q11 + Q12) alpha1 + (Q12 + Q22) alpha2)
  // dT / 2 (the thermal force resultant per unit thickness), and the 90° plies' sigma2 is
  // Q22 (e - alpha2 dT) + Q12 (e - alpha1 dT); the DEM's on a 4 mm square coupon within 2%.
  const double dt = -100;
  const double e = ((q11 + q12) * m.alpha1 + (q12 + q22) * m.alpha2) * dt / (2 * (a11 + a12));
  const double cure90 = q22 * (e - m.alpha2 * dt) + q12 * (e - m.alpha1 * dt);
  CHECK(rows.at("[0/90]s|cure_stress_90|clt") * 1e6 == doctest::Approx(cure90).epsilon(1e-9));
  CHECK(rows.at("[0/90]s|cure_stress_0|clt") ==
        doctest::Approx(-rows.at("[0/90]s|cure_stress_90|clt")));
  CHECK(rows.at("[0/90]s|cure_stress_90|dem") ==
        doctest::Approx(rows.at("[0/90]s|cure_stress_90|clt")).epsilon(0.02));
  CHECK(rows.at("[0/90]s|cure_stress_0|dem") ==
        doctest::Approx(rows.at("[0/90]s|cure_stress_0|clt")).epsilon(0.02));
  CHECK(rows.at("[0/90]s|onset_stress|clt yt with cure") * 1e6 ==
        doctest::Approx((m.strength.YT - cure90) / k90).epsilon(1e-9));
  REQUIRE(rows.count("[0/90]s|onset_stress|dem") == 1);
  CHECK(rows.at("[0/90]s|onset_stress|dem") <= rows.at("[0/90]s|strength|dem"));
  // The same laminate pulled from its cured state (same strengths): its first crack comes earlier
  // by about CLT's cure sigma2 over k90 (measured 0.92 of it: the weakest site lies at a free
  // edge, where the cure's and the load's stresses differ from CLT's).
  REQUIRE(rows.count("[0/90]s|onset_stress|dem with cure") == 1);
  const double drop =
      rows.at("[0/90]s|onset_stress|dem") - rows.at("[0/90]s|onset_stress|dem with cure");
  MESSAGE("cure lowers the DEM's onset by " << drop << " MPa, CLT's " << cure90 / k90 * 1e-6);
  CHECK(drop * 1e6 * k90 / cure90 > 0.8);
  CHECK(drop * 1e6 * k90 / cure90 < 1.2);
  CHECK(rows.count("[0/90]s|strength|dem with cure") == 1);
  CHECK(rows.count("[0/90]s|saturation_crack_density|dem with cure") == 1);
  const std::string report = read(dir / "report.md");
  CHECK(report.find("## Summary") != std::string::npos);
  CHECK(report.find("## Transverse cracking against fracture mechanics") != std::string::npos);
  CHECK(fs::exists(dir / "plots" / "crossply_crack_density.dat"));
  CHECK(report.find("| [0/90]s |") != std::string::npos);
  CHECK(fs::exists(dir / "crossply__0_90_s_cracks.csv"));
  // Crack maps per ply at maps.load_fractions (default 0.1, 0.25, 0.5, 1) of the peak and the
  // final state: damage only grows along the path, and the maps' VTU series is written.
  double broken = 0;
  for (const char* map : {"0.1 of peak", "0.25 of peak", "0.5 of peak", "1 of peak", "final"}) {
    const std::string key = fmt::format("[0/90]s|broken bonds at {}|dem square", map);
    INFO(key);
    REQUIRE(rows.count(key) == 1);
    CHECK(rows.at(key) >= broken);
    broken = rows.at(key);
  }
  CHECK(broken > 0);
  CHECK(report.find("### [0/90]s: crack maps per ply") != std::string::npos);
  CHECK(fs::exists(dir / "vtu" / "crossply__0_90_s_damage_maps.pvd"));
  // Crack planes against strain: the header, and densities that never fall.
  const std::string planes = read(dir / "crossply__0_90_s_crack_planes.csv");
  CHECK(planes.rfind("event,strain,stress_MPa,crack_planes_per_mm,traction_free_per_mm,E_over_E0\n",
                     0) == 0);
  {
    std::istringstream lines(planes);
    std::string line;
    std::getline(lines, line);
    double previous = 0;
    int rows = 0;
    while (std::getline(lines, line)) {
      std::vector<double> v;
      std::istringstream fields(line);
      for (std::string f; std::getline(fields, f, ',');) v.push_back(std::stod(f));
      REQUIRE(v.size() == 6);
      CHECK(v[3] >= previous);
      CHECK(v[4] <= v[3]);
      previous = v[3];
      ++rows;
    }
    CHECK(rows > 10);
  }
  // CalculiX of the same laminate with the peak's transverse cracks cut in: softer than intact,
  // stiffer than the ply-discount limit (the cracks are a finite number, not every section).
  REQUIRE(rows.count("[0/90]s|stiffness ratio at peak between grips|dem square") == 1);
  // With the peak's cracks only: read no later than the peak, so no softer (a broken bond only
  // takes stiffness away), and no bond broken off the counted planes is hidden.
  const std::string same =
      "[0/90]s|stiffness ratio with the peak's cracks between grips|dem square";
  REQUIRE(rows.count(same) == 1);
  CHECK(rows.at(same) >= rows.at("[0/90]s|stiffness ratio at peak between grips|dem square"));
  CHECK(rows.at(same) < 1.0);
  const std::string off =
      "[0/90]s|broken bonds off the crack planes with the peak's cracks|dem square";
  REQUIRE(rows.count(off) == 1);
  CHECK(rows.at(off) >= 0);
  if (calculix_availability().available) {
    REQUIRE(rows.count("[0/90]s|cracks cut in calculix|calculix same cracks") == 1);
    CHECK(rows.at("[0/90]s|cracks cut in calculix|calculix same cracks") >= 1);
    const double fem =
        rows.at("[0/90]s|stiffness ratio at peak between grips|calculix same cracks");
    CHECK(fem < 1.0);
    CHECK(fem > m.E1 / (m.E1 + m.E2));
    CHECK(report.find("E/E0 CalculiX, same cracks") != std::string::npos);
    // The mesh twice as coarse is stiffer (the crack tips' error), and the extrapolation to a
    // fine mesh, 2 R(h) - R(2h), softer than the config's mesh.
    const double coarse =
        rows.at("[0/90]s|stiffness ratio at peak between grips|calculix same cracks coarse mesh");
    const double extrapolated =
        rows.at("[0/90]s|stiffness ratio at peak between grips|calculix same cracks extrapolated");
    CHECK(coarse > fem);
    CHECK(extrapolated == doctest::Approx(2 * fem - coarse).epsilon(1e-9));
  } else {
    CHECK(report.find("CalculiX not run") != std::string::npos);
  }
}

TEST_CASE("plydem run crossply at the material point: traction-free cracks, 0 deg to the end") {
  // failure_criterion = "puck": the 90 deg plies' sites crack in straight, traction-free
  // transverse cracks (bond by bond every column of the quick coupon cracked: 10 per mm, none
  // traction-free), and the 0 deg plies carry the laminate on towards the ply-discount bound of
  // last-ply failure, XT / 2 for [0/90]s of equal plies (measured 0.87 of it; bond by bond 0.55).
  const fs::path dir = fresh_directory("crossply_material_point");
  std::ofstream(dir / "mp.toml")
      << kMaterialPointConfig
      << "[coupon]\nlength_mm = 2\nwidth_mm = 0.5\nthickness_mm = 0.2\ndiameter_mm = 0.1\n"
         "[interface]\ntransverse_shear = true\n[quick]\nlayups = [\"[0/90]s\"]\n";
  RunOptions options;
  options.config = dir / "mp.toml";
  options.out_dir = dir / "out";
  options.quick = true;
  run_experiment(options);
  const std::map<std::string, double> rows = rows_of(dir / "out" / "results.csv");
  const Material m = load_material("eglass-my750");
  const double density = rows.at("[0/90]s|crack density 90 at peak|dem square");
  const double free = rows.at("[0/90]s|traction-free crack density 90 at peak|dem square");
  const double strength = rows.at("[0/90]s|strength|dem square");
  MESSAGE("material point: " << density << " cracks/mm, " << free
                             << " traction-free; strength / (XT / 2) "
                             << (strength * 1e6 / (0.5 * m.strength.XT)));
  CHECK(density > 0);
  // Fewer cracks than every column (0.1 mm particles: 10 per mm): the bound as it was when the
  // density was counted over 1.5 mm (under 0.6 of its 15 gaps: at most 8 cracks), over the free
  // length between the strength test's grips, 1.3 mm (the 2 mm coupon less four columns of grip
  // at each end; measured 8 cracks, 6.2 per mm).
  CHECK(density * 1.3 < 0.6 * 10 * 1.5);
  CHECK(free == doctest::Approx(density));
  CHECK(strength * 1e6 > 0.8 * 0.5 * m.strength.XT);
}

TEST_CASE(
    "the coupled criterion: the 90 deg layer's first crack releases G_Ic, at the in-situ "
    "strength") {
  // A [0/90]s coupon without scatter, 2 x 0.5 mm, 0.2 mm plies, 0.1 mm particles, Puck at the
  // material point, G_matrix = 200 J/m^2, stopped after its first event: the crack through the
  // 0.4 mm 90 deg layer opens at once (its 2 x 5 sites), when opening it at fixed grips releases
  // G_Ic w (2t) -- the released energy the events solver measures after the event (its updated
  // factor) against the area's fracture energy -- and at the laminate stress where the thin
  // embedded layer's in-situ strength sqrt(8 G / (pi t Lambda22)) (Camanho et al. 2006, written
  // out here) loads its 90 deg plies.
  StrengthSettings s;
  s.coupon.material = load_material("eglass-my750");
  const double g = 200;
  s.coupon.material.strength.G_matrix = g;
  s.strategy = "square";
  s.layup = parse_layup("[0/90]s");
  s.coupon.length = 2e-3;
  s.coupon.width = 0.5e-3;
  s.coupon.thickness = 0.2e-3;
  s.coupon.particle_diameter = 0.1e-3;
  s.interface.transverse_shear = true;
  s.failure_criterion = PlyFailureModel::kPuck;
  s.weibull_modulus = 0;
  s.coupled_criterion = true;
  s.events.max_events = 1;
  const StrengthResult r = StrengthTest(s).run();
  REQUIRE(r.events == 1);
  const double area = s.coupon.width * 2 * s.coupon.thickness;
  CHECK(r.crack_area == doctest::Approx(area).epsilon(1e-9));
  CHECK(r.crack_fracture_energy == doctest::Approx(g * area).epsilon(1e-9));
  CHECK(r.dissipated_energy == doctest::Approx(g * area).epsilon(1e-6));
  const Material& m = s.coupon.material;
  const double q = 1 / (1 - m.nu12 * m.nu21());
  const double q11 = m.E1 * q, q22 = m.E2 * q, q12 = m.nu12 * q22;
  const double a11 = (q11 + q22) / 2, a12 = q12;
  const double k90 = (q22 * a11 - q12 * a12) / (a11 * a11 - a12 * a12);
  const double lambda22 = 2 * (1 / m.E2 - m.nu21() * m.nu21() / m.E1);
  const double in_situ = std::sqrt(8 * g / (std::numbers::pi * 2 * s.coupon.thickness * lambda22));
  MESSAGE("first crack at " << r.first_failure_stress * 1e-6 << " MPa, in-situ "
                            << in_situ / k90 * 1e-6 << " MPa, YT " << m.strength.YT / k90 * 1e-6);
  CHECK(r.first_failure_stress == doctest::Approx(in_situ / k90).epsilon(0.1));

  // Refused: with softening (the coupled criterion's cracks open brittle) and without G_matrix.
  StrengthSettings soft = s;
  soft.strength_options.softening = true;
  soft.coupon.material.strength.G_fibre = 12000;
  CHECK_THROWS_WITH_AS(StrengthTest(soft).run(), doctest::Contains("coupled criterion"), Error);
  StrengthSettings no_energy = s;
  no_energy.coupon.material.strength.G_matrix = 0;
  CHECK_THROWS_WITH_AS(StrengthTest(no_energy).run(), doctest::Contains("gives no G_matrix"),
                       Error);
}

TEST_CASE("a crossply config whose layup is not a cross-ply is refused, naming it") {
  const fs::path dir = fresh_directory("crossply_bad");
  std::ofstream(dir / "bad.toml") << "experiment = \"crossply\"\nlayups = [\"[0/45]s\"]\n";
  RunOptions options;
  options.config = dir / "bad.toml";
  options.out_dir = dir / "out";
  CHECK_THROWS_WITH_AS(run_experiment(options),
                       doctest::Contains("'[0/45]s' is not a cross-ply [0_m/90_n]s"), Error);
  // The coupled criterion without a fracture energy (the built-in material gives no G_matrix).
  std::ofstream(dir / "no_energy.toml") << kMaterialPointConfig << "coupled_criterion = true\n";
  options.config = dir / "no_energy.toml";
  CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains("give references.G_Ic_J_m2"),
                       Error);
}

TEST_CASE("plydem run crossply at two particle sizes: the finest reports, the coarser as dem d=") {
  const fs::path dir = fresh_directory("crossply_sizes");
  std::ofstream(dir / "sizes.toml")
      << kMaterialPointConfig
      << "layups = [\"[0/90]s\"]\n"
         "[coupon]\nlength_mm = 1.6\nwidth_mm = 0.4\nthickness_mm = 0.2\n"
         "diameters_mm = [0.05, 0.1]\n";
  RunOptions options;
  options.config = dir / "sizes.toml";
  options.out_dir = dir / "out";
  run_experiment(options);
  const std::map<std::string, double> rows = rows_of(dir / "out" / "results.csv");
  for (const char* quantity :
       {"onset_stress", "onset_strain", "saturation_crack_density", "strength"}) {
    CHECK(rows.count(fmt::format("[0/90]s|{}|dem", quantity)) == 1);
    CHECK(rows.count(fmt::format("[0/90]s|{}|dem d=0.1", quantity)) == 1);
    CHECK(rows.count(fmt::format("[0/90]s|{}|dem d=0.05", quantity)) == 0);
  }
  // The report is the finest's: its strength is the one the strength test's rows give.
  CHECK(rows.at("[0/90]s|strength|dem") == rows.at("[0/90]s|strength|dem square"));
  const std::string report = read(dir / "out" / "report.md");
  CHECK(report.find("## Particle size") != std::string::npos);
  CHECK(report.find("0.05 mm particles") != std::string::npos);

  std::ofstream(dir / "both.toml") << "experiment = \"crossply\"\nlayups = [\"[0/90]s\"]\n"
                                      "[coupon]\ndiameter_mm = 0.1\ndiameters_mm = [0.1, 0.05]\n";
  options.config = dir / "both.toml";
  CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains("not both"), Error);
  std::ofstream(dir / "twice.toml") << "experiment = \"crossply\"\nlayups = [\"[0/90]s\"]\n"
                                       "[coupon]\ndiameters_mm = [0.1, 0.1]\n";
  options.config = dir / "twice.toml";
  CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains("twice"), Error);
}
