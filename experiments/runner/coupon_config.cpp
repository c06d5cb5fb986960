#include "experiments/runner/coupon_config.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "core/material.hpp"

namespace plydem {

CouponSpec coupon_from_config(const ExperimentConfig& c, bool quick) {
  constexpr double mm = 1e-3;
  CouponSpec spec;
  spec.material = load_material(c.string("material", "eglass-my750"));
  auto size = [&](const std::string& key, double fallback_mm) {
    const double full = c.number(fmt::format("coupon.{}", key), fallback_mm);
    return (quick ? c.number(fmt::format("quick.{}", key), full) : full) * mm;
  };
  spec.length = size("length_mm", 10);
  spec.width = size("width_mm", 0.83);
  spec.thickness = size("thickness_mm", 0.2);
  spec.particle_diameter = size("diameter_mm", 0.05);
  spec.validate();
  return spec;
}

GripCondition grips_from_config(const ExperimentConfig& c) {
  const std::string grips = c.string("coupon.grips", "free");
  if (grips == "free") return GripCondition::kFree;
  if (grips == "clamped") return GripCondition::kClamped;
  throw Error(fmt::format("{}: coupon.grips must be \"free\" or \"clamped\", got \"{}\"",
                          c.path().string(), grips));
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
