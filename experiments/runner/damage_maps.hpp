#pragma once
/// \file
/// Damage maps per ply of a strength test's run: the bonds in plan view by state at chosen
/// fractions of the peak load (the first critical state on the way up that reaches each) and
/// after the last event, with their broken bonds and cracks per ply (solvers/cracks.hpp), as
/// figures, a markdown table, a VTU series and results.csv rows. Shared by the notched plate
/// (hole_failure) and the cross-plies (crossply).

#include <filesystem>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/runner/experiment.hpp"

namespace plydem {

/// The grip force [N] at curve point k of a strength result (its stress is the reaction over the
/// gauge cross-section).
double grip_force(const StrengthResult& result, std::size_t k);

/// A copy of the run's final model with the bonds that broke at or after critical state `event`
/// intact again: the damage present at that state (the path is linear between events, so the
/// broken set is all that differs).
Model damage_at(const StrengthResult& result, long event);

/// What to draw and how to name it.
struct DamageMapsSpec {
  std::string name;         ///< the config's: results.csv rows
  std::string case_name;    ///< the rows' case
  std::string source;       ///< the rows' source
  std::string file_prefix;  ///< files: <prefix>_damage_<map>.png, vtu/<prefix>_damage_maps.pvd
  std::string title;        ///< what the figures' titles name (the layup)
  std::vector<double> fractions;        ///< of the peak load, each in (0, 1], sorted
  std::vector<std::string> ply_labels;  ///< one per ply, bottom first
  double area = 0;  ///< the cross-section the table's stress divides the grip force by [m^2]
  std::string stress_name = "stress";  ///< the table's name for that stress
};

/// maps.load_fractions of `config` (`defaults` when not given), sorted. Throws plydem::Error
/// naming the file for a fraction outside (0, 1].
std::vector<double> load_fractions_from_config(const ExperimentConfig& config,
                                               const std::vector<double>& defaults);

/// The maps' report text: the table of states and the figures' markdown.
struct DamageMaps {
  std::string table, figures;
};

/// The maps of `result` (a strength test's, with its breaks) as `spec` asks: figures and the VTU
/// series into `out_dir`, their files and the rows `broken bonds at <map>` into `out`.
DamageMaps draw_damage_maps(const StrengthResult& result, const DamageMapsSpec& spec,
                            const std::filesystem::path& out_dir, ExperimentOutput& out);

}  // namespace plydem
