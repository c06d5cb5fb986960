#include "strategies/registry.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <mutex>

#include "core/error.hpp"

namespace plydem {

void Registry::add(const std::string& name, const std::string& description,
                   StrategyFactory factory) {
  require(!name.empty(), "a strategy needs a name");
  require(factory != nullptr, fmt::format("strategy '{}' has no factory", name));
  require(!contains(name), fmt::format("a strategy named '{}' is already registered", name));
  entries_.emplace(name, Entry{description, std::move(factory)});
}

bool Registry::contains(const std::string& name) const {
  return entries_.count(name) > 0;
}

std::unique_ptr<Strategy> Registry::create(const std::string& name) const {
  const auto it = entries_.find(name);
  require(it != entries_.end(), fmt::format("unknown strategy '{}'; registered strategies: {}",
                                            name, fmt::join(names(), ", ")));
  return it->second.factory();
}

std::vector<std::string> Registry::names() const {
  std::vector<std::string> result;
  for (const auto& entry : entries_) result.push_back(entry.first);
  return result;
}

std::string Registry::description(const std::string& name) const {
  const auto it = entries_.find(name);
  require(it != entries_.end(), fmt::format("unknown strategy '{}'", name));
  return it->second.description;
}

namespace {

thread_local int lookup_depth = 0;

}  // namespace

bool inside_representation_lookup() {
  return lookup_depth > 0;
}

std::vector<std::string> strategies_representing(const Registry& registry, const Material& material,
                                                 double ply_angle, double thickness,
                                                 const std::string& except) {
  static std::mutex mutex;
  static std::map<std::string, bool> remembered;  // registry|strategy|ply -> represents
  const std::string ply =
      fmt::format("{}|{:a} {:a} {:a} {:a} {:a}|{:a}|{:a}", material.name, material.E1, material.E2,
                  material.G12, material.nu12, material.nu23, ply_angle, thickness);
  std::vector<std::string> result;
  for (const std::string& name : registry.names()) {
    if (name == except) continue;
    const std::string key = fmt::format("{}|{}|{}", static_cast<const void*>(&registry), name, ply);
    {
      const std::lock_guard<std::mutex> lock(mutex);
      const auto it = remembered.find(key);
      if (it != remembered.end()) {
        if (it->second) result.push_back(name);
        continue;
      }
    }
    bool represents = false;
    ++lookup_depth;
    try {
      const Calibration cal = registry.create(name)->calibrate(material, ply_angle, thickness);
      represents = cal.relaxed_error < 1e-6;
    } catch (...) {
      represents = false;  // a refusal, whatever its words (a Python strategy's included)
    }
    --lookup_depth;
    {
      const std::lock_guard<std::mutex> lock(mutex);
      remembered[key] = represents;
    }
    if (represents) result.push_back(name);
  }
  return result;
}

Registry& default_registry() {
  static Registry registry = [] {
    Registry r;
    register_builtin_strategies(r);
    return r;
  }();
  return registry;
}

}  // namespace plydem
