#pragma once
/// \file
/// How a strength test (experiments/protocols/strength.hpp) is shown: a table for people
/// (MPa, %), a JSON object for scripts (SI units, Pa), and its figures and ParaView files.
///
/// The JSON keys strength, strain_at_peak, first_failure_stress [Pa], curve (list of [strain,
/// stress]), broken_bonds (counts by family and mode), theory (max_stress, tsai_hill, tsai_wu,
/// hashin [Pa]; null where the material lacks a strength the criterion needs), events and
/// wall_seconds are a contract: keys may be added, never renamed. `curve` holds the fitted gauge
/// strain, `curve_nominal` the same points against the grips' nominal strain (separation over
/// initial distance), where a snap-back shows.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/output/figures.hpp"
#include "experiments/protocols/strength.hpp"

namespace plydem {

/// "max-stress", "Tsai-Hill", "Tsai-Wu", "Hashin".
const char* criterion_label(FailureCriterion criterion);

/// The DEM stress the classical criteria are set beside: the strength (peak) of one ply, whose
/// criteria predict its failure; the first failure of a laminate, whose criteria are first-ply
/// failure.
double criteria_compared_stress(const StrengthResult& result);
/// What that is: "strength" or "first failure".
const char* criteria_compared_name(const StrengthResult& result);

std::string format_strength_table(const StrengthResult& result, const StrengthSettings& settings);
nlohmann::json strength_json(const StrengthResult& result, const StrengthSettings& settings);

/// The stress-strain curve [%, MPa] with each classical criterion's strength drawn in as a
/// horizontal line, and the peak marked.
Figure plot_strength_curve(const StrengthResult& result, const std::filesystem::path& out_dir,
                           const std::string& stem, const std::string& title);

/// The crack pattern: the coupon's bonds after the run by state (plot_bond_states), over the part
/// of the coupon that holds the broken bonds (with a margin of one coupon width each side), or
/// all of it when none broke.
Figure plot_crack_pattern(const StrengthResult& result, const std::filesystem::path& out_dir,
                          const std::string& stem, const std::string& title);

/// Writes DIR/vtu/STEM.pvd with the particles and bonds .vtu files of every snapshot of `result`
/// (time = event number; bond state and damage as cell data) or, without snapshots, of its final
/// state. Returns the files written, relative to `out_dir`.
std::vector<std::filesystem::path> write_strength_vtu(const StrengthResult& result,
                                                      const std::filesystem::path& out_dir,
                                                      const std::string& stem);

}  // namespace plydem
