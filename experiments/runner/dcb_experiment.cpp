// The DCB experiment kind (`plydem run experiments/dcb.toml`, kind `dcb`): the double cantilever
// beam of experiments/protocols/dcb.hpp opened to propagation, beside simple and corrected
// beam theory. Config keys (docs/experiments.md, "Delamination: the DCB"):
//
//   experiment = "dcb"
//   material = "eglass-my750"     strategy = "square"      strategy_options = []
//   [laminate]  layup = "[0_16]", ply_thickness_mm
//   [coupon]    length_mm, width_mm, crack_mm, diameter_mm, max_crack_mm
//   [quick]     layup, ply_thickness_mm, length_mm, crack_mm, diameter_mm, max_crack_mm
//   [interface] strength_normal, strength_shear (Pa), GIc, GIIc (J/m^2), bk_exponent, normal,
//   shear (N/m^3)
//   [events]    max_events, tooth_stiffness_ratio, max_update_rank
//   [output]    vtu_series
//
// results.csv rows (a contract): dcb,<case>,propagation_load,<source>,<value>,N and
// dcb,<case>,initial_compliance,<source>,<value>,m/N, sources `dem`, `beam theory` and
// `corrected beam theory`; also the DEM curve reduced as ASTM D5528's modified beam theory does.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>

#include "core/error.hpp"
#include "core/units.hpp"
#include "experiments/output/crack_report.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/dcb.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/report_text.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "strategies/laminate.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

// A `dcb` config's settings: the test's, and the case's name (the layup as written).
struct DcbExperimentSettings {
  DcbSettings test;
  std::string case_name;
};

DcbExperimentSettings parse_dcb(const ExperimentConfig& c, const ExperimentContext& context) {
  const SettingsDescription<DcbSettings>& d = dcb_settings_description();
  c.require_known_keys(config_keys(d));
  const std::string origin = c.path().string();
  DcbSettings s = d.defaults();
  // The layup as written names the case ([quick] layup in a quick run).
  std::string layup = c.string("laminate.layup", format_layup(s.layup));
  if (context.quick) layup = c.string("quick.layup", layup);
  read_config_settings(c, d, {}, context.quick, s);
  try {
    s.validate();
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", origin, e.what()));
  }
  return {s, layup};
}

KindSettings dcb_kind_settings() {
  const SettingsDescription<DcbSettings>& d = dcb_settings_description();
  return {d.rows(d.defaults()), {}};
}

DcbResult run_dcb_experiment(const DcbExperimentSettings& settings, const ExperimentContext&) {
  const DcbSettings& s = settings.test;
  const std::string& case_name = settings.case_name;
  spdlog::info("dcb {}: {} x {} mm, arms {:g} mm, a0 {:g} mm, particles of {:g} mm", case_name,
               s.length / kMetresPerMm, s.width / kMetresPerMm, s.arm_thickness() / kMetresPerMm,
               s.crack / kMetresPerMm, s.particle_diameter / kMetresPerMm);
  return run_dcb(s, [&](const EventProgress& p) {
    spdlog::info("dcb {}: {} events, {} bonds broken, peak load {:.4g} N, {:.0f} s", case_name,
                 p.events, p.broken, p.peak_reaction, p.elapsed_seconds);
  });
}

// results.csv: the contract rows (file comment), then the DEM's measurements.
void add_dcb_rows(const DcbResult& r, const DcbReduction& mbt, const std::string& case_name,
                  ExperimentOutput& out) {
  const DcbBeamTheory& t = r.theory;
  auto row = [&](const std::string& quantity, const std::string& source, double value,
                 const std::string& unit) {
    if (std::isfinite(value)) out.rows.push_back({"dcb", case_name, quantity, source, value, unit});
  };
  row("propagation_load", "dem", r.propagation_load, "N");
  row("propagation_load", "beam theory", t.propagation_load, "N");
  row("propagation_load", "corrected beam theory", t.corrected_propagation_load, "N");
  row("initial_compliance", "dem", r.initial_compliance, "m/N");
  row("initial_compliance", "beam theory", t.compliance, "m/N");
  row("initial_compliance", "corrected beam theory", t.corrected_compliance, "m/N");
  row("GIc", "interface (input)", r.interface_strength.GIc, "J/m^2");
  if (mbt.points >= 3) {
    row("GIc", "dem, modified beam theory reduction", mbt.GIc, "J/m^2");
    row("crack_length_correction", "dem, modified beam theory reduction", mbt.delta, "m");
    row("flexural_modulus", "dem, modified beam theory reduction", mbt.flexural_modulus, "Pa");
  }
  row("crack_length_correction", "corrected beam theory", t.chi * r.arm_thickness, "m");
  row("energy_released_per_crack_area", "dem", r.released_per_area, "J/m^2");
  row("initial_crack", "dem", r.initial_crack, "m");
  row("crack_at_peak", "dem", r.crack_at_peak, "m");
  row("cohesive_zone_at_peak", "dem", r.cohesive_zone_at_peak, "m");
  row("final_crack", "dem", r.final_crack, "m");
  row("opening_at_peak", "dem", r.opening_at_peak, "m");
  row("events", "dem", static_cast<double>(r.events), "1");
  row("particles", "dem", r.particles, "1");
  row("wall time", "dem", r.wall_seconds, "s");
}

// The figures, the VTU series and the crack report, written into `dir`.
struct DcbFigures {
  Figure load, crack, crack_map;
  CrackReport cracks;
};

DcbFigures dcb_figures(const DcbResult& r, const DcbSettings& s, const fs::path& dir,
                       const std::string& case_name, ExperimentOutput& out) {
  // The theory curves: linear up to propagation at a0, then P(a), delta(a) for a0 <= a <= max.
  Curve dem{fmt::format("DEM {}", r.strategy), {}, {}, true};
  Curve crack{fmt::format("DEM {}", r.strategy), {}, {}, true};
  for (std::size_t i = 0; i < r.load.size(); ++i) {
    dem.x.push_back(r.opening[i] / kMetresPerMm);
    dem.y.push_back(r.load[i]);
    crack.x.push_back(r.opening[i] / kMetresPerMm);
    crack.y.push_back(r.crack[i] / kMetresPerMm);
  }
  std::vector<Curve> load_curves{dem};
  std::vector<Curve> crack_curves{crack};
  for (const bool corrected : {false, true}) {
    const char* label = corrected ? "corrected beam theory" : "beam theory";
    Curve p{label, {0.0}, {0.0}, false};
    Curve a{label, {}, {}, false};
    const int steps = 60;
    for (int k = 0; k <= steps; ++k) {
      const double length = r.initial_crack + (s.max_crack - r.initial_crack) * k / steps;
      const DcbBeamTheory at =
          dcb_beam_theory(r.material, r.width, r.arm_thickness, length, r.interface_strength.GIc);
      const double load = corrected ? at.corrected_propagation_load : at.propagation_load;
      const double compliance = corrected ? at.corrected_compliance : at.compliance;
      p.x.push_back(load * compliance / kMetresPerMm);
      p.y.push_back(load);
      a.x.push_back(load * compliance / kMetresPerMm);
      a.y.push_back(length / kMetresPerMm);
    }
    load_curves.push_back(p);
    crack_curves.push_back(a);
  }
  const std::string stem = "dcb";
  PlotAxes axes;
  axes.key = "right top";
  const Figure load_figure =
      plot_curves(load_curves, dir, stem + "_load_opening",
                  fmt::format("DCB {}: load against opening (GIc {:g} J/m^2)", case_name,
                              r.interface_strength.GIc),
                  "opening delta [mm]", "load P [N]", axes);
  PlotAxes left;
  const Figure crack_figure =
      plot_curves(crack_curves, dir, stem + "_crack_length",
                  fmt::format("DCB {}: crack length against opening", case_name),
                  "opening delta [mm]", "crack length a [mm]", left);
  const double window = 4.0 * r.arm_thickness;
  const double x0 = r.model->particles.reference_position.col(0).minCoeff();
  const Figure crack_map = plot_bond_states(
      *r.model, dir, stem + "_delamination",
      fmt::format("DCB {}: bonds around the crack tip at the end (side view)", case_name),
      x0 + r.initial_crack - window, x0 + r.final_crack + window);
  for (const Figure* f : {&load_figure, &crack_figure, &crack_map})
    out.files.insert(out.files.end(), f->files.begin(), f->files.end());

  // VTU series of the selected critical states (or the final state).
  fs::create_directories(dir / "vtu");
  VtkSeries series((dir / "vtu" / "dcb.pvd").string());
  if (r.snapshots.empty()) {
    series.add_model(static_cast<double>(r.events), *r.model);
  } else {
    for (const DcbSnapshot& snapshot : r.snapshots)
      series.add_model(static_cast<double>(snapshot.event), *snapshot.model);
  }
  out.files.push_back(fs::path("vtu") / "dcb.pvd");
  for (const std::string& file : series.files()) out.files.push_back(fs::path("vtu") / file);

  const CrackReport cracks =
      crack_report(*r.model, r.breaks, {}, dir, stem, fmt::format("DCB {}: cracks", case_name));
  out.files.insert(out.files.end(), cracks.files.begin(), cracks.files.end());
  return {load_figure, crack_figure, crack_map, cracks};
}

// The report section: the model, DEM beside beam theory, the ASTM reduction, the figures.
std::string dcb_markdown(const DcbResult& r, const DcbSettings& s, const DcbReduction& mbt,
                         const std::string& case_name, const DcbFigures& figures) {
  const DcbBeamTheory& t = r.theory;
  const Figure& load_figure = figures.load;
  const Figure& crack_figure = figures.crack;
  const Figure& crack_map = figures.crack_map;
  std::string md;
  md += fmt::format(
      "A side-view model of the DCB (experiments/protocols/dcb.hpp): the particle layer "
      "is the beam's length-thickness plane, the {:g} mm width its out-of-plane thickness "
      "(plane stress, E1 = {:g} GPa along the beam). Laminate {} of {:g} mm plies: two arms of "
      "h = {:g} mm ({} strategy, {} rows of {:g} mm particles), {:g} mm long, joined on the "
      "mid-plane by {} interface bonds (strength {:g} MPa normal, {:g} MPa shear; K_n {:.3g}, "
      "K_s {:.3g} N/m^3; GIc {:g} J/m^2, each bond softening linearly to kappa_u = {:.3g}). "
      "Starter delamination a0 = {:g} mm from the load line (as built). The end columns are "
      "pulled apart (sequentially linear analysis: each point a critical state); the run "
      "stopped: {} after {} events ({} factorizations, {:.1f} s).\n\n",
      r.width / kMetresPerMm, r.material.E1 * 1e-9, case_name, s.ply_thickness / kMetresPerMm,
      r.arm_thickness / kMetresPerMm, r.strategy,
      static_cast<int>(std::round(r.arm_thickness / r.particle_diameter)),
      r.particle_diameter / kMetresPerMm, r.length / kMetresPerMm, r.interface_bonds,
      r.interface_strength.normal * 1e-6, r.interface_strength.shear * 1e-6, r.interface.normal,
      r.interface.shear, r.interface_strength.GIc, r.interface_ductility,
      r.initial_crack / kMetresPerMm, r.stop, r.events, r.factorizations, r.wall_seconds);
  md += markdown_row(
            {"quantity", "DEM", "beam theory", "DEM vs it", "corrected beam theory", "DEM vs it"}) +
        "|---|--:|--:|--:|--:|--:|\n";
  md += markdown_row({"propagation load P (N)", fmt::format("{:.4g}", r.propagation_load),
                      fmt::format("{:.4g}", t.propagation_load),
                      percent_change(r.propagation_load, t.propagation_load),
                      fmt::format("{:.4g}", t.corrected_propagation_load),
                      percent_change(r.propagation_load, t.corrected_propagation_load)});
  md += markdown_row({"initial compliance C (mm/N)",
                      fmt::format("{:.5g}", r.initial_compliance / kMetresPerMm),
                      fmt::format("{:.5g}", t.compliance / kMetresPerMm),
                      percent_change(r.initial_compliance, t.compliance),
                      fmt::format("{:.5g}", t.corrected_compliance / kMetresPerMm),
                      percent_change(r.initial_compliance, t.corrected_compliance)});
  md += fmt::format(
      "\nThe DEM's propagation load is its peak load (at crack length {:.4g} mm, opening "
      "{:.4g} mm; {:.3g} mm of softened interface bonds ahead of the tip, the cohesive zone "
      "that shields it). Beam theory: C = 8 a^3 / (E1 b h^3), P = (b h / a) sqrt(GIc E1 h / 12); "
      "the "
      "corrected theory uses a + chi h with chi = {:.4g} (Hashemi, Kinloch & Williams 1990), "
      "for the root rotation and the uncracked part's elastic foundation. Both are linear, as "
      "the model is.\n\n",
      r.crack_at_peak / kMetresPerMm, r.opening_at_peak / kMetresPerMm,
      r.cohesive_zone_at_peak / kMetresPerMm, t.chi);
  if (mbt.points >= 3) {
    md += fmt::format(
        "The DEM curve reduced as an experiment is (ASTM D5528, modified beam theory, {} "
        "propagation points): C^(1/3) against a gives Delta = {:.4g} mm (corrected beam theory: "
        "chi h = {:.4g} mm) and a flexural modulus of {:.4g} GPa (E1 {:.4g}); G_I = 3 P delta / "
        "(2 b (a + |Delta|)) averages {:.4g} J/m^2 against the interface's GIc {:g} ({}). The "
        "energy released per crack area grown is {:.4g} J/m^2.\n\n",
        mbt.points, mbt.delta / kMetresPerMm, t.chi * r.arm_thickness / kMetresPerMm,
        mbt.flexural_modulus * 1e-9, r.material.E1 * 1e-9, mbt.GIc, r.interface_strength.GIc,
        percent_change(mbt.GIc, r.interface_strength.GIc), r.released_per_area);
  }
  md += figure_markdown(load_figure, "Load against opening: DEM beside beam theory") + "\n";
  md += figure_markdown(crack_figure, "Crack length against opening") + "\n";
  md += figure_markdown(crack_map, "The delamination at the end of the run") + "\n";
  md += figures.cracks.markdown;
  return md;
}

ExperimentOutput report_dcb(const DcbExperimentSettings& settings, const DcbResult& r,
                            const ExperimentContext& context) {
  const std::string& case_name = settings.case_name;
  ExperimentOutput out;
  out.title =
      fmt::format("Double cantilever beam: {} {} ({})", r.material.name, case_name, r.strategy);
  const DcbReduction mbt = reduce_dcb_curve(r);
  add_dcb_rows(r, mbt, case_name, out);
  const DcbFigures figures = dcb_figures(r, settings.test, context.out_dir, case_name, out);
  out.report_markdown = dcb_markdown(r, settings.test, mbt, case_name, figures);
  return out;
}

}  // namespace

void register_dcb_experiment(ExperimentRegistry& registry) {
  registry.add("dcb",
               "double cantilever beam of a unidirectional laminate opened to delamination "
               "growth, beside simple and corrected beam theory",
               parse_dcb, run_dcb_experiment, report_dcb);
  registry.set_settings("dcb", dcb_kind_settings);
}

}  // namespace plydem
