#include "experiments/runner/settings_reference.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <set>

#include "experiments/runner/experiment.hpp"
#include "experiments/runner/settings_descriptions.hpp"

namespace plydem {

namespace {

// The kinds whose settings are one of the commands' tables (the same struct, the same defaults).
const std::set<std::string> kCommandKinds{"tension", "strength"};

SettingsTable run_table() {
  const SettingsDescription<RunSettings>& d = run_settings_description();
  return {"run",
          "Every command and kind: the run",
          "The run's own settings: every command takes them (`plydem tension`, `strength`, "
          "`calibrate`, `run`), every kind's config at its top level (`plydem run --threads` wins "
          "over the config's), and Python's `tension_test()` and `strength_test()` as keywords.",
          "tension, strength, calibrate, run",
          "every kind",
          "keywords of plydem.tension_test() and plydem.strength_test()",
          d.rows(d.defaults()),
          {}};
}

SettingsTable tension_table() {
  const SettingsDescription<TensionRun>& d = tension_run_description();
  return {"tension",
          "`plydem tension`, the kind `tension`, `plydem.TensionSettings`",
          "The tension test (experiments/protocols/tension.hpp) and CalculiX of the same coupon. "
          "The kind `tension` takes the same settings as config keys, with the same defaults.",
          "tension",
          "tension",
          "plydem.TensionSettings (plydem.CouponSpec for coupon.*)",
          d.rows(d.defaults()),
          {}};
}

SettingsTable strength_table() {
  const SettingsDescription<StrengthSettings>& d = strength_settings_description();
  SettingsTable t{"strength",
                  "`plydem strength`, the kind `strength`, `plydem.StrengthSettings`",
                  "The tension test to failure (experiments/protocols/strength.hpp). The kind "
                  "`strength` takes the same settings as config keys, with the same defaults, but "
                  "the ply angle: its keys `angle_deg` and `angles_deg` give the cases.",
                  "strength",
                  "strength",
                  "plydem.StrengthSettings (plydem.CouponSpec for coupon.*)",
                  d.rows(d.defaults()),
                  {}};
  if (const auto kind = default_experiment_registry().settings("strength")) {
    t.own_keys = kind->own_keys;
  }
  return t;
}

SettingsTable calibrate_table() {
  const SettingsDescription<TensionSettings>& d = tension_settings_description();
  return {"calibrate",
          "`plydem calibrate`",
          "The calibration a coupon of these settings gets, as `plydem tension` builds it.",
          "calibrate",
          "",
          "",
          d.rows(d.defaults(), calibrate_selection()),
          {}};
}

std::string escape(std::string text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string code_or_absent(const std::string& name, const std::string& why) {
  if (!name.empty()) return fmt::format("`{}`", name);
  return why.empty() ? "—" : fmt::format("— ({})", why);
}

std::string range_text(const SettingRow& r) {
  std::vector<std::string> parts;
  if (r.choices) parts.push_back(fmt::format("{}", fmt::join(r.choices(), ", ")));
  if (r.min && r.max) {
    parts.push_back(fmt::format("{:g} to {:g}", *r.min, *r.max));
  } else if (r.min) {
    parts.push_back(fmt::format("≥ {:g}", *r.min));
  } else if (r.max) {
    parts.push_back(fmt::format("≤ {:g}", *r.max));
  }
  if (!r.validated_range.empty()) parts.push_back(r.validated_range);
  return fmt::format("{}", fmt::join(parts, "; "));
}

std::string unit_text(const SettingRow& r) {
  if (r.unit.edge == r.unit.si) return r.unit.edge;
  return fmt::format("{} (Python: {})", r.unit.edge, r.unit.si);
}

std::string default_text(const SettingRow& r) {
  if (r.optional && std::holds_alternative<std::monostate>(r.default_value)) return r.unset;
  if (r.default_text.empty()) return "\"\"";
  return fmt::format("`{}`", r.default_text);
}

std::string meaning(const SettingRow& r) {
  std::string text = r.help;
  if (!r.quick_key.empty()) text += fmt::format("; `{}` replaces it in a quick run", r.quick_key);
  if (r.python_native) text += fmt::format("; Python: {}", r.python_type);
  for (const std::string& c : r.conditions) text += fmt::format(". *{}*", c);
  return escape(text);
}

std::string command_table(const SettingsTable& t) {
  std::string md =
      "| setting | command line | config key | Python | default | unit | range, choices | what "
      "it does |\n|---|---|---|---|---|---|---|---|\n";
  for (const SettingRow& r : t.rows) {
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} |\n", r.name,
                      escape(code_or_absent(r.flag, r.no_flag)),
                      escape(code_or_absent(r.key, r.no_key)),
                      escape(code_or_absent(r.python, r.no_python)), escape(default_text(r)),
                      escape(unit_text(r)), escape(range_text(r)), meaning(r));
  }
  return md;
}

std::string kind_table(const SettingsTable& t) {
  std::string md =
      "| config key | setting | default | unit | range, choices | what it does |\n"
      "|---|---|---|---|---|---|\n";
  for (const SettingRow& r : t.rows) {
    md += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", r.key, r.name, escape(default_text(r)),
                      escape(r.unit.edge), escape(range_text(r)), meaning(r));
  }
  return md;
}

}  // namespace

std::vector<SettingsTable> settings_tables() {
  std::vector<SettingsTable> tables{run_table(), tension_table(), strength_table(),
                                    calibrate_table()};
  const ExperimentRegistry& registry = default_experiment_registry();
  for (const std::string& kind : registry.kinds()) {
    if (kCommandKinds.count(kind) > 0) continue;
    const std::optional<KindSettings> settings = registry.settings(kind);
    if (!settings) continue;
    SettingsTable t;
    t.id = kind;
    t.title = fmt::format("The kind `{}`", kind);
    t.text = registry.description(kind) + ".";
    t.kind = kind;
    for (const SettingRow& r : settings->rows)
      if (!r.key.empty()) t.rows.push_back(r);
    t.own_keys = settings->own_keys;
    tables.push_back(std::move(t));
  }
  return tables;
}

std::string settings_markdown() {
  std::string md =
      "# Settings\n\n"
      "Every setting of plydem's commands, experiment kinds and Python classes, generated by "
      "`plydem settings` from the settings descriptions (experiments/runner/"
      "settings_descriptions.cpp, core/settings.hpp): do not edit this file; the test "
      "`settings_reference` fails when it differs from what the build generates.\n\n"
      "A setting has one description and a name at each edge: its command-line flag, its key in "
      "an experiment config (TOML; dotted keys are tables: `coupon.length_mm` is `length_mm` "
      "under `[coupon]`) and its Python attribute or keyword. A setting missing at an edge says "
      "why. The command line and configs take numbers in the unit shown (mm, deg), Python in SI "
      "(m, rad). A setting given where it changes nothing is refused with the reason (\"does "
      "nothing here\"), on the command line and in configs alike.\n";
  for (const SettingsTable& t : settings_tables()) {
    md += fmt::format("\n## {}\n\n{}\n\n", t.title, t.text);
    md += t.command.empty() && t.python.empty() ? kind_table(t) : command_table(t);
    if (!t.own_keys.empty()) {
      md += fmt::format("\nKeys of the kind `{}`'s own:\n\n", t.kind);
      for (const auto& [key, text] : t.own_keys)
        md += fmt::format("- `{}`: {}\n", key, escape(text));
    }
  }
  return md;
}

nlohmann::json setting_value_json(const SettingValue& value) {
  struct Json {
    nlohmann::json operator()(std::monostate) const { return nullptr; }
    nlohmann::json operator()(bool b) const { return b; }
    nlohmann::json operator()(long i) const { return i; }
    nlohmann::json operator()(double x) const { return x; }
    nlohmann::json operator()(const std::string& s) const { return s; }
    nlohmann::json operator()(const std::vector<std::string>& list) const { return list; }
  };
  return std::visit(Json{}, value);
}

namespace {

nlohmann::json row_json(const SettingRow& r) {
  nlohmann::json j{{"name", r.name},
                   {"type", setting_type_name(r.type)},
                   {"flag", r.flag},
                   {"key", r.key},
                   {"quick_key", r.quick_key},
                   {"python", r.python},
                   {"no_flag", r.no_flag},
                   {"no_key", r.no_key},
                   {"no_python", r.no_python},
                   {"unit", r.unit.edge},
                   {"si_unit", r.unit.si},
                   {"help", r.help},
                   {"choices", r.choices ? r.choices() : std::vector<std::string>{}},
                   {"min", r.min ? nlohmann::json(*r.min) : nlohmann::json(nullptr)},
                   {"max", r.max ? nlohmann::json(*r.max) : nlohmann::json(nullptr)},
                   {"validated_range", r.validated_range},
                   {"optional", r.optional},
                   {"unset", r.unset},
                   {"python_native", r.python_native},
                   {"python_type", r.python_type},
                   {"edge_inverts", r.edge_inverts},
                   {"default", setting_value_json(r.default_value)},
                   {"default_text", r.default_text},
                   {"conditions", r.conditions}};
  return j;
}

}  // namespace

nlohmann::json settings_json() {
  nlohmann::json tables = nlohmann::json::array();
  for (const SettingsTable& t : settings_tables()) {
    nlohmann::json rows = nlohmann::json::array();
    for (const SettingRow& r : t.rows) rows.push_back(row_json(r));
    nlohmann::json own = nlohmann::json::array();
    for (const auto& [key, text] : t.own_keys) own.push_back({key, text});
    tables.push_back({{"id", t.id},
                      {"title", t.title},
                      {"command", t.command},
                      {"kind", t.kind},
                      {"python", t.python},
                      {"settings", rows},
                      {"own_keys", own}});
  }
  return tables;
}

}  // namespace plydem
