#include "strategies/registry.hpp"

#include <fmt/format.h>

#include <map>
#include <mutex>

namespace plydem {

Registry::Registry()
    : FactoryRegistry<Strategy>({"strategy", "a strategy needs a name",
                                 "a strategy named '{}' is already registered",
                                 "unknown strategy '{}'; registered strategies: {}"}) {}

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
