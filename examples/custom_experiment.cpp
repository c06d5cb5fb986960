// An experiment kind of your own, registered from outside the library.
//
// `plydem run CONFIG.toml` finds the experiment to run by the config's `experiment` key in a
// registry of kinds (experiments/runner/experiment.hpp), as `--strategy` finds strategies. This
// program defines a kind, `sweep`, in its own file as the built-in kinds are written (a settings
// struct and three steps: parse the config, run, report), adds it to the registry in its own
// main(), and runs a config through the library's runner, which writes report.md and results.csv
// as for the paper's tables: nothing in plydem is edited or recompiled.
//
// The kind pulls one single-ply coupon per fibre angle (the static tension test) and sets its Ex
// beside the ply's CLT value. Its config (tests/data/tiny_sweep.toml):
//   experiment = "sweep"
//   material = "eglass-my750"
//   angles_deg = [0, 45, 90]
//   [coupon]
//   length_mm = 1.2
//   width_mm = 0.6
//
// Sample run:
//   build/examples/custom_experiment tests/data/tiny_sweep.toml --out results/sweep
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/run_experiment.hpp"

namespace {

// A kind is three steps over its own settings struct: parse the config, run, report.
struct SweepSettings {
  plydem::TensionSettings test;
  std::vector<double> angles_deg;
};

SweepSettings parse_sweep(const plydem::ExperimentConfig& config,
                          const plydem::ExperimentContext& context) {
  // A misspelt key is an error, not a silent default.
  config.require_known_keys({"experiment", "description", "material", "strategy", "angles_deg",
                             "coupon.length_mm", "coupon.width_mm", "coupon.diameter_mm"});
  SweepSettings s;
  s.test.strategy = config.string("strategy", "hex2d");
  s.test.coupon.material = plydem::load_material(config.string("material", "eglass-my750"));
  const double shrink = context.quick ? 0.5 : 1.0;
  s.test.coupon.length = shrink * config.number("coupon.length_mm", 2) * 1e-3;
  s.test.coupon.width = shrink * config.number("coupon.width_mm", 0.83) * 1e-3;
  s.test.coupon.particle_diameter = config.number("coupon.diameter_mm", 0.05) * 1e-3;
  s.test.measure_specimen_stiffness = false;
  s.angles_deg = config.numbers("angles_deg", {0, 45, 90});
  return s;
}

// One static tension test per angle.
std::vector<plydem::TensionResult> run_sweep(const SweepSettings& s,
                                             const plydem::ExperimentContext&) {
  std::vector<plydem::TensionResult> results;
  for (const double degrees : s.angles_deg) {
    plydem::TensionSettings test = s.test;
    test.coupon.ply_angle = degrees * std::numbers::pi / 180;
    results.push_back(plydem::TensionTest(test).run());
  }
  return results;
}

// report.md's section and results.csv's rows (the runner writes both files).
plydem::ExperimentOutput report_sweep(const SweepSettings& s,
                                      const std::vector<plydem::TensionResult>& results,
                                      const plydem::ExperimentContext&) {
  plydem::ExperimentOutput out;
  out.title = "Off-axis sweep";
  out.report_markdown = "| angle | Ex DEM [GPa] | Ex CLT [GPa] | rel. err. |\n|---|---|---|---|\n";
  for (std::size_t k = 0; k < results.size(); ++k) {
    const plydem::TensionResult& r = results[k];
    const std::string angle = fmt::format("{:g} deg", s.angles_deg[k]);
    out.report_markdown +=
        fmt::format("| {} | {:.3f} | {:.3f} | {:+.2f}% |\n", angle, r.dem.Ex * 1e-9,
                    r.theory.Ex * 1e-9, 100 * (r.dem.Ex / r.theory.Ex - 1));
    const std::string dem = "dem " + s.test.strategy;
    out.rows.push_back({"sweep", angle, "Ex", dem, r.dem.Ex * 1e-9, "GPa"});
    out.rows.push_back({"sweep", angle, "Ex", "clt", r.theory.Ex * 1e-9, "GPa"});
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string config, out_dir;
  bool quick = false;
  CLI::App app{"plydem run with a user-registered experiment kind, sweep"};
  app.add_option("config", config, "experiment config (TOML)")->required();
  app.add_option("--out", out_dir, "output folder (default results/NAME)");
  app.add_flag("--quick", quick, "smaller coupons");
  CLI11_PARSE(app, argc, argv);
  try {
    // The one line that makes the kind available to every config that names it.
    plydem::default_experiment_registry().add(
        "sweep", "Ex of single-ply coupons over fibre angles, beside CLT", parse_sweep, run_sweep,
        report_sweep);

    plydem::RunOptions options;
    options.config = config;
    options.out_dir = out_dir;
    options.quick = quick;
    const plydem::RunSummary summary = plydem::run_experiment(options);
    const std::vector<plydem::ResultRow>& rows = summary.output.rows;  // DEM, CLT per angle
    for (std::size_t i = 0; i + 1 < rows.size(); i += 2) {
      std::cout << fmt::format("sweep {}: Ex {:.3f} GPa, CLT {:.3f} GPa ({:+.2f}% vs CLT)\n",
                               rows[i].case_name, rows[i].value, rows[i + 1].value,
                               100 * (rows[i].value / rows[i + 1].value - 1));
    }
    std::cout << fmt::format("wrote {} and {} in {:.1f} s\n", summary.report.string(),
                             summary.results.string(), summary.wall_seconds);
    return 0;
  } catch (const plydem::Error& e) {
    std::cerr << "custom_experiment: error: " << e.what() << "\n";
    return 2;
  }
}
