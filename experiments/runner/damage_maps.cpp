#include "experiments/runner/damage_maps.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/units.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/runner/report_text.hpp"
#include "solvers/cracks.hpp"

namespace plydem {
namespace fs = std::filesystem;

double grip_force(const StrengthResult& r, std::size_t k) {
  return r.stress[k] * r.cross_section;
}

Model damage_at(const StrengthResult& r, long event) {
  Model m = *r.model;
  for (const BondBreak& b : r.breaks) {
    if (b.at >= static_cast<double>(event)) {
      m.bonds.state(b.bond) = static_cast<int>(BondState::kIntact);
      m.bonds.damage(b.bond) = 0;
    }
  }
  return m;
}

std::vector<double> load_fractions_from_config(const ExperimentConfig& c,
                                               const std::vector<double>& defaults) {
  std::vector<double> fractions = c.numbers("maps.load_fractions", defaults);
  for (double f : fractions) {
    require(std::isfinite(f) && f > 0 && f <= 1,
            fmt::format("{}: maps.load_fractions must lie in (0, 1] (fractions of the peak "
                        "grip force), got {}",
                        c.path().string(), f));
  }
  std::sort(fractions.begin(), fractions.end());
  return fractions;
}

DamageMaps draw_damage_maps(const StrengthResult& r, const DamageMapsSpec& spec,
                            const fs::path& out_dir, ExperimentOutput& out) {
  std::string maps;
  std::string map_table =
      markdown_row({"map", "event", "grip force (N)", fmt::format("{} (MPa)", spec.stress_name),
                    "broken bonds", "cracks per ply"}) +
      "|---|--:|--:|--:|--:|---|\n";
  // The maps' states as a VTU series too (time = event), drawn on the undeformed specimen: the
  // displacements at an earlier critical state are not kept (only the bonds' states are).
  fs::create_directories(out_dir / "vtu");
  const std::string maps_stem = file_stem(fmt::format("{}_damage_maps", spec.file_prefix));
  VtkSeries maps_series((out_dir / "vtu" / fmt::format("{}.pvd", maps_stem)).string());
  auto add_map = [&](const std::string& label, long event, const Model& state, double force) {
    Model undeformed = state;
    undeformed.particles.displacement.setZero();
    undeformed.particles.rotation.setZero();
    maps_series.add_model(static_cast<double>(event), undeformed);
    std::vector<BondBreak> so_far;
    for (const BondBreak& b : r.breaks)
      if (b.at < static_cast<double>(event)) so_far.push_back(b);
    const std::vector<Crack> cracks = find_cracks(state, so_far);
    std::string per_ply;
    for (std::size_t k = 0; k < spec.ply_labels.size(); ++k) {
      const auto count = std::count_if(cracks.begin(), cracks.end(), [&](const Crack& cr) {
        return !cr.interface && cr.ply == static_cast<int>(k);
      });
      per_ply += fmt::format("{}{}: {}", k == 0 ? "" : ", ", k, count);
    }
    map_table += markdown_row({label, fmt::format("{}", event), fmt::format("{:.1f}", force),
                               fmt::format("{:.2f}", force / spec.area * kMPaPerPa),
                               fmt::format("{}", so_far.size()), per_ply});
    const std::string stem = file_stem(fmt::format("{}_damage_{}", spec.file_prefix, label));
    const Figure f = plot_bond_states(
        state, out_dir, stem,
        fmt::format("{}: damage at {} (grip force {:.0f} N)", spec.title, label, force), 0, 0,
        spec.ply_labels);
    out.files.insert(out.files.end(), f.files.begin(), f.files.end());
    maps += figure_markdown(f, fmt::format("damage per ply at {}: broken bonds in tension red, "
                                           "in shear blue",
                                           label)) +
            "\n";
    out.rows.push_back({spec.name, spec.case_name, fmt::format("broken bonds at {}", label),
                        spec.source, static_cast<double>(so_far.size()), "1"});
  };
  const std::size_t peak = static_cast<std::size_t>(r.peak) + 1;
  const double peak_force = grip_force(r, peak);
  for (double f : spec.fractions) {
    std::size_t k = 1;
    while (k < peak && grip_force(r, k) < f * peak_force) ++k;
    add_map(fmt::format("{:g} of peak", f), static_cast<long>(k),
            damage_at(r, static_cast<long>(k)), grip_force(r, k));
  }
  add_map("final", r.events + 1, *r.model, grip_force(r, r.stress.size() - 1));
  out.files.push_back(fs::path("vtu") / fmt::format("{}.pvd", maps_stem));
  for (const std::string& file : maps_series.files()) out.files.push_back(fs::path("vtu") / file);
  maps += fmt::format(
      "ParaView: `vtu/{}.pvd` (these states on the undeformed specimen; bond cell data "
      "`state`, `damage`).\n",
      maps_stem);
  return {map_table, maps};
}

}  // namespace plydem
