#include "experiments/runner/plugin.hpp"

#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <exception>
#include <iterator>
#include <string_view>

#include "core/error.hpp"

namespace fs = std::filesystem;

namespace plydem {

namespace {

using PluginEntry = void (*)(PluginRegistries&);

// The names in `after` that `before` lacks (both sorted, as names() returns them).
std::vector<std::string> added_names(const std::vector<std::string>& before,
                                     const std::vector<std::string>& after) {
  std::vector<std::string> added;
  std::set_difference(after.begin(), after.end(), before.begin(), before.end(),
                      std::back_inserter(added));
  return added;
}

// The library's symbol `name`, or nullptr.
void* symbol(void* library, const char* name) {
  dlerror();
  return dlsym(library, name);
}

}  // namespace

bool is_shared_library_name(const fs::path& file) {
  const std::string name = file.filename().string();
  const std::size_t so = name.find(".so");
  if (so == std::string::npos || so == 0) return false;
  const std::string_view rest = std::string_view(name).substr(so + 3);
  // NAME.so, or a versioned NAME.so.1.2
  return rest.empty() ||
         (rest.front() == '.' && rest.find_first_not_of(".0123456789") == std::string_view::npos);
}

LoadedPlugin load_plugin_library(const fs::path& file, PluginRegistries registries,
                                 const std::string& this_version) {
  const std::string what = fmt::format("plug-in {}", file.string());
  require(fs::is_regular_file(file),
          fmt::format("{}: no such file (a shared library built with PLYDEM_PLUGIN, "
                      "experiments/runner/plugin.hpp)",
                      what));
  // RTLD_NOW: an undefined symbol is refused here, with its name, not at its first call.
  void* library = dlopen(fs::absolute(file).c_str(), RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) {
    const char* reason = dlerror();
    throw Error(fmt::format("{}: cannot be loaded: {}", what, reason ? reason : "unknown reason"));
  }
  const auto* version = static_cast<const char*>(symbol(library, plugin_version_symbol));
  const auto entry = reinterpret_cast<PluginEntry>(symbol(library, plugin_entry_symbol));
  if (version == nullptr || entry == nullptr) {
    dlclose(library);
    throw Error(fmt::format(
        "{}: not a plydem plug-in: it exports no {} (a plug-in ends with PLYDEM_PLUGIN(its "
        "registration function), from experiments/runner/plugin.hpp)",
        what, version == nullptr ? plugin_version_symbol : plugin_entry_symbol));
  }
  if (std::string_view(version) != this_version) {
    const std::string built_against = version;
    dlclose(library);
    throw Error(fmt::format(
        "{}: built against plydem {}, but this is plydem {}: rebuild it against this plydem "
        "(find_package(plydem {}))",
        what, built_against, this_version, this_version));
  }
  const std::vector<std::string> strategies = registries.strategies.names();
  const std::vector<std::string> experiments = registries.experiments.names();
  // The library is never closed from here on: what it registered may point into its code.
  try {
    entry(registries);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: its registration failed: {}", what, e.what()));
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: its registration raised: {}", what, e.what()));
  }
  return {file, added_names(strategies, registries.strategies.names()),
          added_names(experiments, registries.experiments.names())};
}

std::vector<fs::path> plugin_path_files(const std::string& plugin_path) {
  std::vector<fs::path> files;
  std::size_t begin = 0;
  while (begin <= plugin_path.size()) {
    std::size_t end = plugin_path.find(':', begin);
    if (end == std::string::npos) end = plugin_path.size();
    const fs::path entry = plugin_path.substr(begin, end - begin);
    begin = end + 1;
    if (entry.empty()) continue;
    if (fs::is_directory(entry)) {
      std::vector<fs::path> libraries;
      for (const fs::directory_entry& f : fs::directory_iterator(entry)) {
        if (f.is_regular_file() && is_shared_library_name(f.path())) libraries.push_back(f.path());
      }
      std::sort(libraries.begin(), libraries.end());
      files.insert(files.end(), libraries.begin(), libraries.end());
    } else {
      require(
          fs::is_regular_file(entry),
          fmt::format("PLYDEM_PLUGIN_PATH: '{}' is neither a file nor a folder", entry.string()));
      files.push_back(entry);
    }
  }
  return files;
}

}  // namespace plydem
