// plydem: particle models of FRP composite laminae, from the command line.
//
// Sample runs:
//   plydem                                   # the paper's 0 deg E-glass/MY750 lamina, Hex2D
//   plydem tension --strategy hex2d --angle 30 --json
//   plydem tension --material my_ply.toml --angle 0 --grips clamped
//   plydem calibrate --strategy hex2d --angle 30 --json
//   plydem strength --angle 30               # tension test to failure beside the criteria
//   plydem strength --layup "[0/90]s" --out results/strength   # report, figures, VTU series
//   plydem strategies                        # registered strategies
//   plydem materials                         # built-in materials
//   plydem run experiments/table4.toml       # the paper's Table 4 into results/table4/
//   plydem run --list                        # the experiment configs
//   plydem settings > docs/settings.md       # every setting: flags, config keys, Python names
//   plydem --version                         # version, commit, compiler, backends
//   plydem --plugin libmine.so strategies    # a C++ plug-in's strategies (docs/install.md)
//
// The commands' settings (their flags, defaults, help and the "does nothing here" refusals) come
// from the settings descriptions (experiments/runner/settings_descriptions.hpp) through
// experiments/cli/settings_cli.hpp; the flags here are the command line's own (--json, --out,
// --quiet, --plugin, --version, run's). Every JSON object printed carries "provenance"
// (experiments/runner/provenance.hpp): the version, commit and command line that produced it.
#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <iostream>
#include <optional>

#include <unistd.h>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/progress.hpp"
#include "experiments/cli/command_line.hpp"
#include "experiments/cli/plugins.hpp"
#include "experiments/cli/python_plugin.hpp"
#include "experiments/cli/settings_cli.hpp"
#include "experiments/output/report.hpp"
#include "experiments/output/strength_report.hpp"
#include "experiments/protocols/run_settings.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/provenance.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "experiments/runner/settings_reference.hpp"
#include "experiments/runner/strength_experiment.hpp"
#include "experiments/runner/tension_experiment.hpp"
#include "solvers/linear_solver.hpp"
#include "strategies/registry.hpp"

namespace {

using plydem::cli::CommandLineSettings;

// What every command takes: how much it says on stderr.
struct LogOptions {
  bool quiet = false;
  double progress_interval = 2;
};

void add_log_options(CLI::App& app, LogOptions& o) {
  app.add_flag("--quiet", o.quiet,
               "no progress or statistics on stderr (warnings and errors stay)");
  app.add_option("--progress-interval", o.progress_interval,
                 "seconds before a long phase first reports its progress, and between reports")
      ->capture_default_str();
}

// The run's settings (--threads, --petsc-options): every command's, and the program's own (the
// default job's, and before a command).
struct RunSettingsOptions {
  std::deque<CommandLineSettings<plydem::RunSettings>> apps;
  void add(CLI::App& app, const std::string& command) {
    apps.emplace_back(app, plydem::run_settings_description(), command);
  }
  /// The given options on `settings`, a command's after the program's.
  void apply(plydem::RunSettings& settings) const {
    for (const CommandLineSettings<plydem::RunSettings>& o : apps) o.apply(settings);
  }
  plydem::RunSettings settings() const {
    plydem::RunSettings s = plydem::run_settings_description().defaults();
    apply(s);
    return s;
  }
};

// An option given where it would change nothing is refused, with the reason.
void refuse_given(const CLI::App& app, const std::vector<std::string>& names,
                  const std::string& reason) {
  for (const std::string& name : names) {
    if (app.count(name) > 0) {
      // Positional arguments by their name: "the config".
      const std::string what = name.front() == '-' ? name : "the " + name;
      throw plydem::Error(fmt::format("{} does nothing here: {}", what, reason));
    }
  }
}

// The strategy named by the settings, with its options set (unknown names fail here).
template <class Settings>
std::unique_ptr<plydem::Strategy> make_strategy(const Settings& s) {
  std::unique_ptr<plydem::Strategy> strategy = plydem::default_registry().create(s.strategy);
  for (const auto& [name, value] : s.strategy_options) strategy->set_option(name, value);
  return strategy;
}

// `plydem tension` (and the default job): the tension test's settings and --fem's.
struct TensionCommand {
  std::optional<CommandLineSettings<plydem::TensionRun>> settings;
  bool json = false;
};

CLI::App* add_tension_command(CLI::App& app, TensionCommand& c) {
  CLI::App* tension = app.add_subcommand(
      "tension", "virtual uniaxial tension test of one ply: Ex, Ey, nu_xy, nu_yx beside CLT");
  c.settings.emplace(*tension, plydem::tension_run_description(), "tension");
  tension->add_flag("--json", c.json, "print one JSON object (SI units) instead of the table");
  return tension;
}

// The tension command's settings: the defaults with the given options, refused where they do
// nothing; unknown strategies and options and checkpoints with the static solver fail here,
// before any work.
plydem::TensionRun tension_run(const TensionCommand& c) {
  plydem::TensionRun run = c.settings->settings();
  run.test.checkpoint.validate();
  make_strategy(run.test);
  run.test.validate();
  return run;
}

// `plydem strength`.
struct StrengthCommand {
  std::optional<CommandLineSettings<plydem::StrengthSettings>> settings;
  bool json = false;
  std::string out;
};

CLI::App* add_strength_command(CLI::App& app, StrengthCommand& c) {
  CLI::App* strength = app.add_subcommand(
      "strength",
      "tension test to failure: strength, strain at peak, first-failure stress and broken bonds "
      "beside XT, YT, S12 and the max-stress, Tsai-Hill, Tsai-Wu, Hashin and Puck criteria");
  c.settings.emplace(*strength, plydem::strength_settings_description(), "strength");
  strength->add_flag("--json", c.json, "print one JSON object (SI units) instead of the table");
  strength->add_option("--out", c.out,
                       "also write report.md, results.csv, the stress-strain and crack-pattern "
                       "PNGs and a VTU series into this folder");
  return strength;
}

plydem::StrengthSettings strength_settings(const StrengthCommand& c) {
  plydem::StrengthSettings s = c.settings->description().defaults();
  c.settings->apply(s);
  s.events.progress_seconds = std::max(1e-9, plydem::progress_interval());
  s.record_snapshots = !c.out.empty();
  c.settings->refuse_inapplicable(s);
  s.checkpoint.validate();
  make_strategy(s);
  s.validate();  // NaN and negative values fail here, before any work
  return s;
}

// `plydem calibrate`: the ply and coupon settings of the tension test.
struct CalibrateCommand {
  std::optional<CommandLineSettings<plydem::TensionSettings>> settings;
  bool json = false;
};

CLI::App* add_calibrate_command(CLI::App& app, CalibrateCommand& c) {
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "bond stiffness of each family, lattice orientation, and the stiffness the model has as "
      "simulated beside the target");
  c.settings.emplace(*calibrate, plydem::tension_settings_description(), "calibrate",
                     plydem::calibrate_selection());
  calibrate->add_flag("--json", c.json, "print one JSON object (SI units)");
  return calibrate;
}

struct RunCommand {
  plydem::RunOptions options;
  std::string config, out;
  bool list = false;
};

CLI::App* add_run_command(CLI::App& app, RunCommand& c) {
  CLI::App* run = app.add_subcommand(
      "run",
      "run an experiment config (experiments/NAME.toml): report.md, results.csv, figures and VTU "
      "files in the output folder");
  run->add_option("config", c.config, "the experiment's TOML file, e.g. experiments/table4.toml");
  run->add_option("--out", c.out, "output folder; default results/NAME");
  run->add_flag("--quick", c.options.quick,
                "smaller coupons and fewer cycles (seconds instead of minutes)");
  run->add_option("--ccx", c.options.calculix, "the CalculiX executable")->capture_default_str();
  run->add_flag("--list", c.list,
                "list the configs in ./experiments (else the source tree's) with their "
                "descriptions");
  run->add_flag("--force", c.options.force,
                "build coupons even when their memory estimate exceeds the machine's available "
                "memory");
  return run;
}

// `plydem settings`: the reference of every setting (docs/settings.md).
struct SettingsCommand {
  bool json = false;
};

CLI::App* add_settings_command(CLI::App& app, SettingsCommand& c) {
  CLI::App* settings = app.add_subcommand(
      "settings",
      "every setting of the commands, the experiment kinds and Python: flag, config key, Python "
      "name, default, unit, range and help (docs/settings.md is this, in Markdown)");
  settings->add_flag("--json", c.json, "the same tables as one JSON array");
  return settings;
}

// What the run calibrated and built, on stderr.
void log_build_statistics() {
  const plydem::BuildStatistics work = plydem::build_statistics();
  spdlog::info("{} ply calibration{}, {} coupon build{} (each laminate ply counts as one)",
               work.calibrations, work.calibrations == 1 ? "" : "s", work.builds,
               work.builds == 1 ? "" : "s");
}

int run_tension(const TensionCommand& c) {
  const plydem::TensionRun run = tension_run(c);
  const plydem::TensionSettings& settings = run.test;
  const std::string narrow = plydem::narrow_laminate_warning(
      settings.coupon.width, settings.coupon.thickness, settings.layup);
  if (!narrow.empty()) spdlog::warn("warning: {}", narrow);
  plydem::TensionTest test(settings);
  test.on_progress([](const plydem::TensionProgress& p) {
    const std::string left =
        p.seconds_left >= 0 ? fmt::format(", about {:.0f} s left", p.seconds_left) : "";
    spdlog::info("{}: {} cycles, unbalanced-force ratio {:.3g}, {:.0f} s{}", p.phase, p.cycles,
                 p.ratio, p.elapsed_seconds, left);
  });
  plydem::TensionResult result;
  try {
    result = test.run();
  } catch (const plydem::UnreachableStiffness& e) {
    if (c.json)
      std::cout << nlohmann::json{{"refused", plydem::refusal_json(e.refusal())},
                                  {"provenance", plydem::provenance_json()}}
                       .dump(2)
                << "\n";
    throw;
  }
  log_build_statistics();
  std::optional<plydem::SameCouponReference> fem;
  if (run.fem) fem = plydem::same_coupon_fem(run, result);
  if (c.json) {
    nlohmann::json j = plydem::tension_json(result, settings);  // with "warnings"
    if (fem) j["fem"] = plydem::same_coupon_json(result, *fem);
    j["provenance"] = plydem::provenance_json();
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << plydem::format_tension_table(result, settings);
    if (fem) std::cout << plydem::format_same_coupon_table(result, *fem);
    if (!narrow.empty()) std::cout << "\nwarning: " << narrow << "\n";
  }
  return 0;
}

// `plydem strength --out DIR`: report.md, results.csv and the strength test's files.
void write_strength_report(const plydem::StrengthResult& result,
                           const plydem::StrengthSettings& settings, double angle_deg,
                           const std::filesystem::path& out_dir, const std::string& command_line,
                           double seconds) {
  const std::string case_name =
      result.layup.empty()
          ? fmt::format("{:g} deg", angle_deg)
          : fmt::format("{} at {:g} deg", plydem::format_layup(result.layup), angle_deg);
  plydem::ExperimentOutput output =
      plydem::strength_output(result, out_dir, "strength", case_name, "strength");
  output.title = fmt::format("Strength: the {} {} ({}, {})", result.material.name,
                             result.layup.empty() ? "ply" : "laminate", case_name, result.strategy);
  output.report_markdown =
      fmt::format("Coupon {:g} × {:g} mm, ply thickness {:g} mm, particle diameter {:g} mm. ",
                  settings.coupon.length * 1e3, settings.coupon.width * 1e3,
                  settings.coupon.thickness * 1e3, settings.coupon.particle_diameter * 1e3) +
      plydem::strength_model_note(settings) + "\n\n" + output.report_markdown;
  const plydem::RunReportFiles files = plydem::write_run_report(
      out_dir, output, "strength", "", fmt::format("command: `{}`", command_line), false, seconds);
  spdlog::info("wrote {} and {} ({} more files) into {}", files.report.filename().string(),
               files.results.filename().string(), output.files.size(), out_dir.string());
}

int run_strength(const StrengthCommand& c, const std::string& command_line) {
  const auto start = std::chrono::steady_clock::now();
  const plydem::StrengthSettings settings = strength_settings(c);
  std::filesystem::path out_dir;
  if (!c.out.empty()) {
    // The folder must be writable before the run, not after it.
    out_dir = c.out;
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    plydem::require(!ec && std::filesystem::is_directory(out_dir),
                    fmt::format("cannot create the output folder '{}': {}", c.out,
                                ec ? ec.message() : "not a folder"));
  }
  plydem::StrengthTest test(settings);
  test.on_progress([](const plydem::EventProgress& p) {
    spdlog::info("{} events, {} bonds broken, load factor {:.4g}, peak reaction {:.4g} N, {:.0f} s",
                 p.events, p.broken, p.load_factor, p.peak_reaction, p.elapsed_seconds);
  });
  const plydem::StrengthResult result = test.run();
  log_build_statistics();
  if (c.json) {
    nlohmann::json j = plydem::strength_json(result, settings);
    j["provenance"] = plydem::provenance_json();
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << plydem::format_strength_table(result, settings);
  }
  if (!out_dir.empty() && plydem::is_root()) {  // under mpiexec rank 0 writes the files
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_strength_report(result, settings, c.settings->edge_number("angle"), out_dir, command_line,
                          seconds);
  }
  return 0;
}

int run_calibrate(const CalibrateCommand& c) {
  const plydem::TensionSettings settings = c.settings->settings();
  const plydem::Material& material = settings.coupon.material;
  const double angle = settings.coupon.ply_angle;
  const std::unique_ptr<plydem::Strategy> strategy = make_strategy(settings);
  // The calibration the coupon of these options gets, as `plydem tension` builds it: for lattice
  // that of the coupon's own packing (Strategy::calibrate_coupon), not of a calibration sample.
  const plydem::CouponSpec& coupon = settings.coupon;
  coupon.validate();
  plydem::Calibration calibration;
  try {
    calibration = strategy->calibrate_coupon(coupon);
  } catch (const plydem::UnreachableStiffness& e) {
    // The refusal's numbers on stdout; its sentence on stderr and exit status 2 as any error.
    if (c.json)
      std::cout << nlohmann::json{{"refused", plydem::refusal_json(e.refusal())},
                                  {"provenance", plydem::provenance_json()}}
                       .dump(2)
                << "\n";
    throw;
  }
  const CommandLineSettings<plydem::TensionSettings>& given = *c.settings;
  if (c.json) {
    nlohmann::json j = plydem::calibration_json(calibration);
    j["strategy"] = settings.strategy;
    j["material"] = material.name;
    j["angle_deg"] = given.edge_number("angle");
    j["thickness"] = coupon.thickness;
    j["coupon"] = {{"length", coupon.length},
                   {"width", coupon.width},
                   {"particle_diameter", coupon.particle_diameter}};
    j["units"] = "SI (N/m, N m/rad, Pa)";
    j["provenance"] = plydem::provenance_json();
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << plydem::format_calibration(calibration, settings.strategy, material, angle);
    std::cout << fmt::format(
        "the calibration a {:g} x {:g} mm coupon of {:g} mm particles gets (what `plydem "
        "tension` with these options builds)\n",
        given.edge_number("length"), given.edge_number("width"), given.edge_number("diameter"));
  }
  return 0;
}

// What plydem_command_line's check_only does after parsing: the settings the command would run
// with, and for a test its coupon's estimate (refused as the run would refuse it).
int check_command(const TensionCommand& tension, const CLI::App& strength_app,
                  const StrengthCommand& strength, const CLI::App& calibrate_app,
                  const CalibrateCommand& calibrate, const CLI::App& run_app,
                  const RunCommand& run) {
  if (calibrate_app.parsed()) {
    make_strategy(calibrate.settings->settings());
  } else if (strength_app.parsed()) {
    const plydem::StrengthSettings settings = strength_settings(strength);
    const plydem::StrengthTest test(settings);
    plydem::check_resources(test.estimate(*make_strategy(settings)), settings.force, "--force");
  } else if (run_app.parsed()) {
    if (!run.list && !run.config.empty()) (void)plydem::ExperimentConfig::load(run.config);
  } else {
    const plydem::TensionSettings settings = tension_run(tension).test;
    const plydem::TensionTest test(settings);
    plydem::check_resources(test.estimate(*make_strategy(settings)), settings.force, "--force");
  }
  return 0;
}

int print_strategies() {
  const plydem::Registry& registry = plydem::default_registry();
  for (const std::string& name : registry.names()) {
    std::cout << fmt::format("{:<14} {}\n", name, registry.description(name));
    for (const plydem::StrategyOption& option : registry.create(name)->options()) {
      std::cout << fmt::format("{:<14}   --strategy-option {}={:g}: {}\n", "", option.name,
                               option.value, option.description);
    }
  }
  return 0;
}

int print_materials() {
  for (const std::string& name : plydem::builtin_material_names()) {
    const plydem::Material m = plydem::load_material(name);
    std::cout << fmt::format(
        "{:<14} E1 {:g} GPa, E2 {:g} GPa, G12 {:g} GPa, nu12 {:g}, nu23 {:g}, density {:g} "
        "kg/m^3\n",
        m.name, m.E1 * 1e-9, m.E2 * 1e-9, m.G12 * 1e-9, m.nu12, m.nu23, m.density);
  }
  return 0;
}

int print_settings(const SettingsCommand& c) {
  if (c.json) {
    std::cout << plydem::settings_json().dump(2) << "\n";
  } else {
    std::cout << plydem::settings_markdown();
  }
  return 0;
}

// Under mpiexec every rank runs the experiment and writes its files as it goes: rank 0 into the
// folder asked for, each other rank into a scratch folder of its own (removed when the command
// ends), so that no two processes write one file at once.
class RankOutputFolder {
 public:
  explicit RankOutputFolder(const std::string& requested) : path_(requested) {
    if (plydem::is_root()) return;
    scratch_ = std::filesystem::temp_directory_path() /
               fmt::format("plydem-rank{}-{}", plydem::mpi_rank(), ::getpid());
    path_ = scratch_ / "results";
  }
  ~RankOutputFolder() {
    std::error_code ignored;
    if (!scratch_.empty()) std::filesystem::remove_all(scratch_, ignored);
  }
  RankOutputFolder(const RankOutputFolder&) = delete;
  RankOutputFolder& operator=(const RankOutputFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_, scratch_;
};

int run_config_command(RunCommand& c, const RunSettingsOptions& run_options) {
  if (c.list) {
    const std::filesystem::path folder = plydem::default_experiments_folder();
    std::cout << fmt::format("experiment configs in {}:\n", folder.string());
    for (const plydem::ConfigListing& listing : plydem::list_experiment_configs(folder)) {
      std::cout << fmt::format("  {:<10} {}\n", listing.name, listing.description);
    }
    return 0;
  }
  plydem::require(!c.config.empty(),
                  "plydem run needs an experiment config (e.g. experiments/table4.toml) or "
                  "--list");
  c.options.config = c.config;
  const RankOutputFolder folder(c.out);
  c.options.out_dir = folder.path();
  c.options.run_settings = [&run_options](plydem::RunSettings& s) { run_options.apply(s); };
  const plydem::RunSummary summary = plydem::run_experiment(c.options);
  log_build_statistics();
  std::cout << fmt::format("{} done in {:.1f} s: {} rows in {}, report {}\n",
                           c.options.config.string(), summary.wall_seconds,
                           summary.output.rows.size(), summary.results.string(),
                           summary.report.string());
  return 0;
}

// The commands, each with its settings, and what every command takes.
struct Commands {
  LogOptions log;
  RunSettingsOptions run_settings;
  TensionCommand tension;
  StrengthCommand strength;
  CalibrateCommand calibrate;
  RunCommand run;
  SettingsCommand settings;
  std::vector<std::string> plugins;
  CLI::App *tension_app = nullptr, *strength_app = nullptr, *calibrate_app = nullptr,
           *strategies_app = nullptr, *materials_app = nullptr, *run_app = nullptr,
           *settings_app = nullptr;
};

void add_commands(CLI::App& app, Commands& c) {
  add_log_options(app, c.log);
  c.run_settings.add(app, "");
  c.tension_app = add_tension_command(app, c.tension);
  c.strength_app = add_strength_command(app, c.strength);
  c.calibrate_app = add_calibrate_command(app, c.calibrate);
  c.strategies_app = app.add_subcommand("strategies", "list the registered strategies");
  c.materials_app = app.add_subcommand("materials", "list the built-in materials");
  c.run_app = add_run_command(app, c.run);
  c.settings_app = add_settings_command(app, c.settings);
  for (CLI::App* command : {c.tension_app, c.strength_app, c.calibrate_app, c.strategies_app,
                            c.materials_app, c.run_app}) {
    add_log_options(*command, c.log);
  }
  for (CLI::App* command : {c.tension_app, c.strength_app, c.calibrate_app, c.run_app}) {
    c.run_settings.add(*command, command->get_name());
  }
  app.add_option("--plugin", c.plugins,
                 "a plug-in loaded before the command, which adds strategies and experiment kinds: "
                 "a Python file whose plydem.register_strategy calls add strategies (see "
                 "docs/python.md, \"Strategies written in Python\"), or a C++ shared library "
                 "(libNAME.so) built with PLYDEM_PLUGIN (docs/install.md); repeatable, after those "
                 "of PLYDEM_PLUGIN_PATH");
  app.set_version_flag(
      "--version",
      [] {
        std::string text = plydem::version_text();
        if (!text.empty() && text.back() == '\n') text.pop_back();
        return text;
      },
      "print the version, git commit, compiler and backends, and exit");
}

// The command after parsing (and after the plug-ins registered their strategies).
int run_command(Commands& c, int argc, char** argv, bool check_only) {
  plydem::set_progress_interval(c.log.progress_interval);
  spdlog::set_level(!plydem::is_root() ? spdlog::level::off
                    : c.log.quiet      ? spdlog::level::warn
                                       : spdlog::level::info);
  const plydem::RunSettings run_settings = c.run_settings.settings();
  if (*c.run_app && c.run.list) {
    refuse_given(*c.run_app,
                 {"config", "--out", "--quick", "--ccx", "--force", "--threads", "--petsc-options"},
                 "--list only lists the configs");
  }
  if (check_only) {
    return check_command(c.tension, *c.strength_app, c.strength, *c.calibrate_app, c.calibrate,
                         *c.run_app, c.run);
  }
  if (*c.strategies_app) return print_strategies();
  if (*c.materials_app) return print_materials();
  if (*c.settings_app) return print_settings(c.settings);
  if (*c.run_app) return run_config_command(c.run, c.run_settings);
  const plydem::RunScope scope(run_settings);
  if (*c.calibrate_app) return run_calibrate(c.calibrate);
  if (*c.strength_app) {
    std::string command_line = "plydem";
    for (int i = 1; i < argc; ++i) command_line += fmt::format(" {}", argv[i]);
    return run_strength(c.strength, command_line);
  }
  return run_tension(c.tension);
}

}  // namespace

int plydem_command_line(int argc, char** argv, bool check_only) {
  CLI::App app{
      "plydem: particle (DEM and lattice) models of fibre-reinforced composite laminae.\n"
      "With no command it runs the paper's 0 deg E-glass/MY750 lamina with the Hex2D strategy\n"
      "and prints E1, E2, nu12, nu21 beside classical lamination theory."};
  app.require_subcommand(0, 1);
  // Options of the program itself (--plugin) may also stand after the command: the commands
  // (which inherit this) pass them up.
  app.fallthrough();
  // Progress and warnings go to stderr: stdout carries only the table or the JSON object.
  if (!spdlog::get("plydem")) spdlog::set_default_logger(spdlog::stderr_color_mt("plydem"));
  spdlog::set_pattern("[%H:%M:%S] %v");
  Commands commands;
  add_commands(app, commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  const auto command = [&]() -> int { return run_command(commands, argc, argv, check_only); };
  try {
    if (check_only) return command();  // plug-ins are not loaded: nothing runs
    plydem::cli::load_plugins(commands.plugins);
    return plydem::cli::run_with_plugins(command);
  } catch (const plydem::Error& e) {
    std::cerr << "plydem: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "plydem: internal error: " << e.what() << "\n";
    return 3;
  }
}
