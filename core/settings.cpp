#include "core/settings.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/units.hpp"

namespace plydem {

const char* setting_type_name(SettingType type) {
  switch (type) {
    case SettingType::kSwitch:
      return "switch";
    case SettingType::kInteger:
      return "integer";
    case SettingType::kNumber:
      return "number";
    case SettingType::kText:
      return "text";
    case SettingType::kTexts:
      return "list of texts";
  }
  return "?";
}

namespace setting_units {

namespace {
double mm_to_m(double x) {
  return x * kMetresPerMm;
}
double m_to_mm(double x) {
  return x / kMetresPerMm;
}
// The command line's conversion of --angle (and the paper tables' radians()): (x * pi) / 180.
double deg_to_rad(double x) {
  return x * std::numbers::pi / 180.0;
}
double rad_to_deg(double x) {
  return x * 180.0 / std::numbers::pi;
}
}  // namespace

SettingUnit same(const std::string& symbol) {
  return {symbol, symbol, nullptr, nullptr};
}
SettingUnit millimetres() {
  return {"mm", "m", &mm_to_m, &m_to_mm};
}
SettingUnit millimetres_per_second() {
  return {"mm/s", "m/s", &mm_to_m, &m_to_mm};
}
SettingUnit degrees() {
  return {"deg", "rad", &deg_to_rad, &rad_to_deg};
}

}  // namespace setting_units

bool SettingsSelection::contains(const std::string& name) const {
  if (!only.empty() && std::find(only.begin(), only.end(), name) == only.end()) return false;
  return std::find(exclude.begin(), exclude.end(), name) == exclude.end();
}

bool SettingsSelection::checks(const std::string& name) const {
  return std::find(unchecked.begin(), unchecked.end(), name) == unchecked.end();
}

std::string format_setting_value(const SettingValue& value) {
  struct Format {
    std::string operator()(std::monostate) const { return ""; }
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(long i) const { return fmt::format("{}", i); }
    std::string operator()(double x) const { return fmt::format("{:g}", x); }
    std::string operator()(const std::string& s) const { return s; }
    std::string operator()(const std::vector<std::string>& list) const {
      return fmt::format("{}", fmt::join(list, ", "));
    }
  };
  return std::visit(Format{}, value);
}

SettingValue setting_edge_value(const SettingInfo& info, const SettingValue& value) {
  if (const double* x = std::get_if<double>(&value)) return info.unit.si_to_edge(*x);
  if (const bool* b = std::get_if<bool>(&value)) return info.edge_inverts ? !*b : *b;
  return value;
}

std::string choice_error(const std::string& what, const std::vector<std::string>& choices,
                         const std::string& value) {
  std::string list;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    if (i > 0) list += i + 1 == choices.size() ? " or " : ", ";
    list += fmt::format("\"{}\"", choices[i]);
  }
  return fmt::format("{} must be {}, got \"{}\"", what, list, value);
}

namespace {

// "{what} must be at least 1, got 0", "... between 1 and 16 ...", "... at most 5 ...".
void check_range(const std::string& what, double value, std::optional<double> min,
                 std::optional<double> max, const std::string& shown) {
  const bool low = min && value < *min;
  const bool high = max && value > *max;
  if (!low && !high) return;
  if (min && max) {
    throw Error(fmt::format("{} must be between {:g} and {:g}, got {}", what, *min, *max, shown));
  }
  throw Error(min ? fmt::format("{} must be at least {:g}, got {}", what, *min, shown)
                  : fmt::format("{} must be at most {:g}, got {}", what, *max, shown));
}

}  // namespace

SettingValue setting_struct_value(const SettingInfo& info, const SettingValue& edge_value,
                                  const std::string& what) {
  if (const bool* b = std::get_if<bool>(&edge_value)) return info.edge_inverts ? !*b : *b;
  if (const long* i = std::get_if<long>(&edge_value)) {
    const std::string shown = fmt::format("{}", *i);
    check_range(what, static_cast<double>(*i), info.min, info.max, shown);
    if (*i < info.integer_min || *i > info.integer_max) {
      throw Error(fmt::format("{} must be between {} and {}, got {}", what, info.integer_min,
                              info.integer_max, shown));
    }
    return *i;
  }
  if (const double* x = std::get_if<double>(&edge_value)) {
    if (info.finite && !std::isfinite(*x)) throw Error(what + " is not a finite number");
    check_range(what, *x, info.min, info.max, fmt::format("{:g}", *x));
    return info.unit.edge_to_si(*x);
  }
  if (const std::string* s = std::get_if<std::string>(&edge_value)) {
    if (info.choices && !info.setter_checks_choices) {
      const std::vector<std::string> choices = info.choices();
      if (std::find(choices.begin(), choices.end(), *s) == choices.end())
        throw Error(choice_error(what, choices, *s));
    }
    return *s;
  }
  return edge_value;
}

std::string help_with_unit(const std::string& help, const std::string& unit) {
  const std::string placeholder = "{unit}";
  const std::size_t at = help.find(placeholder);
  if (at == std::string::npos) return unit.empty() ? help : help + " " + unit;
  if (!unit.empty()) return help.substr(0, at) + unit + help.substr(at + placeholder.size());
  const std::size_t from = at > 0 && help[at - 1] == ' ' ? at - 1 : at;
  return help.substr(0, from) + help.substr(at + placeholder.size());
}

std::string setting_edge_name(const SettingInfo& info, SettingEdge edge) {
  switch (edge) {
    case SettingEdge::kCommandLine:
      return info.flag.empty() ? info.name : info.flag;
    case SettingEdge::kConfig:
      return info.key.empty() ? info.name : info.key;
    case SettingEdge::kPython:
      return info.python.empty() ? info.name : info.python;
    case SettingEdge::kReference:
      return info.name;
  }
  return info.name;
}

namespace {

// One placeholder: {name} or {name=value}, as `edge` writes it.
std::string render_placeholder(const SettingInfo& info, const std::string& value, bool has_value,
                               SettingEdge edge) {
  const std::string name = setting_edge_name(info, edge);
  const bool text = info.type == SettingType::kText || info.type == SettingType::kTexts;
  switch (edge) {
    case SettingEdge::kCommandLine:
      return has_value ? name + " " + value : name;
    case SettingEdge::kConfig:
      if (!has_value) return info.type == SettingType::kSwitch ? name + " = true" : name;
      return text ? fmt::format("{} = \"{}\"", name, value) : name + " = " + value;
    case SettingEdge::kPython:
      if (!has_value) return info.type == SettingType::kSwitch ? name + "=True" : name;
      return text ? fmt::format("{}='{}'", name, value) : name + "=" + value;
    case SettingEdge::kReference:
      return has_value ? fmt::format("`{}` {}", name, value) : fmt::format("`{}`", name);
  }
  return name;
}

}  // namespace

std::string render_setting_reason(std::string_view reason, SettingEdge edge,
                                  const std::function<const SettingInfo*(std::string_view)>& find) {
  std::string out;
  std::size_t at = 0;
  while (at < reason.size()) {
    const std::size_t open = reason.find('{', at);
    const std::size_t close = open == std::string_view::npos ? open : reason.find('}', open);
    if (close == std::string_view::npos) {
      out += reason.substr(at);
      break;
    }
    out += reason.substr(at, open - at);
    const std::string_view inside = reason.substr(open + 1, close - open - 1);
    const std::size_t eq = inside.find('=');
    const std::string_view name = inside.substr(0, eq);
    const SettingInfo* info = find(name);
    if (info == nullptr) {
      out += reason.substr(open, close - open + 1);
    } else {
      const bool has_value = eq != std::string_view::npos;
      out += render_placeholder(*info, has_value ? std::string(inside.substr(eq + 1)) : "",
                                has_value, edge);
    }
    at = close + 1;
  }
  return out;
}

}  // namespace plydem
