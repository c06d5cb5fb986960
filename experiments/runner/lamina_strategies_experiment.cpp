// The kind `lamina-strategies` (the paper's Table 2, `plydem run experiments/table2.toml`): one
// lamina with every strategy the config lists: moduli from the static tension test, the fixed-cycle
// and quasi-static explicit runs' times, beside correct CLT and the paper
// (experiments/runner/paper_tables.hpp).
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/error.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/paper_tables.hpp"
#include "experiments/runner/report_text.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace {

using namespace paper_tables;

// The paper's numbers for one strategy, where the config gives them.
struct StrategyPaper {
  std::optional<Values> dem;  ///< paper.dem.NAME
  double minutes = kNaN;      ///< paper.minutes.NAME
};

// The tension command's settings this kind takes for its explicit runs (explicit.backend,
// explicit.tolerance, explicit.ramp_cycles, explicit.load_stages, explicit.max_cycles).
const SettingsSelection kExplicitKeys{
    {"backend", "tolerance", "ramp_cycles", "load_stages", "max_cycles"}, {}};

// A `lamina-strategies` config's settings.
struct LaminaStrategiesSettings {
  std::string name;  ///< the config's, naming rows and files
  bool quick = false;
  double angle_deg = 0;
  std::vector<std::string> strategies;
  long paper_cycles = 0;   ///< explicit.cycles: the paper's fixed-cycle run
  long probe_cycles = 0;   ///< explicit.quick_cycles, at most paper_cycles
  double time_limit = 0;   ///< explicit.time_limit_s
  TensionSettings base;    ///< the static test; its explicit runs change the solver
  TensionSettings staged;  ///< the staged explicit solver's tolerance, ramp, stages, cycles
  Values clt;
  std::optional<Values> experiment;  ///< paper.experiment
  std::vector<StrategyPaper> paper;  ///< per strategy
  double window = 0;                 ///< of the bond figures [m]
};

LaminaStrategiesSettings parse_lamina_strategies(const ExperimentConfig& c,
                                                 const ExperimentContext& context) {
  std::vector<std::string> known = known_keys({"strategies", "angle_deg", "explicit.cycles",
                                               "explicit.quick_cycles", "explicit.time_limit_s"});
  for (const std::string& key : config_keys(tension_settings_description(), kExplicitKeys))
    known.push_back(key);
  c.require_known_keys(known);
  const std::string name = c.name();
  const bool quick = context.quick;
  const CouponSpec coupon = coupon_from_config(c, quick);
  const double angle_deg = c.number("angle_deg", 0);
  const std::vector<std::string> strategies =
      c.strings("strategies", {"lattice", "hcp", "hex2d", "square"});
  const long paper_cycles = c.integer("explicit.cycles", 200000);
  const long probe_cycles = std::min(c.integer("explicit.quick_cycles", 500), paper_cycles);
  const double time_limit = c.number("explicit.time_limit_s", 900);
  if (probe_cycles <= 0 || paper_cycles <= 0) {
    throw Error(fmt::format("{}: explicit.cycles and explicit.quick_cycles must be positive",
                            c.path().string()));
  }
  TensionSettings base;
  base.force = context.force;
  base.coupon = coupon;
  base.coupon.ply_angle = radians(angle_deg);
  base.grips = grips_from_config(c);
  base.solver = TensionSolver::kStatic;
  // The explicit runs' settings, keys of the tension command's (explicit.*): the staged run's,
  // whose solver is explicit; its backend (cpu or cuda) the fixed-cycle run's too.
  TensionSettings staged = base;
  staged.solver = TensionSolver::kExplicit;
  read_config_settings(c, tension_settings_description(), kExplicitKeys, false, staged);
  base.explicit_settings.backend = staged.explicit_settings.backend;
  const Values clt = values_of(in_plane_constants(
      rotate_reduced_stiffness(reduced_stiffness(coupon.material), base.coupon.ply_angle)));
  LaminaStrategiesSettings settings;
  settings.name = name;
  settings.quick = quick;
  settings.angle_deg = angle_deg;
  settings.strategies = strategies;
  settings.paper_cycles = paper_cycles;
  settings.probe_cycles = probe_cycles;
  settings.time_limit = time_limit;
  settings.base = base;
  settings.staged = staged;
  settings.clt = clt;
  settings.experiment = paper_values(c, "paper.experiment");
  for (const std::string& strategy_name : strategies) {
    settings.paper.push_back({paper_values(c, fmt::format("paper.dem.{}", strategy_name)),
                              c.number(fmt::format("paper.minutes.{}", strategy_name), kNaN)});
  }
  settings.window = figure_window(c, coupon);
  return settings;
}

// One strategy's runs, as far as they got: the static tension test, the fixed-cycle explicit run
// (or its probe) and the staged explicit run to quasi-static; `refused` says why it stopped.
struct StrategyRuns {
  std::string strategy;
  bool registered = true;
  std::optional<TensionResult> tension;
  std::optional<PullResult> fixed;
  long run_cycles = 0;       ///< the fixed run's cycles: paper_cycles, or the probe's
  double fixed_seconds = 0;  ///< its time, or the time extrapolated from the probe
  std::optional<PullResult> staged;
  std::string refused;
};

StrategyRuns run_strategy(const LaminaStrategiesSettings& settings,
                          const std::string& strategy_name) {
  StrategyRuns runs;
  runs.strategy = strategy_name;
  if (!default_registry().contains(strategy_name)) {
    runs.registered = false;
    return runs;
  }
  spdlog::info("{}: strategy {}", settings.name, strategy_name);
  try {
    TensionSettings s = settings.base;
    s.strategy = strategy_name;
    const TensionResult& r = runs.tension.emplace(TensionTest(s).run());

    // The paper's fixed-cycle explicit run, one coupon along x. A probe of quick_cycles first: a
    // quick run, or a full one whose extrapolated time exceeds explicit.time_limit_s, reports the
    // extrapolation (building the coupon, timed on its own, counted once) instead of running
    // every cycle. The explicit runs pull the static test's coupon along x again (no new build).
    const long paper_cycles = settings.paper_cycles, probe_cycles = settings.probe_cycles;
    const Specimen& coupon_x = *r.coupon_x;
    TensionSettings e = s;
    e.solver = TensionSolver::kExplicit;
    e.fixed_cycles = probe_cycles;
    PullResult fixed = TensionTest(e).pull(coupon_x, e.coupon.ply_angle);
    const double build_seconds = fixed.build_seconds;
    const double extrapolated = build_seconds + (fixed.wall_seconds - build_seconds) *
                                                    static_cast<double>(paper_cycles) /
                                                    static_cast<double>(probe_cycles);
    long run_cycles = probe_cycles;
    if (!settings.quick && probe_cycles < paper_cycles && extrapolated <= settings.time_limit) {
      e.fixed_cycles = paper_cycles;
      fixed = TensionTest(e).pull(coupon_x, e.coupon.ply_angle);
      run_cycles = paper_cycles;
    }
    runs.run_cycles = run_cycles;
    runs.fixed_seconds = run_cycles == paper_cycles ? fixed.wall_seconds : extrapolated;
    runs.fixed = std::move(fixed);

    // The staged explicit solver to its quasi-static tolerance, same coupon.
    TensionSettings q = settings.staged;
    q.strategy = strategy_name;
    q.solver = TensionSolver::kExplicit;
    runs.staged = TensionTest(q).pull(coupon_x, q.coupon.ply_angle);
  } catch (const Error& e) {
    runs.refused = e.what();
  }
  return runs;
}

std::vector<StrategyRuns> run_lamina_strategies(const LaminaStrategiesSettings& settings,
                                                const ExperimentContext&) {
  std::vector<StrategyRuns> runs;
  for (const std::string& strategy_name : settings.strategies)
    runs.push_back(run_strategy(settings, strategy_name));
  return runs;
}

// The report's three tables and its curves, filled strategy by strategy.
struct Table2 {
  std::string moduli, times, explicit_moduli, figures;
  std::vector<Curve> curves;
  double max_strain = 0;
};

// One strategy's lines of the tables, its rows, curves and bond figure.
void report_strategy(const LaminaStrategiesSettings& settings, std::size_t k,
                     const StrategyRuns& runs, const std::filesystem::path& out_dir,
                     ExperimentOutput& out, Table2& table) {
  const std::string& name = settings.name;
  const std::string& strategy_name = runs.strategy;
  const Values& clt = settings.clt;
  const long paper_cycles = settings.paper_cycles;
  const StrategyPaper& paper = settings.paper[k];
  const std::string dem_source = fmt::format("dem {}", strategy_name);
  auto paper_line = [&] {
    if (!paper.dem) return;
    table.moduli += constants_line(fmt::format("paper DEM, {}", strategy_name), *paper.dem, clt);
    add_rows(out.rows, name, strategy_name, "paper dem", *paper.dem);
  };
  if (std::isfinite(paper.minutes)) {
    out.rows.push_back({name, strategy_name, "computing time", "paper dem", paper.minutes, "min"});
  }
  const std::string paper_time = number_cell(paper.minutes, "{:g}", 1);
  if (!runs.registered) {
    table.moduli += message_line(fmt::format("DEM {}", strategy_name), "not registered");
    paper_line();
    table.times += markdown_row({strategy_name, "not registered", "", "", "", "", "", paper_time});
    return;
  }
  std::string refused = runs.refused;
  double static_seconds = 0;
  if (runs.tension) {
    const TensionResult& r = *runs.tension;
    const Values dem = values_of(r.dem);
    table.moduli += constants_line(fmt::format("DEM {} (static)", strategy_name), dem, clt);
    paper_line();
    add_rows(out.rows, name, strategy_name, dem_source, dem);
    static_seconds = r.along_x.wall_seconds + r.along_y.wall_seconds;
    out.rows.push_back({name, strategy_name, "particles", dem_source,
                        static_cast<double>(r.along_x.particles), "1"});
    out.rows.push_back(
        {name, strategy_name, "bonds", dem_source, static_cast<double>(r.along_x.bonds), "1"});
    out.rows.push_back({name, strategy_name, "static tension test time (both pulls)", dem_source,
                        static_seconds, "s"});
    table.curves.push_back(pull_curve(fmt::format("{} static, along x", strategy_name), r.along_x));
  }
  if (runs.fixed) {
    const PullResult& fixed = *runs.fixed;
    const long run_cycles = runs.run_cycles;
    const std::string fixed_source =
        run_cycles == paper_cycles
            ? dem_source
            : fmt::format("dem {} extrapolated from {} cycles", strategy_name, run_cycles);
    out.rows.push_back({name, strategy_name,
                        fmt::format("time for {} explicit cycles", paper_cycles), fixed_source,
                        runs.fixed_seconds, "s"});
    if (run_cycles == paper_cycles) {
      table.explicit_moduli += markdown_row(
          {strategy_name, number_cell(fixed.modulus, "{:.3f}", 1e-9),
           percent_change(fixed.modulus, clt.Ex), number_cell(fixed.poisson, "{:.4f}", 1),
           percent_change(fixed.poisson, clt.nu_xy), fmt::format("{:.3g}", fixed.final_ratio),
           fmt::format("{:.3g}", fixed.loading_transits)});
      out.rows.push_back({name, strategy_name, "Ex (fixed cycles)",
                          fmt::format("dem {} explicit", strategy_name), fixed.modulus * 1e-9,
                          "GPa"});
      Curve history = pull_curve(
          fmt::format("{} explicit, {} cycles (second half)", strategy_name, run_cycles), fixed);
      history.points = true;
      table.curves.push_back(history);
      for (double strain : fixed.strain) table.max_strain = std::max(table.max_strain, strain);
    }
  }
  if (runs.staged) {
    const PullResult& staged = *runs.staged;
    const TensionResult& r = *runs.tension;
    out.rows.push_back({name, strategy_name, "time to quasi-static",
                        fmt::format("dem {} explicit", strategy_name), staged.wall_seconds, "s"});
    out.rows.push_back({name, strategy_name, "cycles to quasi-static",
                        fmt::format("dem {} explicit", strategy_name),
                        static_cast<double>(staged.cycles), "1"});
    table.times += markdown_row(
        {strategy_name, fmt::format("{}", r.along_x.particles), fmt::format("{}", r.along_x.bonds),
         fmt::format("{:.2f}", static_seconds),
         runs.run_cycles == paper_cycles ? fmt::format("{:.1f}", runs.fixed_seconds)
                                         : fmt::format("{:.1f} (extrapolated from {} cycles)",
                                                       runs.fixed_seconds, runs.run_cycles),
         fmt::format("{:.1f}", staged.wall_seconds), fmt::format("{}", staged.cycles), paper_time});
    // The static pull along x: solved at the target strain under the test's grips. A figure
    // that cannot be written refuses the strategy, as a failed run does.
    if (refused.empty()) {
      try {
        table.figures += write_model(
            *r.along_x.model, out_dir, file_stem(fmt::format("{}_{}", name, strategy_name)),
            fmt::format("{}: bonds coloured by normal stiffness (plan view, first {:g} mm)",
                        strategy_name, settings.window / kMetresPerMm),
            settings.window, out);
      } catch (const Error& e) {
        refused = e.what();
      }
    }
  }
  if (!refused.empty()) {
    table.moduli +=
        message_line(fmt::format("DEM {}", strategy_name), fmt::format("refused: {}", refused));
    paper_line();
    table.times += markdown_row(
        {strategy_name, fmt::format("refused: {}", refused), "", "", "", "", "", paper_time});
  }
}

ExperimentOutput report_lamina_strategies(const LaminaStrategiesSettings& settings,
                                          const std::vector<StrategyRuns>& runs,
                                          const ExperimentContext& context) {
  const std::string& name = settings.name;
  const CouponSpec& coupon = settings.base.coupon;
  const TensionSettings& base = settings.base;
  const Values& clt = settings.clt;
  const long paper_cycles = settings.paper_cycles;
  const double time_limit = settings.time_limit;
  ExperimentOutput out;
  out.title = fmt::format("Table 2: the {:g}° {} lamina with every strategy", settings.angle_deg,
                          coupon.material.name);
  Table2 table;
  table.moduli = constants_header();
  table.moduli += constants_line("CLT (correct, computed)", clt, clt);
  add_rows(out.rows, name, "lamina", "clt", clt);
  if (settings.experiment) {
    table.moduli +=
        constants_line("experiment (WWFE-II, paper Table 2)", *settings.experiment, clt);
    add_rows(out.rows, name, "lamina", "experiment", *settings.experiment);
  }
  table.times =
      markdown_row({"strategy", "particles", "bonds", "static test (s)",
                    fmt::format("{} explicit cycles (s)", paper_cycles),
                    "quasi-static explicit (s)", "quasi-static cycles", "paper time (min)"});
  table.times += "|---|---|---|---|---|---|---|---|\n";
  table.max_strain = base.target_strain;
  for (std::size_t k = 0; k < runs.size(); ++k)
    report_strategy(settings, k, runs[k], context.out_dir, out, table);
  std::vector<Curve>& curves = table.curves;
  const double max_strain = table.max_strain;
  const std::string& moduli = table.moduli;
  const std::string& times = table.times;
  const std::string& explicit_moduli = table.explicit_moduli;
  const std::string& figures = table.figures;
  curves.push_back(theory_line("CLT Ex", clt.Ex, max_strain));
  const Figure stress_strain =
      plot_curves(curves, context.out_dir, fmt::format("{}_stress_strain", name),
                  "stress-strain along x", "strain eps_x [%]", "stress sigma_x [MPa]");
  out.files.insert(out.files.end(), stress_strain.files.begin(), stress_strain.files.end());

  std::string& md = out.report_markdown;
  md += fmt::format(
      "Coupon {:g} × {:g} mm, ply thickness {:g} mm, particle diameter {:g} mm; {}.\n\n",
      coupon.length / kMetresPerMm, coupon.width / kMetresPerMm, coupon.thickness / kMetresPerMm,
      coupon.particle_diameter / kMetresPerMm, grips_sentence(base.grips));
  md +=
      "## Table 2: elastic constants\n\n"
      "DEM moduli from the static tension test (one sparse solve per pull; the state an "
      "explicit run converges to), Gxy from the specimen's membrane stiffness. Relative errors "
      "against correct CLT.\n\n";
  md += fmt::format("{}\n", moduli);
  md += fmt::format(
      "## Table 2: computing time\n\n"
      "Wall-clock seconds on this machine. `{} explicit cycles`: the paper's fixed-cycle run "
      "(one coupon pulled along x); a row marked extrapolated ran only the first cycles (a "
      "quick run, or a full run that would take longer than explicit.time_limit_s = {:g} s) and "
      "extrapolates their time linearly, building the coupon counted once. `quasi-static "
      "explicit`: the staged explicit solver (damped "
      "central differences, one coupon along x) until the unbalanced-force ratio is below its "
      "tolerance. `static test`: both pulls with the static solver, building included. The "
      "paper's times are PFC's, on its machine.\n\n",
      paper_cycles, time_limit);
  md += fmt::format("{}\n", times);
  if (!explicit_moduli.empty()) {
    md += fmt::format(
        "## Table 2: moduli from the fixed-cycle explicit run\n\n"
        "Fitted over the second half of the {} cycles. A final unbalanced-force ratio far above "
        "the tolerance, or fewer than {:g} wave transits, means inertia is part of the "
        "measured stress.\n\n",
        paper_cycles, kQuasiStaticTransits);
    md += fmt::format("{}|---|---|---|---|---|---|---|\n{}\n",
                      markdown_row({"strategy", "Ex (GPa)", "rel. err.", "νxy", "rel. err.",
                                    "final unbalanced-force ratio", "loading wave transits"}),
                      explicit_moduli);
  }
  md += fmt::format("## Figures\n\n{}\n{}", figure_markdown(stress_strain, "Stress-strain along x"),
                    figures);
  return out;
}

}  // namespace

void register_lamina_strategies_experiment(ExperimentRegistry& registry) {
  registry.add("lamina-strategies",
               "Table 2: one lamina with every strategy: moduli, explicit and static run times",
               parse_lamina_strategies, run_lamina_strategies, report_lamina_strategies);
  registry.set_settings("lamina-strategies", [] {
    KindSettings k = paper_kind_settings(
        coupon_config_selection(),
        {{"strategies", "the strategies; default [\"lattice\", \"hcp\", \"hex2d\", \"square\"]"},
         {"angle_deg", "the ply angle [deg]; default 0"},
         {"explicit.cycles", "the paper's fixed-cycle explicit run; default 200000"},
         {"explicit.quick_cycles", "the probe's cycles, extrapolated (quick runs); default 500"},
         {"explicit.time_limit_s",
          "longer runs are extrapolated from the probe [s]; default 900"}});
    const SettingsDescription<TensionSettings>& d = tension_settings_description();
    for (const SettingRow& row : d.rows(d.defaults(), kExplicitKeys)) k.rows.push_back(row);
    return k;
  });
}

}  // namespace plydem
