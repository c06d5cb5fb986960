#pragma once
/// \file
/// The experiment configs' edge of the settings descriptions (core/settings.hpp): a kind reads the
/// settings it takes from its config with read_config_settings, and accepts their keys with
/// config_keys (ExperimentConfig::require_known_keys: a misspelt key stays an error). A kind's own
/// defaults are the struct it reads into (a key that is not given leaves its field as it was).
///
/// A config's key holds the value in the setting's edge unit (mm, deg) as the command line does;
/// under [quick] the same key (quick_key) replaces it in a quick run (`plydem run --quick`). Bad
/// values are refused naming the file and the key; a key given where it would change nothing is
/// refused with the reason ("file.toml: 'interface.normal' does nothing here: ..."), as on the
/// command line.

#include <fmt/format.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/settings.hpp"
#include "experiments/runner/experiment.hpp"

namespace plydem {

/// The keys (and quick keys) of the fields `selection` keeps.
template <class S>
std::vector<std::string> config_keys(const SettingsDescription<S>& description,
                                     const SettingsSelection& selection = {}) {
  std::vector<std::string> keys;
  for (const SettingField<S>* f : description.selected(selection)) {
    if (!f->key.empty()) keys.push_back(f->key);
    if (!f->quick_key.empty()) keys.push_back(f->quick_key);
  }
  return keys;
}

/// The same, and a kind's own keys (KindSettings::own_keys: key and what it is).
template <class S>
std::vector<std::string> config_keys(
    const SettingsDescription<S>& description, const SettingsSelection& selection,
    const std::vector<std::pair<std::string, std::string>>& own_keys) {
  std::vector<std::string> keys = config_keys(description, selection);
  for (const auto& entry : own_keys) keys.push_back(entry.first);
  return keys;
}

/// A setting's value as `config` gives it under `key`, in the edge's unit (ExperimentConfig's
/// getters refuse a value of the wrong type, naming the file and the key).
SettingValue config_edge_value(const ExperimentConfig& config, const SettingInfo& info,
                               const std::string& key);

/// Sets a field's value, an error of the setter naming the file and the key.
template <class S>
void set_from_config(const ExperimentConfig& config, const SettingField<S>& field,
                     const std::string& key, S& settings) {
  const std::string origin = config.path().string();
  const std::string what = fmt::format("{}: {}", origin, key);
  const SettingValue value =
      setting_struct_value(field, config_edge_value(config, field, key), what);
  try {
    field.set(settings, value, what);
  } catch (const Error& e) {
    const std::string message = e.what();
    if (message.rfind(origin, 0) == 0) throw;
    throw Error(fmt::format("{}: {}", what, message));
  }
}

/// Reads the fields of `selection` that `config` gives into `settings` (in declaration order; in a
/// `quick` run a field's quick key, where given, instead of its key), then refuses the first given
/// key whose conditions `settings` does not meet (but those `selection` leaves unchecked).
template <class S>
void read_config_settings(const ExperimentConfig& config, const SettingsDescription<S>& description,
                          const SettingsSelection& selection, bool quick, S& settings) {
  std::map<std::string, std::string> given;  // field name -> the key it was read from
  for (const SettingField<S>* f : description.selected(selection)) {
    std::string key;
    if (quick && !f->quick_key.empty() && config.contains(f->quick_key)) {
      key = f->quick_key;
    } else if (!f->key.empty() && config.contains(f->key)) {
      key = f->key;
    } else {
      continue;
    }
    set_from_config(config, *f, key, settings);
    given[f->name] = key;
  }
  const std::string origin = config.path().string();
  description.refuse_inapplicable(
      settings,
      [&](const SettingField<S>& f) { return given.count(f.name) > 0 && selection.checks(f.name); },
      SettingEdge::kConfig,
      [&](const SettingField<S>& f) { return fmt::format("{}: '{}'", origin, given.at(f.name)); });
}

}  // namespace plydem
