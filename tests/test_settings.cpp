// Every setting declared once (core/settings.hpp, experiments/runner/settings_descriptions.hpp):
// each described setting has a name at every edge or says why not; parsing its command-line flag
// sets its field (experiments/cli/settings_cli.hpp); its config key is read by the description's
// reader (experiments/runner/settings_config.hpp) and known to every kind that takes it; a kind
// that runs a command's test starts from the command's defaults. tests/python/test_settings.py
// checks Python and the real `plydem --help` against the same descriptions.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/cli/settings_cli.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "experiments/runner/settings_reference.hpp"
#include "solvers/linear_solver.hpp"

using namespace plydem;

namespace {

// A value of `f` other than its default `edge_default`, as the command line and configs take it.
SettingValue sample(const SettingInfo& f, const SettingValue& edge_default) {
  const std::string name = f.name;
  switch (f.type) {
    case SettingType::kSwitch:
      return !std::get<bool>(edge_default);
    case SettingType::kInteger: {
      long v = std::get<long>(edge_default) + 1;
      if (f.max && static_cast<double>(v) > *f.max) v = static_cast<long>(*f.min);
      return v;
    }
    case SettingType::kNumber: {
      if (std::holds_alternative<std::monostate>(edge_default)) return 8.0;
      double v = std::get<double>(edge_default) + 0.25;
      if (f.max && v > *f.max) v = *f.min;
      return v;
    }
    case SettingType::kTexts:
      return std::vector<std::string>{"c=1.8"};
    case SettingType::kText:
      break;
  }
  const std::string current = std::get<std::string>(edge_default);
  if (f.choices) {
    for (const std::string& c : f.choices())
      if (c != current && !(c == "petsc" && !petsc_available())) return c;
  }
  if (name == "material") {
    for (const std::string& m : builtin_material_names())
      if (m != current) return m;
  }
  if (name == "layup") return std::string(current.empty() ? "[0/90]" : "[0_4]");
  if (name == "strategy") return std::string(current == "square" ? "hex2d" : "square");
  return current + "x";
}

// The command-line arguments that give `value` to `f`.
std::vector<std::string> arguments(const SettingInfo& f, const SettingValue& value) {
  if (f.type == SettingType::kSwitch) return {f.flag};
  if (const auto* list = std::get_if<std::vector<std::string>>(&value)) {
    std::vector<std::string> args;
    for (const std::string& item : *list) args.insert(args.end(), {f.flag, item});
    return args;
  }
  if (const double* x = std::get_if<double>(&value)) return {f.flag, fmt::format("{:.17g}", *x)};
  return {f.flag, format_setting_value(value)};
}

// The field's value (as text) when `edge` is set on `defaults` without any edge.
template <class S>
std::string set_directly(const SettingField<S>& f, S settings, const SettingValue& edge) {
  f.set(settings, setting_struct_value(f, edge, "test"), "test");
  return format_setting_value(f.get(settings));
}

// Every field of `d` has a name at each edge, or a reason why not; names are unique per edge.
template <class S>
void check_edges(const SettingsDescription<S>& d) {
  std::set<std::string> flags, keys, pythons;
  for (const SettingField<S>& f : d.fields()) {
    INFO(f.name);
    CHECK(!f.help.empty());
    CHECK((!f.flag.empty() || !f.no_flag.empty()));
    CHECK((!f.key.empty() || !f.no_key.empty()));
    CHECK((!f.python.empty() || !f.no_python.empty()));
    if (!f.flag.empty()) CHECK(flags.insert(f.flag).second);
    if (!f.key.empty()) CHECK(keys.insert(f.key).second);
    if (!f.python.empty()) CHECK(pythons.insert(f.python).second);
    CHECK(f.get);
    CHECK(f.set);
  }
}

// Parsing each flag of `d` with a value other than its default sets its field to that value.
template <class S>
void check_command_line(const SettingsDescription<S>& d, const std::string& command) {
  const S defaults = d.defaults();
  for (const SettingField<S>& f : d.fields()) {
    if (f.flag.empty()) continue;
    INFO(f.flag);
    const SettingValue edge = sample(f, setting_edge_value(f, f.get(defaults)));
    CLI::App app;
    cli::CommandLineSettings<S> options(app, d, command);
    CHECK(app.help().find(f.flag) != std::string::npos);
    std::vector<std::string> args = arguments(f, edge);
    std::reverse(args.begin(), args.end());  // CLI11 parses a vector from its back
    app.parse(args);
    CHECK(options.given(f.name));
    S s = defaults;
    options.apply(s);
    CHECK(format_setting_value(f.get(s)) == set_directly(f, defaults, edge));
    CHECK(format_setting_value(f.get(s)) != format_setting_value(f.get(defaults)));
  }
}

// A value in TOML's syntax.
std::string toml_literal(const SettingValue& value) {
  if (const auto* s = std::get_if<std::string>(&value)) return fmt::format("\"{}\"", *s);
  if (const auto* list = std::get_if<std::vector<std::string>>(&value)) {
    std::string out = "[";
    for (const std::string& item : *list) out += fmt::format("\"{}\", ", item);
    return out + "]";
  }
  if (const double* x = std::get_if<double>(&value)) return fmt::format("{:.17g}", *x);
  return format_setting_value(value);
}

// A value of another TOML type than the setting's.
std::string wrong_type(SettingType type) {
  return type == SettingType::kText || type == SettingType::kTexts ? "1.5" : "\"text\"";
}

// Each config key of `d` (and quick key) given a value other than its default sets the field.
template <class S>
void check_config(const SettingsDescription<S>& d) {
  const S defaults = d.defaults();
  for (const SettingField<S>& f : d.fields()) {
    for (const bool quick : {false, true}) {
      const std::string key = quick ? f.quick_key : f.key;
      if (key.empty()) continue;
      INFO(key);
      const SettingValue edge = sample(f, setting_edge_value(f, f.get(defaults)));
      const std::string text = fmt::format("{} = {}\n", key, toml_literal(edge));
      S s = defaults;
      // Conditions aside (a key may be refused where it does nothing), the value is set.
      try {
        read_config_settings(ExperimentConfig::parse(text, "t.toml"), d, {}, quick, s);
      } catch (const Error& e) {
        const std::string message = e.what();
        CHECK((message.find("does nothing here") != std::string::npos ||
               message.find("' needs ") != std::string::npos));
      }
      CHECK(format_setting_value(f.get(s)) == set_directly(f, defaults, edge));
    }
  }
}

// A config of `kind` that it accepts but for `line` (the keys a kind requires added).
std::string kind_config(const std::string& kind, const std::string& line) {
  std::string text = fmt::format("experiment = \"{}\"\n", kind);
  const std::vector<std::pair<std::string, std::string>> required{
      {"laminate", "layup = \"[0/90]\""},
      {"dcb", "interface.strength_normal = 40e6"},
      {"dcb", "interface.GIc = 250"}};
  const std::string key = line.substr(0, line.find(' '));
  for (const auto& [for_kind, entry] : required) {
    if (for_kind == kind && entry.substr(0, entry.find(' ')) != key) text += entry + "\n";
  }
  return text + line + "\n";
}

}  // namespace

TEST_CASE("every described setting is named at each edge or says why not") {
  check_edges(run_settings_description());
  check_edges(coupon_settings_description());
  check_edges(tension_settings_description());
  check_edges(tension_run_description());
  check_edges(strength_settings_description());
  check_edges(dcb_settings_description());
}

TEST_CASE("every command-line flag of a description sets its field") {
  check_command_line(run_settings_description(), "tension");
  check_command_line(tension_run_description(), "tension");
  check_command_line(strength_settings_description(), "strength");
}

TEST_CASE("every config key of a description sets its field, [quick] keys in a quick run") {
  check_config(run_settings_description());
  check_config(tension_run_description());
  check_config(strength_settings_description());
  check_config(dcb_settings_description());
}

TEST_CASE("every kind knows and reads every key it describes, and the run's keys") {
  ExperimentRegistry& registry = default_experiment_registry();
  ExperimentContext context;
  context.out_dir = ".";
  int kinds = 0;
  for (const std::string& kind : registry.kinds()) {
    const std::optional<KindSettings> settings = registry.settings(kind);
    if (!settings) continue;
    ++kinds;
    std::vector<std::string> keys;
    for (const SettingRow& row : settings->rows) {
      if (!row.key.empty()) keys.push_back(row.key);
      if (!row.quick_key.empty()) keys.push_back(row.quick_key);
      INFO(kind, ": ", row.key, " = ", row.default_text);
      // A value of the wrong type is refused naming the key: the kind reads it.
      for (const bool quick : {false, true}) {
        const std::string key = quick ? row.quick_key : row.key;
        if (key.empty()) continue;
        ExperimentContext c = context;
        c.quick = quick;
        const std::string text =
            kind_config(kind, fmt::format("{} = {}", key, wrong_type(row.type)));
        const std::unique_ptr<Experiment> experiment = registry.create(kind);
        CHECK_THROWS_WITH_AS(experiment->check(ExperimentConfig::parse(text, "t.toml"), c),
                             doctest::Contains(key.c_str()), Error);
      }
    }
    // The run's keys are every kind's (run_experiment reads them).
    for (const SettingRow& row : run_settings_description().rows(RunSettings{})) {
      INFO(kind, ": ", row.key);
      const std::string text =
          kind_config(kind, fmt::format("{} = {}", row.key, toml_literal(row.default_value)));
      CHECK_NOTHROW(registry.create(kind)->check(ExperimentConfig::parse(text, "t.toml"), context));
    }
    // An unknown key is still an error.
    CHECK_THROWS_WITH_AS(
        registry.create(kind)->check(
            ExperimentConfig::parse(kind_config(kind, "nosuch_key = 1"), "t.toml"), context),
        doctest::Contains("unknown key 'nosuch_key'"), Error);
  }
  CHECK(kinds >= 4);
}

TEST_CASE("plydem run reads the run's keys of every config before it writes anything") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "plydem_settings_run";
  std::filesystem::create_directories(dir);
  for (const SettingRow& row : run_settings_description().rows(RunSettings{})) {
    INFO(row.key);
    const std::filesystem::path config = dir / "run_key.toml";
    std::ofstream(config) << fmt::format("experiment = \"tension\"\n{} = {}\n", row.key,
                                         wrong_type(row.type));
    RunOptions options;
    options.config = config;
    options.out_dir = dir / "out";
    CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains(row.key.c_str()), Error);
    CHECK_FALSE(std::filesystem::exists(options.out_dir));
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("the kinds of the commands start from the commands' defaults") {
  const std::vector<SettingsTable> tables = settings_tables();
  ExperimentRegistry& registry = default_experiment_registry();
  for (const std::string id : {"tension", "strength"}) {
    const auto table = std::find_if(tables.begin(), tables.end(),
                                    [&](const SettingsTable& t) { return t.id == id; });
    REQUIRE(table != tables.end());
    const std::optional<KindSettings> kind = registry.settings(id);
    REQUIRE(kind);
    int compared = 0;
    for (const SettingRow& row : kind->rows) {
      const auto command = std::find_if(table->rows.begin(), table->rows.end(),
                                        [&](const SettingRow& r) { return r.name == row.name; });
      REQUIRE(command != table->rows.end());
      INFO(id, ": ", row.name);
      CHECK(row.default_text == command->default_text);
      ++compared;
    }
    CHECK(compared >= 20);
  }
}

TEST_CASE("refusals name each edge's setting: --layup on the command line, layup in configs") {
  const SettingsDescription<TensionRun>& d = tension_run_description();
  CLI::App app;
  cli::CommandLineSettings<TensionRun> options(app, d, "tension");
  app.parse(std::vector<std::string>{"0.5", "--damping"});
  CHECK_THROWS_WITH_AS(options.settings(),
                       "--damping does nothing here: it is a setting of explicit dynamics, and the "
                       "static solver (--solver static, the default) solves once at the target "
                       "strain (add --solver explicit)",
                       Error);
  TensionRun run = d.defaults();
  CHECK_THROWS_WITH_AS(
      read_config_settings(ExperimentConfig::parse("explicit.damping = 0.5\n", "t.toml"), d, {},
                           false, run),
      "t.toml: 'explicit.damping' does nothing here: it is a setting of explicit dynamics, and the "
      "static solver (solver = \"static\", the default) solves once at the target strain (add "
      "solver = \"explicit\")",
      Error);
  CHECK_THROWS_WITH_AS(
      read_config_settings(ExperimentConfig::parse("coupon.grips = \"loose\"\n", "t.toml"), d, {},
                           false, run),
      "t.toml: coupon.grips must be \"free\" or \"clamped\", got \"loose\"", Error);
}

TEST_CASE("units convert at the edges as the command line always did") {
  const SettingsDescription<TensionRun>& d = tension_run_description();
  CLI::App app;
  cli::CommandLineSettings<TensionRun> options(app, d, "tension");
  app.parse(std::vector<std::string>{"2.5", "--width-mm", "30", "--angle", "--raw-edges"});
  const TensionRun run = options.settings();
  CHECK(run.test.coupon.ply_angle == 30 * std::numbers::pi / 180.0);
  CHECK(run.test.coupon.width == 2.5 * 1e-3);
  CHECK_FALSE(run.test.coupon.complete_boundary_cells);
  CHECK(options.edge_number("angle") == 30);
  // Untouched settings keep the description's defaults exactly.
  CHECK(run.test.coupon.length == TensionSettings{}.coupon.length);
}

TEST_CASE("the reference page lists every setting of the commands and kinds") {
  const std::string md = settings_markdown();
  for (const SettingsTable& t : settings_tables()) {
    INFO(t.id);
    CHECK(md.find(t.title) != std::string::npos);
    for (const SettingRow& r : t.rows) {
      if (!r.flag.empty()) CHECK(md.find("`" + r.flag + "`") != std::string::npos);
      if (!r.key.empty()) CHECK(md.find("`" + r.key + "`") != std::string::npos);
    }
  }
  CHECK(md.find("`--threads`") != std::string::npos);
}
