#pragma once
/// \file
/// Experiments that `plydem run experiments/NAME.toml` runs: the paper's Tables 2-5 and the
/// hole-in-plate. An experiment is a class registered under a kind; a config file names its kind
/// with the key `experiment` and holds that kind's settings:
///
///   # experiments/table4.toml
///   experiment = "laminate"
///   description = "Table 4: the [0/90/0] laminate, DEM beside CLT, CalculiX and the paper"
///   layup = "[0/90/0]"
///
/// Every run writes into one output folder: report.md (assembled from the experiments' sections),
/// results.csv (one row per measured or reference value) and the figures and VTU files the
/// experiment makes. Kinds are registered like strategies (strategies/registry.hpp), so a user adds
/// an experiment without editing the runner.
///
/// A built-in kind is one file, experiments/runner/<kind>_experiment.cpp, holding its settings
/// struct and parse -> run -> report (ExperimentSteps) and exporting
/// `void register_<kind>_experiment(ExperimentRegistry&)`; adding `<kind>` to the CMake list
/// PLYDEM_EXPERIMENTS compiles the file and calls the function.

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/registry.hpp"
#include "core/settings.hpp"

namespace plydem {

/// A parsed experiment config (TOML). Keys may be dotted to reach into tables ("fem.element").
/// Getters throw plydem::Error naming the file and the key when a value has the wrong type; a
/// missing key gives the fallback.
class ExperimentConfig {
 public:
  /// Throws plydem::Error naming the file (and line and column for a syntax error).
  static ExperimentConfig load(const std::filesystem::path& path);
  /// Parses TOML text; `origin` names it in messages.
  static ExperimentConfig parse(const std::string& text, const std::string& origin);

  const std::filesystem::path& path() const;
  /// The file name without extension ("table2").
  std::string name() const;
  /// The `experiment` key: the registered kind. Throws if it is missing.
  std::string kind() const;
  /// The `description` key, or "".
  std::string description() const;

  bool contains(const std::string& key) const;
  std::string string(const std::string& key, const std::string& fallback) const;
  /// Integers are accepted as numbers; NaN and infinities are refused.
  double number(const std::string& key, double fallback) const;
  /// A non-negative integer (counts, seeds); refuses fractions.
  long integer(const std::string& key, long fallback) const;
  bool boolean(const std::string& key, bool fallback) const;
  std::vector<std::string> strings(const std::string& key,
                                   const std::vector<std::string>& fallback) const;
  std::vector<double> numbers(const std::string& key, const std::vector<double>& fallback) const;
  /// Throws plydem::Error naming every key (dotted, at any depth) that is not in `known` or below
  /// a known table: a misspelt key is an error, not a silent default. The keys every kind takes
  /// (`experiment`, `description` and the run's settings, `threads` and `petsc_options`:
  /// run_settings_description()) are always known.
  void require_known_keys(const std::vector<std::string>& known) const;

 private:
  struct Data;
  std::shared_ptr<const Data> data_;
  std::filesystem::path path_;
};

/// Where an experiment runs and writes.
struct ExperimentContext {
  std::filesystem::path out_dir;  ///< exists when run() is called
  /// Smaller sizes and fewer cycles, for tests and a quick look (`plydem run --quick`); the
  /// report says that it is a quick run.
  bool quick = false;
  /// CalculiX executable (`ccx`); when it is missing the FEM columns say so plainly.
  std::string calculix = "ccx";
  /// Build coupons even when their memory estimate exceeds the machine's available memory
  /// (`plydem run --force`; experiments/protocols/resource_estimate.hpp).
  bool force = false;
};

/// One value in results.csv: `experiment,case,quantity,source,value,unit`. `source` is where the
/// value comes from ("dem hex2d", "clt", "calculix", "paper dem", "paper theory", "experiment").
struct ResultRow {
  std::string experiment;
  std::string case_name;  ///< e.g. "0 deg", "[0/90/0]"
  std::string quantity;   ///< e.g. "E1", "nu12", "static solve time", "ux L2 error"
  std::string source;
  double value = 0;
  std::string unit;  ///< "GPa", "1", "s", ...: values are written in this unit
};

/// What an experiment produced. report_markdown is its section of report.md (tables with relative
/// errors, figure links relative to the output folder); files lists what it wrote, relative to it.
struct ExperimentOutput {
  std::string title;
  std::string report_markdown;
  std::vector<ResultRow> rows;
  std::vector<std::filesystem::path> files;
};

class Experiment {
 public:
  virtual ~Experiment() = default;
  /// Runs the experiment of `config`. Throws plydem::Error for a bad config or a failed run.
  virtual ExperimentOutput run(const ExperimentConfig& config,
                               const ExperimentContext& context) const = 0;
  /// Reads `config` as run() would before building anything, and refuses what run() would refuse
  /// there (a key it does not know, a bad value, a setting that does nothing); runs nothing. The
  /// default reads nothing.
  virtual void check(const ExperimentConfig& config, const ExperimentContext& context) const;
};

using ExperimentFactory = FactoryRegistry<Experiment>::Factory;

/// What a kind's config takes, for the reference page (docs/settings.md, `plydem settings`) and the
/// tests: its described settings with the kind's own defaults (SettingsDescription::rows), and the
/// keys it reads itself, each with what it is.
struct KindSettings {
  std::vector<SettingRow> rows;
  std::vector<std::pair<std::string, std::string>> own_keys;
};

/// An experiment kind written as three steps over its own settings struct, the shape of every
/// built-in kind (one file each, experiments/runner/<kind>_experiment.cpp):
///   parse   the config's keys -> Settings; refuses an unknown key or a bad value with a
///           plydem::Error naming the file and the key, before anything is built;
///   run     Settings -> Results: the computation (build, solve, FEM);
///   report  Settings and Results -> ExperimentOutput: report.md's section, results.csv's rows,
///           and the figures, VTU and data files written into context.out_dir.
/// ExperimentRegistry::add(kind, description, parse, run, report) registers one.
template <class Settings, class Results>
class ExperimentSteps : public Experiment {
 public:
  using Parse = Settings (*)(const ExperimentConfig& config, const ExperimentContext& context);
  using Run = Results (*)(const Settings& settings, const ExperimentContext& context);
  using Report = ExperimentOutput (*)(const Settings& settings, const Results& results,
                                      const ExperimentContext& context);

  ExperimentSteps(Parse parse, Run run, Report report)
      : parse_(parse), run_(run), report_(report) {}

  ExperimentOutput run(const ExperimentConfig& config,
                       const ExperimentContext& context) const override {
    const Settings settings = parse_(config, context);
    const Results results = run_(settings, context);
    return report_(settings, results, context);
  }
  void check(const ExperimentConfig& config, const ExperimentContext& context) const override {
    (void)parse_(config, context);
  }

 private:
  Parse parse_;
  Run run_;
  Report report_;
};

/// Experiment kinds by name (core/registry.hpp, as strategies/registry.hpp for strategies):
/// add() throws plydem::Error if the kind is empty or taken, create() lists the registered kinds
/// if `kind` is unknown.
class ExperimentRegistry : public FactoryRegistry<Experiment> {
 public:
  ExperimentRegistry();
  using FactoryRegistry<Experiment>::add;
  /// Registers a kind written as parse -> run -> report (ExperimentSteps).
  template <class Settings, class Results>
  void add(const std::string& kind, const std::string& description,
           Settings (*parse)(const ExperimentConfig&, const ExperimentContext&),
           Results (*run)(const Settings&, const ExperimentContext&),
           ExperimentOutput (*report)(const Settings&, const Results&, const ExperimentContext&)) {
    add(kind, description, [parse, run, report] {
      return std::make_unique<ExperimentSteps<Settings, Results>>(parse, run, report);
    });
  }
  std::vector<std::string> kinds() const { return names(); }
  /// Registers what `kind`'s config takes (read when asked: the reference page, the tests).
  void set_settings(const std::string& kind, std::function<KindSettings()> settings);
  /// What `kind`'s config takes, if it registered it.
  std::optional<KindSettings> settings(const std::string& kind) const;

 private:
  std::map<std::string, std::function<KindSettings()>> settings_;
};

/// The process-wide experiment registry, filled with the built-in kinds on first use.
ExperimentRegistry& default_experiment_registry();

/// Calls every built-in experiment file's register_<kind>_experiment() (generated from the list
/// PLYDEM_EXPERIMENTS in CMakeLists.txt).
void register_builtin_experiments(ExperimentRegistry& registry);

}  // namespace plydem
