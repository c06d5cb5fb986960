#pragma once
/// \file
/// Factories of T by name: the one registry behind the strategies (strategies/registry.hpp) and
/// the experiment kinds (experiments/runner/experiment.hpp). Each names its entries in its own
/// words (RegistryWording), so its errors read as the user's terms.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace plydem {

/// What a registry calls its entries, in the words of its errors.
struct RegistryWording {
  std::string noun;        ///< "strategy": "unknown strategy 'x'", "strategy 'x' has no factory"
  std::string needs_name;  ///< the refusal of an empty name
  std::string taken;       ///< the refusal of a taken name; {} is the name
  std::string unknown;     ///< an unknown name; {} is the name, the second {} the registered ones
};

template <class T>
class FactoryRegistry {
 public:
  using Factory = std::function<std::unique_ptr<T>()>;

  explicit FactoryRegistry(RegistryWording wording) : wording_(std::move(wording)) {}

  /// Adds an entry; throws plydem::Error if the name is empty or taken or the factory is empty.
  void add(const std::string& name, const std::string& description, Factory factory) {
    if (name.empty()) throw Error(wording_.needs_name);
    if (factory == nullptr) throw Error(fmt::format("{} '{}' has no factory", wording_.noun, name));
    if (contains(name)) throw Error(fmt::format(fmt::runtime(wording_.taken), name));
    entries_.emplace(name, Entry{description, std::move(factory)});
  }

  bool contains(const std::string& name) const { return entries_.count(name) > 0; }

  /// A new instance; throws plydem::Error listing the registered names if `name` is unknown.
  std::unique_ptr<T> create(const std::string& name) const {
    const auto it = entries_.find(name);
    if (it == entries_.end()) {
      throw Error(fmt::format(fmt::runtime(wording_.unknown), name, fmt::join(names(), ", ")));
    }
    return it->second.factory();
  }

  /// The registered names, in alphabetical order.
  std::vector<std::string> names() const {
    std::vector<std::string> result;
    for (const auto& entry : entries_) result.push_back(entry.first);
    return result;
  }

  /// The one-line description `name` was added with; throws plydem::Error if `name` is unknown.
  std::string description(const std::string& name) const {
    const auto it = entries_.find(name);
    if (it == entries_.end()) throw Error(fmt::format("unknown {} '{}'", wording_.noun, name));
    return it->second.description;
  }

 private:
  struct Entry {
    std::string description;
    Factory factory;
  };
  RegistryWording wording_;
  std::map<std::string, Entry> entries_;
};

}  // namespace plydem
