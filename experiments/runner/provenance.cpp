#include "experiments/runner/provenance.hpp"

#include <fmt/format.h>

#include <fstream>
#include <iterator>
#include <vector>

#include "experiments/runner/run_experiment.hpp"

namespace plydem {

namespace {

// This process's arguments (Linux: /proc/self/cmdline, NUL-separated); empty where unreadable.
std::vector<std::string> process_arguments() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> args;
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\0', begin);
    if (end == std::string::npos) end = text.size();
    args.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return args;
}

std::string shell_quote(const std::string& arg) {
  const bool plain = !arg.empty() && arg.find_first_not_of(
                                         "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                         "0123456789_-+=./,:@%^") == std::string::npos;
  if (plain) return arg;
  std::string quoted = "'";
  for (const char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace

std::string shell_command_line(const std::vector<std::string>& args) {
  std::string line;
  for (const std::string& arg : args) {
    if (!line.empty()) line += ' ';
    line += shell_quote(arg);
  }
  return line;
}

Provenance provenance() {
  Provenance p;
  p.version = build_project_version();
  p.git = build_git_version();
  p.commit = build_git_commit();
  p.compiler = build_compiler();
  p.build_type = build_type();
  p.cuda = build_has_cuda();
  p.petsc = build_petsc_version();
  p.python = build_python_version();
  p.command_line = shell_command_line(process_arguments());
  return p;
}

nlohmann::json provenance_json() {
  const Provenance p = provenance();
  const auto version_or_false = [](const std::string& v) {
    return v.empty() ? nlohmann::json(false) : nlohmann::json(v);
  };
  return {{"version", p.version},
          {"git", p.git},
          {"commit", p.commit},
          {"compiler", p.compiler},
          {"build_type", p.build_type},
          {"backends",
           {{"cuda", p.cuda},
            {"petsc", version_or_false(p.petsc)},
            {"python", version_or_false(p.python)}}},
          {"command_line", p.command_line}};
}

std::string version_text() {
  const Provenance p = provenance();
  std::string text = fmt::format("plydem {}\n", plydem_version());
  text +=
      fmt::format("commit:   {}\n", p.commit.empty() ? "unknown (not built from git)" : p.commit);
  text += fmt::format("compiler: {} ({} build, C++20)\n", p.compiler, p.build_type);
  text += fmt::format("backends: CUDA {}, PETSc {}, Python {}\n",
                      p.cuda ? "yes (--backend cuda)" : "no",
                      p.petsc.empty() ? "no" : p.petsc + " (--linear-solver petsc, mpiexec)",
                      p.python.empty() ? "no" : p.python + " (import plydem, --plugin FILE.py)");
  text += "plug-ins: C++ shared libraries (--plugin libNAME.so, PLYDEM_PLUGIN_PATH)\n";
  return text;
}

}  // namespace plydem
