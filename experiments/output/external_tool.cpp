#include "experiments/output/external_tool.hpp"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string_view>

#include "core/error.hpp"

namespace plydem {

namespace fs = std::filesystem;

std::optional<std::string> find_executable(const std::string& executable) {
  auto runnable = [](const fs::path& path) {
    std::error_code ec;
    return fs::is_regular_file(path, ec) && ::access(path.c_str(), X_OK) == 0;
  };
  if (executable.empty()) return std::nullopt;
  if (executable.find('/') != std::string::npos) {
    if (runnable(executable)) return executable;
    return std::nullopt;
  }
  const char* path_env = std::getenv("PATH");
  std::string_view path_list = path_env ? path_env : "";
  while (!path_list.empty()) {
    const auto colon = path_list.find(':');
    const std::string_view dir = path_list.substr(0, colon);
    const fs::path candidate = fs::path(dir.empty() ? "." : std::string(dir)) / executable;
    if (runnable(candidate)) return candidate.string();
    if (colon == std::string_view::npos) break;
    path_list.remove_prefix(colon + 1);
  }
  return std::nullopt;
}

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) {
    if (c == '\'')
      quoted += "'\\''";
    else
      quoted += c;
  }
  quoted += '\'';
  return quoted;
}

GnuplotAvailability gnuplot_availability(const std::string& executable) {
  GnuplotAvailability result;
  const std::optional<std::string> path = find_executable(executable);
  if (!path) {
    result.message = fmt::format(
        "gnuplot is not installed: '{}' not found (Debian: apt-get install gnuplot-nox)",
        executable);
    return result;
  }
  result.available = true;
  result.executable = *path;
  return result;
}

void run_gnuplot(const std::string& script, const fs::path& directory,
                 const std::string& script_name) {
  const GnuplotAvailability gnuplot = gnuplot_availability();
  if (!gnuplot.available) throw Error(gnuplot.message);
  const fs::path script_path = directory / script_name;
  {
    std::ofstream file(script_path, std::ios::binary);
    file << script;
    if (!file) throw Error(fmt::format("cannot write {}", script_path.string()));
  }
  const fs::path log_path = directory / fmt::format("{}.log", script_name);
  const std::string command = fmt::format(
      "cd {} && {} {} > {} 2>&1", shell_quote(directory.string()), shell_quote(gnuplot.executable),
      shell_quote(script_name), shell_quote(log_path.filename().string()));
  const int status = std::system(command.c_str());
  const int exit_code = status == -1 ? -1 : (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  std::ostringstream log;
  if (std::ifstream in(log_path); in) log << in.rdbuf();
  if (exit_code != 0) {
    throw Error(fmt::format("gnuplot failed on {} (exit code {}):\n{}", script_path.string(),
                            exit_code, log.str()));
  }
  std::error_code ec;
  if (log.str().empty()) fs::remove(log_path, ec);
}

}  // namespace plydem
