#include "experiments/runner/coupon_config.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"

namespace plydem {

SettingsSelection coupon_config_selection() {
  return {{"material", "length", "width", "thickness", "diameter", "grips"}, {}};
}

CouponSpec coupon_from_config(const ExperimentConfig& c, bool quick) {
  const SettingsDescription<CouponSpec>& d = coupon_settings_description();
  CouponSpec spec = d.defaults();
  read_config_settings(c, d, {{"material", "length", "width", "thickness", "diameter"}, {}}, quick,
                       spec);
  spec.validate();
  return spec;
}

GripCondition grips_from_config(const ExperimentConfig& c) {
  const SettingsDescription<TensionSettings>& d = tension_settings_description();
  TensionSettings s = d.defaults();
  read_config_settings(c, d, {{"grips"}, {}}, false, s);
  return s.grips;
}

std::vector<std::string> coupon_config_keys() {
  return config_keys(tension_settings_description(), coupon_config_selection());
}

std::vector<std::pair<std::string, double>> parse_strategy_options(
    const std::vector<std::string>& entries, const std::string& what) {
  std::vector<std::pair<std::string, double>> result;
  for (const std::string& entry : entries) {
    const auto eq = entry.find('=');
    require(eq != std::string::npos && eq > 0 && eq + 1 < entry.size(),
            fmt::format("{} '{}' is not NAME=VALUE", what, entry));
    const std::string value = entry.substr(eq + 1);
    std::size_t used = 0;
    double number = 0;
    try {
      number = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used == value.size() && std::isfinite(number),
            fmt::format("{} '{}': '{}' is not a finite number", what, entry, value));
    result.emplace_back(entry.substr(0, eq), number);
  }
  return result;
}

}  // namespace plydem
