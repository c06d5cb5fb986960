#include "experiments/runner/coupon_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/units.hpp"
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

std::vector<double> particle_diameters_from_config(const ExperimentConfig& c, bool quick,
                                                   double diameter) {
  const std::string origin = c.path().string();
  // A quick run reads [quick]'s diameters where it gives either key, [coupon]'s otherwise.
  const bool own = quick && (c.contains("quick.diameters_mm") || c.contains("quick.diameter_mm"));
  const std::string table = own ? "quick" : "coupon";
  const std::vector<double> mm = c.numbers(table + ".diameters_mm", {});
  if (mm.empty()) return {diameter};
  require(!c.contains(table + ".diameter_mm"),
          fmt::format("{0}: give {1}.diameters_mm or {1}.diameter_mm, not both", origin, table));
  std::vector<double> diameters;
  for (double d : mm) {
    require(
        std::isfinite(d) && d > 0,
        fmt::format("{}: coupon.diameters_mm must be positive diameters in mm, got {}", origin, d));
    diameters.push_back(d * kMetresPerMm);
  }
  std::sort(diameters.begin(), diameters.end(), std::greater<>());
  require(std::adjacent_find(diameters.begin(), diameters.end()) == diameters.end(),
          fmt::format("{}: coupon.diameters_mm names a diameter twice", origin));
  return diameters;
}

std::vector<std::pair<std::string, std::string>> with_particle_diameters_keys(
    const std::string& what, std::vector<std::pair<std::string, std::string>> keys) {
  keys.emplace_back("coupon.diameters_mm",
                    fmt::format("particle diameters [mm] to run {} at (replaces "
                                "coupon.diameter_mm): the finest gives the report, the others rows "
                                "of source \"dem d=<mm>\" and the particle-size table; default: "
                                "coupon.diameter_mm alone",
                                what));
  keys.emplace_back("quick.diameters_mm", "the particle diameters of a quick run");
  return keys;
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
