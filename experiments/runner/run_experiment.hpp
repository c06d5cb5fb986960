#pragma once
/// \file
/// The runner behind `plydem run experiments/NAME.toml [--out DIR] [--quick]`: loads the config,
/// creates the output folder, runs the registered kind (experiments/runner/experiment.hpp) and
/// writes
///   DIR/report.md    title, date, machine, plydem version, the experiment's section, the files;
///   DIR/results.csv  one row per value: experiment,case,quantity,source,value,unit;
///   DIR/provenance.json  the plydem version, commit, compiler, backends and command line
///                    (experiments/runner/provenance.hpp);
/// beside the figures and VTU files the experiment wrote itself.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "experiments/protocols/run_settings.hpp"
#include "experiments/runner/experiment.hpp"

namespace plydem {

struct RunOptions {
  std::filesystem::path config;   ///< the experiment's TOML file
  std::filesystem::path out_dir;  ///< empty = results/NAME (relative to the current directory)
  bool quick = false;             ///< ExperimentContext::quick
  std::string calculix = "ccx";   ///< ExperimentContext::calculix
  bool force = false;             ///< ExperimentContext::force
  /// Sets the command line's run settings (--threads, --petsc-options) over the config's
  /// (`threads`, `petsc_options`); empty: the config's.
  std::function<void(RunSettings&)> run_settings;
};

struct RunSummary {
  std::filesystem::path out_dir;
  std::filesystem::path report;   ///< DIR/report.md
  std::filesystem::path results;  ///< DIR/results.csv
  ExperimentOutput output;
  double wall_seconds = 0;
};

/// Runs one experiment config, with its run settings (threads, petsc_options: RunScope) for the
/// run and its report. Throws plydem::Error for a missing or malformed config, an unknown kind or
/// key, or a failed run (the output folder may then hold partial files).
RunSummary run_experiment(const RunOptions& options);

/// The two files write_run_report writes.
struct RunReportFiles {
  std::filesystem::path report;   ///< DIR/report.md
  std::filesystem::path results;  ///< DIR/results.csv
};

/// Writes DIR/results.csv (the output's rows), DIR/provenance.json (provenance_json()) and
/// DIR/report.md: the output's title (or `fallback_title`), `description`, `what` was run (a
/// config and its kind, or a command line), the date, machine, plydem version, commit, this
/// process's command line and wall time, the output's section and its file list.
/// `quick` adds the line that says it was a quick run. Throws plydem::Error if a file cannot be
/// written. run_experiment writes its files with it; `plydem strength --out` too.
RunReportFiles write_run_report(const std::filesystem::path& out_dir,
                                const ExperimentOutput& output, const std::string& fallback_title,
                                const std::string& description, const std::string& what, bool quick,
                                double wall_seconds);

/// results.csv's text: the header `experiment,case,quantity,source,value,unit` and one line per
/// row (fields with a comma or quote are quoted; values with 10 significant digits).
std::string results_csv(const std::vector<ResultRow>& rows);

/// An experiment config found by list_experiment_configs.
struct ConfigListing {
  std::filesystem::path path;
  std::string name;         ///< file name without .toml
  std::string description;  ///< its `description`, or why it could not be read
};

/// The *.toml files in `folder`, sorted by name, with their descriptions. A file that does not
/// parse is listed with the parse error as its description. Throws plydem::Error if `folder` is
/// not a directory.
std::vector<ConfigListing> list_experiment_configs(const std::filesystem::path& folder);

/// The folder `plydem run --list` lists: ./experiments if it holds a .toml file, else the source
/// tree's experiments/ (known at build time).
std::filesystem::path default_experiments_folder();

/// The plydem version: the project version and, when built from git, `git describe` (at the
/// last CMake configure).
std::string plydem_version();

/// Facts CMake writes into the generated build_info.cpp: the source tree, `git describe` (empty
/// outside git) and the project version.
const char* build_source_dir();
const char* build_git_version();
const char* build_project_version();

}  // namespace plydem
