#pragma once
/// \file
/// Which plydem produced a result, and how: the version, git commit, compiler and backends of
/// this build (CMake writes them into the generated build_info.cpp at configure time) and the
/// command line of this process. `plydem --version` prints them; every JSON object the command
/// line prints carries provenance_json() under "provenance"; report.md lists them and
/// provenance.json beside results.csv holds them (run_experiment.hpp, write_run_report).

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace plydem {

struct Provenance {
  std::string version;       ///< the project version, e.g. "0.1.0"
  std::string git;           ///< `git describe --always --dirty`; empty outside git
  std::string commit;        ///< the full commit hash; empty outside git
  std::string compiler;      ///< e.g. "GNU 12.2.0"
  std::string build_type;    ///< e.g. "Release"
  bool cuda = false;         ///< the CUDA backend of the explicit integrator is built
  std::string petsc;         ///< PETSc's version where --linear-solver petsc is built, else empty
  std::string python;        ///< Python's version where the Python module is built, else empty
  std::string command_line;  ///< this process's arguments, shell-quoted (/proc/self/cmdline)
};

/// This build's facts and this process's command line.
Provenance provenance();

/// provenance() as a JSON object: version, git, commit, compiler, build_type, backends (cuda,
/// petsc, python: false or the version) and command_line.
nlohmann::json provenance_json();

/// `plydem --version`: a line with the version, then commit, compiler and backends.
std::string version_text();

/// `args` joined by spaces, each quoted for a POSIX shell where it needs it.
std::string shell_command_line(const std::vector<std::string>& args);

/// Facts CMake writes into the generated build_info.cpp beside those of run_experiment.hpp
/// (build_git_version, build_project_version).
const char* build_git_commit();
const char* build_compiler();
const char* build_type();
bool build_has_cuda();
const char* build_petsc_version();
const char* build_python_version();

}  // namespace plydem
