// Running CalculiX: finding ccx, the work directory, the `ccx -i job` call and its log, and
// run_calculix, which meshes, writes, runs and reads in turn.
#include "experiments/fem/calculix.hpp"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "experiments/fem/calculix_detail.hpp"
#include "experiments/output/external_tool.hpp"

namespace plydem {
namespace {

using Clock = Stopwatch::Clock;
namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("cannot read CalculiX output {}", path.string()));
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A temporary directory removed on destruction, or the user's, kept.
class WorkDirectory {
 public:
  explicit WorkDirectory(const std::string& requested) {
    if (!requested.empty()) {
      path_ = requested;
      std::error_code ec;
      fs::create_directories(path_, ec);
      if (!fs::is_directory(path_))
        throw Error(fmt::format("cannot create the CalculiX work directory {}", requested));
      return;
    }
    std::string pattern = (fs::temp_directory_path() / "plydem-ccx-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr)
      throw Error(fmt::format("cannot create a temporary directory like {}", pattern));
    path_ = pattern;
    remove_ = true;
  }
  ~WorkDirectory() {
    if (!remove_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  WorkDirectory(const WorkDirectory&) = delete;
  WorkDirectory& operator=(const WorkDirectory&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool remove_ = false;
};

// The lines of ccx's log that report errors (and input cards it could not read), or the log's
// tail when there are none.
std::string log_problems(const std::string& log) {
  std::istringstream in(log);
  std::string line, problems;
  std::vector<std::string> tail;
  bool in_error = false;
  int problem_lines = 0;
  while (std::getline(in, line)) {
    const bool error = line.find("*ERROR") != std::string::npos ||
                       line.find("*WARNING reading") != std::string::npos ||
                       line.find("cannot be inter") != std::string::npos;
    if (error || (in_error && !line.empty() && line.find('*') == std::string::npos)) {
      if (++problem_lines <= 12) problems += line + "\n";
      in_error = true;
    } else {
      in_error = false;
    }
    tail.push_back(line);
    if (tail.size() > 15) tail.erase(tail.begin());
  }
  if (problem_lines > 12) problems += fmt::format("... ({} more lines)\n", problem_lines - 12);
  if (!problems.empty()) return problems;
  std::string text;
  for (const auto& l : tail) text += l + "\n";
  return text;
}

// Writes `deck` as job.inp in the work directory, runs ccx on it and returns job.dat's text; the
// solver's wall time goes to `solver_seconds`. Throws plydem::Error, quoting the log's error
// lines, when ccx fails.
std::string run_ccx(const std::string& deck, const FemSettings& settings,
                    const CalculixAvailability& ccx, double& solver_seconds) {
  const WorkDirectory directory(settings.work_directory);
  {
    std::ofstream file(directory.path() / "job.inp", std::ios::binary);
    file << deck;
    if (!file) throw Error(fmt::format("cannot write {}", (directory.path() / "job.inp").string()));
  }
  const std::string command = fmt::format(
      "cd {} && OMP_NUM_THREADS={} CCX_NPROC_EQUATION_SOLVER={} {} -i job > job.log 2>&1",
      shell_quote(directory.path().string()), settings.threads, settings.threads,
      shell_quote(ccx.executable));
  const auto solve_start = Clock::now();
  const int status = std::system(command.c_str());
  solver_seconds = seconds_since(solve_start);
  const fs::path log_path = directory.path() / "job.log";
  const std::string log = fs::exists(log_path) ? read_text(log_path) : std::string();
  const int exit_code = status == -1 ? -1 : (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  if (exit_code != 0 || log.find("*ERROR") != std::string::npos ||
      log.find("*WARNING reading") != std::string::npos ||
      log.find("Job finished") == std::string::npos) {
    throw Error(fmt::format("CalculiX ({}) failed on {} (exit code {}):\n{}", ccx.executable,
                            (directory.path() / "job.inp").string(), exit_code, log_problems(log)));
  }
  return read_text(directory.path() / "job.dat");
}

}  // namespace

CalculixAvailability calculix_availability(const std::string& executable) {
  CalculixAvailability result;
  if (executable.empty()) {
    result.message = "CalculiX (ccx) is not installed: no executable name given";
    return result;
  }
  if (const std::optional<std::string> path = find_executable(executable)) {
    result.available = true;
    result.executable = *path;
  } else if (executable.find('/') != std::string::npos) {
    result.message =
        fmt::format("CalculiX (ccx) is not installed: '{}' is not an executable file", executable);
  } else {
    result.message = fmt::format(
        "CalculiX (ccx) is not installed: '{}' not found on PATH (Debian: apt-get install "
        "calculix-ccx)",
        executable);
  }
  return result;
}

FemSolution run_calculix(const FemSpecimen& specimen, const FemSettings& settings) {
  const auto start = Clock::now();
  specimen.validate();
  settings.validate();
  FemSolution solution;
  solution.element = settings.mesh.element;
  const CalculixAvailability ccx = calculix_availability(settings.executable);
  if (!ccx.available) {
    solution.message = ccx.message;
    return solution;
  }
  const FemMesh mesh = build_fem_mesh(specimen, settings.mesh);
  FemLoading loading = settings.loading;
  if (loading.end_displacement == 0) loading.end_displacement = 1e-3 * specimen.length;
  const std::string deck = calculix_input(specimen, mesh, loading, settings.element_stresses);

  const std::string dat_text = run_ccx(deck, settings, ccx, solution.solver_seconds);
  const calculix_detail::DatResults dat = calculix_detail::parse_dat(
      dat_text, mesh.node_count(), mesh.element_count(), settings.element_stresses);
  solution.end_displacement = loading.end_displacement;
  calculix_detail::measure_solution(specimen, settings, mesh, dat, solution);
  solution.available = true;
  solution.wall_seconds = seconds_since(start);
  return solution;
}

}  // namespace plydem
