#include "strategies/registry.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

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

Registry& default_registry() {
  static Registry registry = [] {
    Registry r;
    register_builtin_strategies(r);
    return r;
  }();
  return registry;
}

}  // namespace plydem
