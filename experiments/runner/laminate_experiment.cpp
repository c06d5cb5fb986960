// The kind `laminate` (the paper's Tables 4 and 5, `plydem run experiments/table4.toml`): a
// layup from the config beside CLT of its A matrix, CalculiX and the paper's rows
// (experiments/runner/paper_tables.hpp).
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/paper_tables.hpp"
#include "experiments/runner/report_text.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "strategies/laminate.hpp"

namespace plydem {
namespace {

using namespace paper_tables;

// A `laminate` config's settings.
struct LaminateExperimentSettings {
  std::string name;        ///< the config's, naming rows and files
  std::string layup_text;  ///< as written
  std::string table;       ///< "Table 4", ...
  std::string case_name;   ///< the layup as format_layup writes it
  TensionSettings s;
  std::vector<Ply> plies;
  Values clt;  ///< of the A matrix
  /// Why CalculiX does not run ("not run (fem.run = false)", "CalculiX not installed"), or "".
  std::string fem_skipped;
  std::optional<FemTwinSettings> same_coupon;  ///< CalculiX of the DEM's own coupons
  /// CalculiX of a wide coupon (fem.length_mm, fem.width_mm).
  std::optional<std::pair<FemSpecimen, FemSettings>> wide;
  std::optional<Values> paper_theory, paper_fem, paper_dem;
  double window = 0;  ///< of the bond figure [m]
};

// The tension command's settings this kind takes: the strategy, the coupon, the grips, the layup
// and its interfaces' stiffness.
const SettingsSelection kLaminateSettings{
    {"strategy", "material", "length", "width", "thickness", "diameter", "grips", "layup",
     "interface_normal", "interface_shear"},
    {}};

LaminateExperimentSettings parse_laminate(const ExperimentConfig& c,
                                          const ExperimentContext& context) {
  const SettingsDescription<TensionSettings>& d = tension_settings_description();
  std::vector<std::string> known = known_keys({"table"});
  for (const std::string& key : config_keys(d, kLaminateSettings)) known.push_back(key);
  c.require_known_keys(known);
  const std::string name = c.name();
  const std::string layup_text = c.string("layup", "");
  if (layup_text.empty())
    throw Error(fmt::format("{}: the key 'layup' is missing", c.path().string()));
  const std::string table = c.string("table", "Laminate");
  TensionSettings s = d.defaults();
  s.force = context.force;
  read_config_settings(c, d, kLaminateSettings, context.quick, s);
  const std::string case_name = format_layup(s.layup);
  const LaminateSpec spec{s.coupon, s.layup, s.interface};
  const std::vector<Ply> plies = laminate_plies(spec);
  const Values clt = values_of(laminate_constants(plies));
  LaminateExperimentSettings ls;
  ls.name = name;
  ls.layup_text = layup_text;
  ls.table = table;
  ls.case_name = case_name;
  ls.s = s;
  ls.plies = plies;
  ls.clt = clt;
  // The FEM keys are read where CalculiX runs.
  const double h = s.coupon.thickness * static_cast<double>(s.layup.size());
  if (!c.boolean("fem.run", true)) {
    ls.fem_skipped = "not run (fem.run = false)";
  } else if (!calculix_availability(context.calculix).available) {
    ls.fem_skipped = "CalculiX not installed";
  } else {
    if (c.boolean("fem.same_coupon", true)) {
      FemTwinSettings twin;
      twin.executable = context.calculix;
      twin.mesh.element = fem_settings_from(c, context, 0).mesh.element;
      ls.same_coupon = twin;
    }
    if (c.contains("fem.length_mm") || c.contains("fem.width_mm")) {
      // The free-edge zone of a laminate is about one thickness wide: left out of the strain
      // fit.
      FemSpecimen specimen{plies,
                           c.number("fem.length_mm", s.coupon.length / kMetresPerMm) * kMetresPerMm,
                           c.number("fem.width_mm", s.coupon.width / kMetresPerMm) * kMetresPerMm};
      const FemSettings fem_settings =
          fem_settings_from(c, context, std::min(h, 0.25 * specimen.width));
      ls.wide = std::pair{specimen, fem_settings};
    }
  }
  ls.paper_theory = paper_values(c, "paper.theory");
  ls.paper_fem = paper_values(c, "paper.fem");
  ls.paper_dem = paper_values(c, "paper.dem");
  ls.window = figure_window(c, s.coupon);
  return ls;
}

struct LaminateResults {
  TensionResult r;
  double dem_seconds = 0;
  std::optional<FemTensionResult> same, wide;  ///< CalculiX, where it ran
};

LaminateResults run_laminate(const LaminateExperimentSettings& ls, const ExperimentContext&) {
  const TensionSettings& s = ls.s;
  LaminateResults out;
  spdlog::info("{}: DEM {} {}", ls.name, ls.s.strategy, ls.layup_text);
  const auto start = std::chrono::steady_clock::now();
  out.r = TensionTest(s).run();
  out.dem_seconds = seconds_since(start);
  if (ls.same_coupon) {
    // The DEM's own coupons in CalculiX: free edges and grips are physics both share, so the DEM
    // against it is the particle model's error (CLT is an infinitely wide plate).
    spdlog::info("{}: CalculiX of the same coupon", ls.name);
    out.same = fem_twin_tension_test(s, out.r, *ls.same_coupon);
  }
  if (ls.wide) {
    spdlog::info("{}: CalculiX of a wide coupon", ls.name);
    out.wide = fem_tension_test(ls.wide->first, ls.wide->second);
  }
  return out;
}

// The constants table's DEM lines and their rows.
std::string dem_lines(const LaminateExperimentSettings& ls, const TensionResult& r,
                      double dem_seconds, ExperimentOutput& out) {
  const std::string& name = ls.name;
  const std::string& case_name = ls.case_name;
  const TensionSettings& s = ls.s;
  const Values& clt = ls.clt;
  std::string t = fmt::format("## {}: {} laminate\n\n", ls.table, ls.layup_text) +
                  constants_header() + constants_line("CLT (correct, A matrix)", clt, clt);
  add_rows(out.rows, ls.name, ls.case_name, "clt", clt);
  const Values dem = values_of(r.dem);
  t += constants_line(fmt::format("DEM {} (tension test)", s.strategy), dem, clt);
  add_rows(out.rows, name, case_name, fmt::format("dem {}", s.strategy), dem);
  out.rows.push_back(
      {name, case_name, "wall time", fmt::format("dem {}", s.strategy), dem_seconds, "s"});
  if (r.specimen.stiffness.norm() > 0) {
    // The same coupon's membrane stiffness under affine boundary displacements
    // (experiments/protocols/stiffness.hpp): no grips, no free edges, the laminate's A/h as
    // the bonds carry it.
    Values membrane = values_of(r.specimen.constants);
    t += constants_line(fmt::format("DEM {} (membrane stiffness, affine boundary)", s.strategy),
                        membrane, clt);
    add_rows(out.rows, name, case_name, fmt::format("dem {} membrane", s.strategy), membrane);
  }
  if (r.specimen.interior_particles > 0) {
    // The same solves, measured in a window inside the frame: the laminate as its bulk carries
    // it, interface bonds included, with no free edge and no frame.
    Values interior = values_of(r.specimen.interior_constants);
    t += constants_line(fmt::format("DEM {} (membrane stiffness, interior window of {} "
                                    "particles)",
                                    s.strategy, r.specimen.interior_particles),
                        interior, clt);
    add_rows(out.rows, name, case_name, fmt::format("dem {} membrane interior", s.strategy),
             interior);
  }
  out.rows.push_back({name, case_name, "particles", fmt::format("dem {}", s.strategy),
                      static_cast<double>(r.along_x.particles), "1"});
  out.rows.push_back({name, case_name, "bonds", fmt::format("dem {}", s.strategy),
                      static_cast<double>(r.along_x.bonds), "1"});
  return t;
}

// The constants table's CalculiX lines and their rows; `same_coupon_table` the DEM against
// CalculiX of the same coupon, `fem_seconds` CalculiX's time.
std::string fem_lines(const LaminateExperimentSettings& ls, const LaminateResults& results,
                      ExperimentOutput& out, std::string& same_coupon_table, double& fem_seconds) {
  const std::string& name = ls.name;
  const std::string& case_name = ls.case_name;
  const TensionSettings& s = ls.s;
  const Values& clt = ls.clt;
  const Values dem = values_of(results.r.dem);
  if (!ls.fem_skipped.empty()) return message_line("CalculiX", ls.fem_skipped);
  std::string t;
  if (results.same) {
    const FemTensionResult& same = *results.same;
    const FemTwinSettings& twin = *ls.same_coupon;
    const Values v = values_of(same.fem, false);
    fem_seconds += same.along_x.wall_seconds + same.along_y.wall_seconds;
    t += constants_line(
        fmt::format("CalculiX, the same {:g} × {:g} mm coupon ({}, {} + {} elements, {} per "
                    "ply)",
                    s.coupon.length / kMetresPerMm, s.coupon.width / kMetresPerMm,
                    fem_element_name(same.along_x.element), same.along_x.elements,
                    same.along_y.elements, twin.mesh.elements_per_ply),
        v, clt);
    add_rows(out.rows, name, case_name, "calculix same coupon", v);
    same_coupon_table = fmt::format(
        "DEM against CalculiX of the same coupon (strains at the DEM's gauge particles, the "
        "grips' force over W h): Ex {}, Ey {}, νxy {:+.4f}, νyx {:+.4f}.\n\n",
        percent_change(dem.Ex, v.Ex), percent_change(dem.Ey, v.Ey), dem.nu_xy - v.nu_xy,
        dem.nu_yx - v.nu_yx);
    const std::string source = fmt::format("dem {} vs calculix same coupon", s.strategy);
    out.rows.push_back(
        {name, case_name, "Ex relative error", source, 100 * (dem.Ex / v.Ex - 1), "%"});
    out.rows.push_back(
        {name, case_name, "Ey relative error", source, 100 * (dem.Ey / v.Ey - 1), "%"});
    out.rows.push_back({name, case_name, "nu_xy difference", source, dem.nu_xy - v.nu_xy, "1"});
    out.rows.push_back({name, case_name, "nu_yx difference", source, dem.nu_yx - v.nu_yx, "1"});
  }
  if (results.wide) {
    const FemSpecimen& specimen = ls.wide->first;
    const FemTensionResult& fem = *results.wide;
    if (!fem.available) {
      t += message_line("CalculiX", fem.message);
    } else {
      fem_seconds += fem.along_x.wall_seconds + fem.along_y.wall_seconds;
      const Values v = values_of(fem.fem, false);
      t += constants_line(fmt::format("CalculiX, a {:g} × {:g} mm coupon ({}, {} + {} elements)",
                                      specimen.length / kMetresPerMm, specimen.width / kMetresPerMm,
                                      fem_element_name(fem.along_x.element), fem.along_x.elements,
                                      fem.along_y.elements),
                          v, clt);
      add_rows(out.rows, name, case_name, "calculix", v);
    }
  }
  out.rows.push_back({name, case_name, "wall time", "calculix", fem_seconds, "s"});
  return t;
}

// The paper's rows of the constants table, theory flagged against correct CLT.
std::string paper_lines(const LaminateExperimentSettings& ls, ExperimentOutput& out) {
  std::string t;
  bool flagged = false;
  const std::pair<const char*, const std::optional<Values>*> sources[] = {
      {"theory", &ls.paper_theory}, {"fem", &ls.paper_fem}, {"dem", &ls.paper_dem}};
  for (const auto& [source, paper] : sources) {
    if (!*paper) continue;
    const bool flag = std::string(source) == "theory";
    t += constants_line(fmt::format("paper {} ({})", source, ls.table), **paper, ls.clt, flag);
    add_rows(out.rows, ls.name, ls.case_name, fmt::format("paper {}", source), **paper);
    flagged = flagged || (flag && paper_theory_off(**paper, ls.clt));
  }
  if (flagged) t += fmt::format("\n{}", paper_theory_note());
  return t;
}

// Figures and VTU: the solved coupon pulled along x. Returns the figures' report lines; `ss` the
// stress-strain figure.
std::string laminate_figures(const LaminateExperimentSettings& ls, const TensionResult& r,
                             const std::filesystem::path& out_dir, ExperimentOutput& out,
                             Figure& ss) {
  const std::string& name = ls.name;
  const std::string& layup_text = ls.layup_text;
  const TensionSettings& s = ls.s;
  const Values& clt = ls.clt;
  const double window = ls.window;
  std::vector<std::string> ply_labels;
  for (std::size_t k = 0; k < s.layup.size(); ++k) {
    ply_labels.push_back(fmt::format("ply {}: {:g}°", k, s.layup[k] * 180 / std::numbers::pi));
  }
  // The static pull along x: solved at the target strain under the test's grips.
  const Model& solved = *r.along_x.model;
  std::string figures = write_model(
      solved, out_dir, file_stem(name),
      fmt::format("{} {}: bonds coloured by normal stiffness, plies side by side (plan view, first "
                  "{:g} mm)",
                  layup_text, s.strategy, window / kMetresPerMm),
      window, out, ply_labels);
  {
    const Particles& p = solved.particles;
    std::vector<double> x, y, ux;
    const int top = p.ply.maxCoeff();
    for (int i = 0; i < p.size(); ++i) {
      if (p.ply(i) != top) continue;
      x.push_back(p.reference_position(i, 0) / kMetresPerMm);
      y.push_back(p.reference_position(i, 1) / kMetresPerMm);
      ux.push_back(p.displacement(i, 0) / kMetresPerMm * 1e3);
    }
    const Figure map = plot_field_map(
        x, y, ux, out_dir, fmt::format("{}_ux", file_stem(name)),
        fmt::format("{}: ux of the top ply at {:g}% strain", layup_text, s.target_strain * 100),
        "ux [um]");
    out.files.insert(out.files.end(), map.files.begin(), map.files.end());
    figures += fmt::format("\n{}", figure_markdown(map, "ux of the top ply, DEM static solve"));
  }
  const double max_strain = std::max(r.along_x.strain.back(), r.along_y.strain.back());
  ss = plot_curves(
      {pull_curve("DEM along x", r.along_x), theory_line("CLT Ex", clt.Ex, max_strain),
       pull_curve("DEM along y", r.along_y), theory_line("CLT Ey", clt.Ey, max_strain)},
      out_dir, fmt::format("{}_stress_strain", file_stem(name)),
      fmt::format("{}: stress-strain, static solve", layup_text), "strain [%]", "stress [MPa]");
  out.files.insert(out.files.end(), ss.files.begin(), ss.files.end());
  return figures;
}

ExperimentOutput report_laminate(const LaminateExperimentSettings& ls,
                                 const LaminateResults& results, const ExperimentContext& context) {
  const std::string& layup_text = ls.layup_text;
  const std::string& case_name = ls.case_name;
  const TensionSettings& s = ls.s;
  const double dem_seconds = results.dem_seconds;
  ExperimentOutput out;
  out.title = fmt::format("{}: the {} laminate", ls.table, layup_text);
  std::string t = dem_lines(ls, results.r, dem_seconds, out);
  double fem_seconds = 0;
  std::string same_coupon_table;
  t += fem_lines(ls, results, out, same_coupon_table, fem_seconds);
  t += paper_lines(ls, out);
  Figure ss;
  const std::string figures = laminate_figures(ls, results.r, context.out_dir, out, ss);

  std::string& md = out.report_markdown;
  md += fmt::format(
      "Layup {}{} (bottom ply first), {} plies of {:g} mm; coupon {:g} × {:g} mm, particle "
      "diameter {:g} mm; {} plies joined by interface bonds of normal stiffness {:.3g} N/m³ and "
      "shear stiffness {:.3g} N/m³ per unit area{}.\n\n",
      layup_text, case_name == layup_text ? "" : fmt::format(" = {}", case_name), s.layup.size(),
      s.coupon.thickness / kMetresPerMm, s.coupon.length / kMetresPerMm,
      s.coupon.width / kMetresPerMm, s.coupon.particle_diameter / kMetresPerMm, s.strategy,
      s.interface.resolved(s.coupon.material, s.coupon.thickness).normal,
      s.interface.resolved(s.coupon.material, s.coupon.thickness).shear,
      s.interface.normal == 0 && s.interface.shear == 0
          ? " (the library default, 10 E2/t and 10 G12/t)"
          : "");
  md += fmt::format(
      "Boundary condition: {}. γxy/εx is the shear coupling under σx alone (A16 ≠ 0 for an "
      "unbalanced layup; a clamped grip would suppress it and measure something else). DEM: "
      "static tension tests (Ex, νxy, γxy/εx pulled along x; Ey, νyx with the laminate turned by "
      "−90°), Gxy from the membrane stiffness. The membrane-stiffness row is the same coupon "
      "with affine displacements prescribed on a boundary frame (no grips, no free edges): "
      "the bonds' A/h, what CLT predicts; the interior-window row measures the same solves "
      "inside the frame, away from its boundary layer (the laminate's bulk, interface bonds "
      "included: they stiffen it where the plies' lattices are turned against each other). "
      "Where the DEM rows differ, the coupon's free "
      "edges and ends (a narrow coupon of a thick, coupled laminate) or the interface bonds' "
      "shear lag are in the tension test. CalculiX of the same coupon is the DEM's coupons in "
      "CalculiX (plies, size, grips), measured where the DEM is (strains at its gauge "
      "particles): the reference for the DEM's own error, since a coupon narrower than a few "
      "laminate thicknesses differs from CLT by physics. CalculiX of a wide coupon leaves the "
      "free-edge zone (one laminate thickness, at most a quarter of the width) out of its strain "
      "fit: the reference for CLT. DEM {:.1f} s, "
      "CalculiX {:.1f} s. The paper's E1, E2, ν12, ν21 are Ex, Ey, νxy, νyx here. Relative "
      "errors against correct CLT.\n\n",
      grips_sentence(s.grips), dem_seconds, fem_seconds);
  md += fmt::format("{}\n{}## Figures\n\n{}\n{}", t, same_coupon_table,
                    figure_markdown(ss, "Stress-strain, DEM beside CLT"), figures);
  return out;
}

}  // namespace

void register_laminate_experiment(ExperimentRegistry& registry) {
  registry.add("laminate",
               "Tables 4 and 5: a laminate beside CLT (A matrix), CalculiX and the paper",
               parse_laminate, run_laminate, report_laminate);
  registry.set_settings("laminate", [] {
    return paper_kind_settings(kLaminateSettings,
                               {{"layup", "required: the laminate"},
                                {"table", "the report's table name; default \"Laminate\""}});
  });
}

}  // namespace plydem
