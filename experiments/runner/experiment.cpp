#include "experiments/runner/experiment.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/toml_reader.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"

namespace plydem {

struct ExperimentConfig::Data {
  toml::table table;
  std::string origin;
};

namespace {

std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    default:
      return "a date or time";
  }
}

Error wrong_type(const std::string& origin, const std::string& key, const toml::node& node,
                 const std::string& expected) {
  return Error(
      fmt::format("{}: key '{}' must be {}, got {}", origin, key, expected, type_name(node)));
}

void collect_keys(const toml::table& table, const std::string& prefix,
                  std::vector<std::string>& keys) {
  for (const auto& [key, node] : table) {
    const std::string name =
        prefix.empty() ? std::string(key.str()) : fmt::format("{}.{}", prefix, key.str());
    keys.push_back(name);
    if (const auto* sub = node.as_table()) collect_keys(*sub, name, keys);
  }
}

}  // namespace

ExperimentConfig ExperimentConfig::load(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) {
    throw Error(
        fmt::format("experiment config '{}' cannot be read (no such file?)", path.string()));
  }
  std::ostringstream text;
  text << in.rdbuf();
  ExperimentConfig config = parse(text.str(), path.string());
  config.path_ = path;
  return config;
}

ExperimentConfig ExperimentConfig::parse(const std::string& text, const std::string& origin) {
  auto data = std::make_shared<Data>();
  data->origin = origin;
  data->table = parse_toml(text, origin, [&origin](const TomlSyntaxError& e) {
    return fmt::format("{}:{}:{}: malformed TOML: {}", origin, e.line, e.column, e.description);
  });
  ExperimentConfig config;
  config.data_ = std::move(data);
  config.path_ = origin;
  return config;
}

const std::filesystem::path& ExperimentConfig::path() const {
  return path_;
}

std::string ExperimentConfig::name() const {
  return path_.stem().string();
}

std::string ExperimentConfig::kind() const {
  if (!contains("experiment")) {
    throw Error(
        fmt::format("{}: the key 'experiment' (the kind of experiment) is missing", data_->origin));
  }
  return string("experiment", "");
}

std::string ExperimentConfig::description() const {
  return string("description", "");
}

bool ExperimentConfig::contains(const std::string& key) const {
  return static_cast<bool>(data_->table.at_path(key));
}

std::string ExperimentConfig::string(const std::string& key, const std::string& fallback) const {
  const toml::node_view<const toml::node> node = data_->table.at_path(key);
  if (!node) return fallback;
  if (const auto* v = node.node()->as_string()) return v->get();
  throw wrong_type(data_->origin, key, *node.node(), "a string");
}

double ExperimentConfig::number(const std::string& key, double fallback) const {
  const toml::node_view<const toml::node> node = data_->table.at_path(key);
  if (!node) return fallback;
  const std::optional<double> value = toml_number(*node.node());
  if (!value) throw wrong_type(data_->origin, key, *node.node(), "a number");
  if (!std::isfinite(*value)) {
    throw Error(fmt::format("{}: key '{}' must be finite, got {}", data_->origin, key, *value));
  }
  return *value;
}

long ExperimentConfig::integer(const std::string& key, long fallback) const {
  const toml::node_view<const toml::node> node = data_->table.at_path(key);
  if (!node) return fallback;
  const auto* v = node.node()->as_integer();
  if (!v) throw wrong_type(data_->origin, key, *node.node(), "an integer");
  if (v->get() < 0) {
    throw Error(
        fmt::format("{}: key '{}' must not be negative, got {}", data_->origin, key, v->get()));
  }
  return static_cast<long>(v->get());
}

bool ExperimentConfig::boolean(const std::string& key, bool fallback) const {
  const toml::node_view<const toml::node> node = data_->table.at_path(key);
  if (!node) return fallback;
  if (const auto* v = node.node()->as_boolean()) return v->get();
  throw wrong_type(data_->origin, key, *node.node(), "true or false");
}

std::vector<std::string> ExperimentConfig::strings(const std::string& key,
                                                   const std::vector<std::string>& fallback) const {
  const toml::node_view<const toml::node> node = data_->table.at_path(key);
  if (!node) return fallback;
  const auto* array = node.node()->as_array();
  if (!array) throw wrong_type(data_->origin, key, *node.node(), "an array of strings");
  std::vector<std::string> out;
  for (const toml::node& element : *array) {
    const auto* v = element.as_string();
    if (!v) throw wrong_type(data_->origin, key, element, "an array of strings; an element");
    out.push_back(v->get());
  }
  return out;
}

std::vector<double> ExperimentConfig::numbers(const std::string& key,
                                              const std::vector<double>& fallback) const {
  const toml::node_view<const toml::node> node = data_->table.at_path(key);
  if (!node) return fallback;
  const auto* array = node.node()->as_array();
  if (!array) throw wrong_type(data_->origin, key, *node.node(), "an array of numbers");
  std::vector<double> out;
  for (const toml::node& element : *array) {
    const std::optional<double> v = toml_number(element);
    if (!v || !std::isfinite(*v)) {
      throw wrong_type(data_->origin, key, element, "an array of finite numbers; an element");
    }
    out.push_back(*v);
  }
  return out;
}

void ExperimentConfig::require_known_keys(const std::vector<std::string>& given_known) const {
  std::vector<std::string> known = given_known;
  for (const char* key : {"experiment", "description"}) {
    if (std::find(known.begin(), known.end(), key) == known.end()) known.push_back(key);
  }
  for (const std::string& key : config_keys(run_settings_description())) known.push_back(key);
  std::vector<std::string> keys;
  collect_keys(data_->table, "", keys);
  std::vector<std::string> unknown;
  for (const std::string& key : keys) {
    const bool ok = std::any_of(known.begin(), known.end(), [&](const std::string& k) {
      return key == k || key.rfind(k + ".", 0) == 0 || k.rfind(key + ".", 0) == 0;
    });
    if (!ok) unknown.push_back(key);
  }
  if (!unknown.empty()) {
    std::string list;
    for (const std::string& k : known) list += fmt::format("{}{}", list.empty() ? "" : ", ", k);
    std::string bad;
    for (const std::string& k : unknown) bad += fmt::format("{}'{}'", bad.empty() ? "" : ", ", k);
    throw Error(
        fmt::format("{}: unknown key {} (this experiment knows: {})", data_->origin, bad, list));
  }
}

void Experiment::check(const ExperimentConfig&, const ExperimentContext&) const {}

void ExperimentRegistry::set_settings(const std::string& kind,
                                      std::function<KindSettings()> settings) {
  require(contains(kind), fmt::format("unknown experiment kind '{}'", kind));
  settings_[kind] = std::move(settings);
}

std::optional<KindSettings> ExperimentRegistry::settings(const std::string& kind) const {
  const auto it = settings_.find(kind);
  if (it == settings_.end()) return std::nullopt;
  return it->second();
}

ExperimentRegistry::ExperimentRegistry()
    : FactoryRegistry<Experiment>({"experiment kind", "an experiment kind needs a name",
                                   "experiment kind '{}' is already registered",
                                   "unknown experiment kind '{}' (registered: {})"}) {}

ExperimentRegistry& default_experiment_registry() {
  static ExperimentRegistry registry = [] {
    ExperimentRegistry r;
    register_builtin_experiments(r);
    return r;
  }();
  return registry;
}

}  // namespace plydem
