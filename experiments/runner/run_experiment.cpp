#include "experiments/runner/run_experiment.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <spdlog/spdlog.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <thread>

#include "core/error.hpp"
#include "experiments/runner/provenance.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"')
      out += "\"\"";
    else
      out += c;
  }
  out += '"';
  return out;
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary);
  file << text;
  if (!file) throw Error(fmt::format("cannot write {}", path.string()));
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[64];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return buffer;
}

std::string machine_line() {
  std::string line;
  utsname u{};
  if (uname(&u) == 0) line = fmt::format("{} {} {}", u.sysname, u.release, u.machine);
  std::string cpu;
  std::ifstream info("/proc/cpuinfo");
  for (std::string l; std::getline(info, l);) {
    if (l.rfind("model name", 0) == 0) {
      const auto colon = l.find(':');
      if (colon != std::string::npos) cpu = l.substr(colon + 2);
      break;
    }
  }
  if (!cpu.empty()) line += fmt::format(", {}", cpu);
  line += fmt::format(", {} hardware threads, {} OpenMP threads (OMP_NUM_THREADS)",
                      std::thread::hardware_concurrency(), omp_get_max_threads());
  return line;
}

}  // namespace

std::string results_csv(const std::vector<ResultRow>& rows) {
  std::string out = "experiment,case,quantity,source,value,unit\n";
  for (const ResultRow& r : rows) {
    out += fmt::format("{},{},{},{},{:.10g},{}\n", csv_field(r.experiment), csv_field(r.case_name),
                       csv_field(r.quantity), csv_field(r.source), r.value, csv_field(r.unit));
  }
  return out;
}

std::string plydem_version() {
  const std::string git = build_git_version();
  if (git.empty()) return build_project_version();
  return fmt::format("{} (git {})", build_project_version(), git);
}

std::vector<ConfigListing> list_experiment_configs(const fs::path& folder) {
  if (!fs::is_directory(folder)) {
    throw Error(fmt::format("'{}' is not a folder of experiment configs", folder.string()));
  }
  std::vector<ConfigListing> list;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".toml") continue;
    ConfigListing item{entry.path(), entry.path().stem().string(), ""};
    try {
      item.description = ExperimentConfig::load(entry.path()).description();
    } catch (const Error& e) {
      item.description = fmt::format("(cannot be read: {})", e.what());
    }
    list.push_back(std::move(item));
  }
  std::sort(list.begin(), list.end(),
            [](const ConfigListing& a, const ConfigListing& b) { return a.name < b.name; });
  return list;
}

fs::path default_experiments_folder() {
  const fs::path local = fs::current_path() / "experiments";
  if (fs::is_directory(local)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(local)) {
      if (entry.path().extension() == ".toml") return local;
    }
  }
  const std::string source = build_source_dir();
  if (!source.empty() && fs::is_directory(fs::path(source) / "experiments")) {
    return fs::path(source) / "experiments";
  }
  return local;
}

RunReportFiles write_run_report(const fs::path& out_dir, const ExperimentOutput& out,
                                const std::string& fallback_title, const std::string& description,
                                const std::string& what, bool quick, double wall_seconds) {
  RunReportFiles files;
  files.results = out_dir / "results.csv";
  write_text(files.results, results_csv(out.rows));
  // Which plydem wrote the files, and how: beside results.csv, whose readers expect its header on
  // the first line (tests/support/results_csv.hpp, pandas), rather than in it.
  const nlohmann::json provenance = provenance_json();
  write_text(out_dir / "provenance.json", provenance.dump(2) + "\n");
  files.report = out_dir / "report.md";
  std::string report = fmt::format("# {}\n\n", out.title.empty() ? fallback_title : out.title);
  if (!description.empty()) report += fmt::format("{}\n\n", description);
  report += fmt::format(
      "- {}{}\n- date: {}\n- machine: {}\n- plydem: {}\n- commit: {}\n- command line: `{}`\n"
      "- wall time: {:.1f} s\n\n",
      what,
      quick ? "\n- **quick run** (`--quick`): smaller coupons and fewer cycles than the paper; use "
              "a full run for the tables"
            : "",
      utc_now(), machine_line(), plydem_version(),
      provenance["commit"].get<std::string>().empty() ? "unknown (not built from git)"
                                                      : provenance["commit"].get<std::string>(),
      provenance["command_line"].get<std::string>(), wall_seconds);
  report += out.report_markdown;
  report +=
      "\n## Files\n\n- `report.md` (this file)\n- `results.csv`: one row per value "
      "(experiment, case, quantity, source, value, unit)\n- `provenance.json`: the plydem version, "
      "commit, compiler, backends and command line that wrote these files\n";
  for (const fs::path& file : out.files) {
    report += fmt::format("- `{}`\n", file.generic_string());
  }
  write_text(files.report, report);
  return files;
}

RunSummary run_experiment(const RunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const ExperimentConfig config = ExperimentConfig::load(options.config);
  const std::string kind = config.kind();
  // An unknown kind fails before anything is written.
  const std::unique_ptr<Experiment> experiment = default_experiment_registry().create(kind);
  // The run's settings (threads, petsc_options), the command line's over the config's.
  RunSettings run = run_settings_description().defaults();
  read_config_settings(config, run_settings_description(), {}, options.quick, run);
  if (options.run_settings) options.run_settings(run);
  const RunScope scope(run);

  RunSummary summary;
  summary.out_dir = options.out_dir.empty() ? fs::path("results") / config.name() : options.out_dir;
  std::error_code ec;
  fs::create_directories(summary.out_dir, ec);
  if (ec || !fs::is_directory(summary.out_dir)) {
    throw Error(fmt::format("cannot create the output folder '{}': {}", summary.out_dir.string(),
                            ec ? ec.message() : "not a folder"));
  }
  ExperimentContext context;
  context.out_dir = summary.out_dir;
  context.quick = options.quick;
  context.calculix = options.calculix;
  context.force = options.force;
  spdlog::info("running {} ({}){} into {}", options.config.string(), kind,
               options.quick ? ", quick" : "", summary.out_dir.string());
  summary.output = experiment->run(config, context);
  summary.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const RunReportFiles files = write_run_report(
      summary.out_dir, summary.output, config.name(), config.description(),
      fmt::format("config: `{}` (experiment kind `{}`)", options.config.string(), kind),
      options.quick, summary.wall_seconds);
  summary.report = files.report;
  summary.results = files.results;
  return summary;
}

}  // namespace plydem
