#pragma once
/// \file
/// The reference of every setting, generated from the settings descriptions
/// (experiments/runner/settings_descriptions.hpp) and the kinds' registered settings
/// (ExperimentRegistry::settings): docs/settings.md is `plydem settings` (the test
/// settings_reference fails when the committed page differs), `plydem settings --json` and
/// Python's plydem.settings_reference() the same tables for scripts and tests.

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/settings.hpp"

namespace plydem {

/// One table of the reference: the settings of a command, a kind or a Python class (one or more of
/// them: the same struct).
struct SettingsTable {
  std::string id;       ///< "run", "tension", "strength", "calibrate", or a kind's name
  std::string title;    ///< the section's heading
  std::string text;     ///< a paragraph under it
  std::string command;  ///< the `plydem` command that takes them ("" = none)
  std::string kind;     ///< the experiment kind that takes them as config keys ("" = none)
  std::string python;   ///< where Python takes them ("" = nowhere)
  std::vector<SettingRow> rows;
  std::vector<std::pair<std::string, std::string>> own_keys;  ///< a kind's own keys, described
};

/// Every table, in the page's order: the run's settings (every command and kind), `plydem
/// tension`, `plydem strength`, `plydem calibrate`, then every registered kind that describes its
/// settings and is not one of the commands' kinds.
std::vector<SettingsTable> settings_tables();

/// docs/settings.md.
std::string settings_markdown();

/// The tables as JSON: [{id, title, command, kind, python, settings: [{name, type, flag, key,
/// quick_key, python, no_flag, no_key, no_python, unit, si_unit, help, choices, min, max,
/// validated_range, optional, unset, python_native, python_type, edge_inverts, default,
/// default_text, conditions}], own_keys: [[key, text]]}].
nlohmann::json settings_json();

/// A setting's value as JSON (numbers, booleans, texts, lists; null when unset).
nlohmann::json setting_value_json(const SettingValue& value);

}  // namespace plydem
