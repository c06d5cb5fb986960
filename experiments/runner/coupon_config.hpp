#pragma once
/// \file
/// The coupon keys every tension-type experiment config shares:
///   material = "eglass-my750"                 (built-in name or a material TOML file)
///   [coupon] length_mm, width_mm, thickness_mm, diameter_mm, grips ("free" or "clamped")
///   [quick]  the same sizes, replacing those of [coupon] in a quick run (`plydem run --quick`)
/// Defaults: the paper's coupon (10 x 0.83 x 0.2 mm, 0.05 mm particles), free grips. The keys are
/// the settings descriptions' (coupon_settings_description(), tension_settings_description()):
/// the command line's --material, --length-mm, ..., --grips.

#include <string>
#include <utility>
#include <vector>

#include "experiments/protocols/coupon.hpp"
#include "experiments/runner/experiment.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// The material and coupon.* sizes [mm] (quick.* in a quick run). Throws plydem::Error for a bad
/// material or size.
CouponSpec coupon_from_config(const ExperimentConfig& config, bool quick);

/// coupon.grips. Throws plydem::Error naming the file for anything but "free" or "clamped".
GripCondition grips_from_config(const ExperimentConfig& config);

/// The keys coupon_from_config and grips_from_config read (quick keys included).
std::vector<std::string> coupon_config_keys();

/// The settings (of tension_settings_description()) coupon_from_config and grips_from_config read.
SettingsSelection coupon_config_selection();

/// coupon.diameters_mm (in a quick run quick.diameters_mm, where [quick] gives it or
/// quick.diameter_mm): the particle diameters a kind runs its specimens at, coarsest first [m];
/// {`diameter`} (the coupon's) when not given. Throws plydem::Error naming the file for a
/// non-positive or repeated diameter, or for diameters_mm beside diameter_mm in the same table.
std::vector<double> particle_diameters_from_config(const ExperimentConfig& config, bool quick,
                                                   double diameter);

/// `keys` (a kind's own config keys with their descriptions) and coupon.diameters_mm,
/// quick.diameters_mm, described as running `what` at each size.
std::vector<std::pair<std::string, std::string>> with_particle_diameters_keys(
    const std::string& what, std::vector<std::pair<std::string, std::string>> keys);

/// Strategy options written "NAME=VALUE" -> (NAME, VALUE). Throws plydem::Error naming the entry,
/// prefixed by `what` ("--strategy-option", or the config and key), when it is not NAME=VALUE or
/// VALUE is not a finite number.
std::vector<std::pair<std::string, double>> parse_strategy_options(
    const std::vector<std::string>& entries, const std::string& what);

}  // namespace plydem
