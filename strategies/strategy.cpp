#include "strategies/strategy.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"

namespace plydem {

void CouponSpec::validate() const {
  const std::pair<const char*, double> sizes[] = {{"length", length},
                                                  {"width", width},
                                                  {"thickness", thickness},
                                                  {"particle diameter", particle_diameter}};
  for (const auto& [name, value] : sizes) {
    require(std::isfinite(value), fmt::format("coupon {} is not a finite number", name));
    require(value > 0, fmt::format("coupon {} must be positive, got {} mm", name, value * 1e3));
  }
  require(std::isfinite(ply_angle), "ply angle is not a finite number");
  require(length >= 4 * particle_diameter && width >= particle_diameter,
          fmt::format("a {} mm x {} mm coupon is too small for particles of diameter {} mm "
                      "(need length >= 4 and width >= 1 diameter)",
                      length * 1e3, width * 1e3, particle_diameter * 1e3));
}

void Strategy::set_option(const std::string& name, double value) {
  std::string known;
  for (const StrategyOption& option : options()) {
    known += known.empty() ? option.name : fmt::format(", {}", option.name);
  }
  throw Error(fmt::format(
      "this strategy has no option '{}' (value {}); {}", name, value,
      known.empty() ? std::string("it takes no options") : fmt::format("its options: {}", known)));
}

}  // namespace plydem
