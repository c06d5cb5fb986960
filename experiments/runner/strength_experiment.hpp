#pragma once
/// \file
/// The strength experiment kind (`plydem run experiments/strength_angles.toml`, kind `strength`):
/// the tension test to failure (experiments/protocols/strength.hpp) of one ply or laminate at
/// each angle of the config, each strength beside the four classical criteria
/// (core/failure_criteria.hpp), and the sections and files `plydem strength --out` writes for one
/// test. Config keys (docs/strength.md, "Strength"; docs/settings.md): the settings of
/// `plydem strength` (strength_settings_description(), the same defaults) but the ply angle, and
/// the cases' angles:
///
///   experiment = "strength"
///   material = "eglass-my750"        strategy = "square"     strategy_options = ["c=1.8"]
///   angles_deg = [0, 15, 30]         (or angle_deg = 30; default 0)
///   layup = "[0/90]s"                (optional: a laminate, turned by each angle)
///   method = "events"                weibull_modulus = 0     seed = 1
///   friction = 0                     softening = false      edge_strengths = "bulk"
///   [coupon] length_mm, width_mm, thickness_mm, diameter_mm, grips, grip_mm, gauge_fraction, ...
///   [quick]  length_mm, width_mm, thickness_mm, diameter_mm, ...
///   [interface] normal, shear (N/m^3), strength_normal, strength_shear (Pa), GIc, GIIc (J/m^2)
///   [events] max_events, stop_fraction, tooth_stiffness_ratio, max_update_rank
///   [output] vtu_series (false: the final state of each angle; true: selected events)
///
/// A case whose strengths cannot be calibrated (a target the strategy cannot reach) is a row that
/// says why, not a failed run.

#include <filesystem>
#include <string>

#include "experiments/protocols/strength.hpp"
#include "experiments/runner/experiment.hpp"

namespace plydem {

/// Registers `strength` (CMake list PLYDEM_EXPERIMENTS entry `strength`).
void register_strength_experiment(ExperimentRegistry& registry);

/// One strength test's report section (the results, the strength calibration, the figures),
/// results.csv rows (experiment `experiment`, case `case_name`), and files in `out_dir`: the
/// stress-strain PNG with the criteria, the crack-pattern PNG and the VTU series
/// (write_strength_vtu), all named from `stem`.
ExperimentOutput strength_output(const StrengthResult& result, const std::filesystem::path& out_dir,
                                 const std::string& experiment, const std::string& case_name,
                                 const std::string& stem);

/// What the strength model represents and how it is loaded, a paragraph for report.md.
std::string strength_model_note(const StrengthSettings& settings);

}  // namespace plydem
