#include "experiments/cli/plugins.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>

#include "core/error.hpp"
#include "experiments/cli/python_plugin.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/plugin.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "strategies/registry.hpp"

namespace plydem::cli {

namespace {

void load_plugin(const std::filesystem::path& file) {
  if (file.extension() == ".py") {
    load_python_plugin(file.string());
  } else if (is_shared_library_name(file)) {
    load_plugin_library(file, {default_registry(), default_experiment_registry()},
                        build_project_version());
  } else {
    throw Error(fmt::format(
        "--plugin {}: neither a Python file (.py) nor a shared library (.so) of plydem plug-ins",
        file.string()));
  }
}

}  // namespace

void load_plugins(const std::vector<std::string>& files) {
  if (const char* plugin_path = std::getenv("PLYDEM_PLUGIN_PATH")) {
    for (const std::filesystem::path& file : plugin_path_files(plugin_path)) load_plugin(file);
  }
  for (const std::string& file : files) load_plugin(file);
}

}  // namespace plydem::cli
