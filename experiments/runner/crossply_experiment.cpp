// The cross-ply experiment kind (`plydem run experiments/crossply.toml`, kind `crossply`):
// [0_m/90_n]s laminates pulled in tension (the strength test, experiments/protocols/
// strength.hpp, with strength scatter) until they fail; per laminate the strength test's own
// section (stress-strain, cracks, crack density against strain), the first-ply failure beside
// CLT's closed form, and the laminate's secant stiffness against the 90° layer's crack density
// beside the shear-lag model and the ply-discount limit (core/transverse_cracking.hpp) and
// beside CalculiX of the same laminate with the same transverse cracks cut in (the DEM's cracks
// across at least 80% of the width at the peak). Config keys (docs/experiments.md,
// "Transverse cracking of cross-plies"):
//
//   experiment = "crossply"
//   material = "eglass-my750"   strategy = "square"   strategy_options = []
//   layups = ["[0/90]s", "[0/90_2]s", "[0/90_4]s"]
//   weibull_modulus = 10        seed = 1      scatter = "90" (or "all")
//   softening = false (true: linear-softening bonds from the material's G_fibre, G_matrix)
//   scatter_per = "site" (one factor per crack site, StrengthSettings::scatter_per_crack_site) or
//                 "bond"
//   [coupon] length_mm, width_mm, thickness_mm (per ply), diameter_mm, grip_mm
//   [quick]  the same sizes, and layups
//   [interface] normal, shear (N/m^3), strength_normal, strength_shear (Pa),
//               transverse_shear = true (the plies carry G13, G23: strategies/laminate.hpp)
//   [fem] element_mm (0 = half a particle diameter), elements_per_ply = 2, threads = 1
//   [events] max_events, stop_fraction, max_update_rank
//   [output] vtu_series
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "core/error.hpp"
#include "core/transverse_cracking.hpp"
#include "core/units.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/report_text.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "experiments/runner/strength_experiment.hpp"
#include "solvers/cracks.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kStiffnessSamples = 100;

bool at_angle(double angle, double degrees) {
  const double turns = (angle - degrees * kDegree) / std::numbers::pi;
  return std::abs(turns - std::round(turns)) < 1e-9;
}

// The 0° sublaminate's plies (m, each side) and the 90° layer's (2n, in the middle) of a
// [0_m/90_n]s layup; throws naming the layup otherwise.
std::pair<int, int> crossply_counts(const std::vector<double>& layup, const std::string& text) {
  const int plies = static_cast<int>(layup.size());
  int m = 0;
  while (m < plies && at_angle(layup[m], 0)) ++m;
  int ninety = 0;
  while (m + ninety < plies && at_angle(layup[m + ninety], 90)) ++ninety;
  const bool ok =
      m > 0 && ninety > 0 && ninety % 2 == 0 && 2 * m + ninety == plies &&
      std::all_of(layup.begin() + m + ninety, layup.end(), [](double a) { return at_angle(a, 0); });
  require(ok, fmt::format("crossply: layup '{}' is not a cross-ply [0_m/90_n]s (0° plies outside, "
                          "an even number of 90° plies in the middle)",
                          text));
  return {m, ninety / 2};
}

// The fraction of the coupon's width a crack must span to count as a transverse crack.
constexpr double kSpanningFraction = 0.8;

// The 90° plies' transverse crack planes (transverse_crack_planes: broken bonds across one gap
// between particle columns over at least kSpanningFraction of the width) whose x lies in
// [x_begin, x_end], per 90° ply.
std::vector<std::vector<CrackPlane>> ninety_planes(const Model& model,
                                                   const std::vector<BondBreak>& breaks,
                                                   const std::vector<int>& ninety, double x_begin,
                                                   double x_end, double width) {
  std::vector<std::vector<CrackPlane>> planes;
  for (int ply : ninety) {
    std::vector<CrackPlane> p =
        transverse_crack_planes(model, breaks, ply, kSpanningFraction * width);
    std::erase_if(p,
                  [&](const CrackPlane& c) { return c.position < x_begin || c.position > x_end; });
    planes.push_back(std::move(p));
  }
  return planes;
}

// A traction-free plane: at least kSpanningFraction of the bonds across it broken (the others
// bridge it).
bool traction_free(const CrackPlane& c) {
  return c.bonds >= kSpanningFraction * c.crossing;
}

// Their mean number per unit length over [x_begin, x_end]; `only_traction_free`: of those only.
double ninety_density(const std::vector<std::vector<CrackPlane>>& planes, double x_begin,
                      double x_end, bool only_traction_free = false) {
  double sum = 0;
  for (const std::vector<CrackPlane>& p : planes)
    sum += static_cast<double>(only_traction_free ? std::count_if(p.begin(), p.end(), traction_free)
                                                  : std::ssize(p));
  return sum / static_cast<double>(planes.size()) / (x_end - x_begin);
}

// CalculiX of the cross-ply with the DEM's transverse cracks cut in: its axial stiffness between
// the grips over the intact laminate's.
struct FemCrackedStiffness {
  std::string skipped;  ///< why it did not run ("" when it did)
  int cracks = 0;       ///< FEM cracks cut
  double ratio = 1;     ///< K cracked / K intact
};

// The 90° plies' crack planes gathered across the plies: planes of different 90° plies within a
// quarter diameter of each other are one FEM crack, at their mean x, through the plies from the
// lowest to the highest of them.
FemCrackedStiffness fem_cracked_stiffness(const std::vector<std::vector<CrackPlane>>& planes,
                                          const std::vector<int>& ninety, const FemSpecimen& intact,
                                          double x_begin, double diameter,
                                          const FemSettings& settings) {
  FemCrackedStiffness out;
  struct Cut {
    double x;
    int ply;
  };
  std::vector<Cut> cuts;
  for (std::size_t k = 0; k < planes.size(); ++k)
    for (const CrackPlane& c : planes[k]) cuts.push_back({c.position, ninety[k]});
  if (cuts.empty()) {
    out.skipped = "no transverse crack at the peak";
    return out;
  }
  std::sort(cuts.begin(), cuts.end(), [](const Cut& a, const Cut& b) { return a.x < b.x; });
  FemSpecimen cracked = intact;
  for (std::size_t k = 0; k < cuts.size();) {
    std::size_t j = k;
    double sum = 0;
    int low = cuts[k].ply, high = cuts[k].ply;
    while (j < cuts.size() && cuts[j].x - cuts[k].x <= 0.25 * diameter) {
      sum += cuts[j].x;
      low = std::min(low, cuts[j].ply);
      high = std::max(high, cuts[j].ply);
      ++j;
    }
    const double x = sum / static_cast<double>(j - k) - x_begin;
    if (x > 0 && x < intact.length) cracked.cracks.push_back({x, low, high});
    k = j;
  }
  out.cracks = static_cast<int>(cracked.cracks.size());
  const FemSolution whole = run_calculix(intact, settings);
  const FemSolution cut = run_calculix(cracked, settings);
  out.ratio =
      (cut.reaction_force / cut.end_displacement) / (whole.reaction_force / whole.end_displacement);
  return out;
}

// A `crossply` config's settings: the strength test common to every laminate, the FEM's, and
// the laminates.
struct CrossplySettings {
  std::string name;  ///< the config's, naming rows and files
  StrengthSettings base;
  FemSettings fem;
  bool scatter_ninety = true;  ///< scatter = "90"
  std::vector<std::string> layups;
  std::vector<std::pair<int, int>> counts;  ///< (m, n) of each [0_m/90_n]s
};

// The kind's settings: the strength command's (strength_settings_description()) but the ply
// angle, the layup (each case's, from layups) and the hole; its defaults are the command's but
// scatter (Weibull modulus 10, per crack site) and the plies carrying the transverse shear.
SettingsSelection crossply_selection() {
  return {{}, {"angle", "layup", "hole_diameter"}};
}

StrengthSettings crossply_defaults(const ExperimentContext& context) {
  StrengthSettings base = strength_settings_description().defaults();
  base.force = context.force;
  base.interface.transverse_shear = true;
  base.weibull_modulus = 10;
  base.scatter_per_crack_site = true;
  return base;
}

const std::vector<std::pair<std::string, std::string>>& crossply_own_keys() {
  static const std::vector<std::pair<std::string, std::string>> keys{
      {"layups",
       "the [0_m/90_n]s laminates, one case each; default [\"[0/90]s\", "
       "\"[0/90_2]s\", \"[0/90_4]s\"]"},
      {"quick.layups", "the laminates of a quick run"},
      {"scatter", "\"90\" (the strength scatter in the 90° plies only, the default) or \"all\""},
      {"fem.element_mm", "CalculiX's in-plane element size [mm]; 0 = half a particle diameter"},
      {"fem.elements_per_ply", "CalculiX's elements through each ply; default 2"},
      {"fem.threads", "threads CalculiX may use; default 1"}};
  return keys;
}

CrossplySettings parse_crossply(const ExperimentConfig& c, const ExperimentContext& context) {
  const SettingsDescription<StrengthSettings>& d = strength_settings_description();
  c.require_known_keys(config_keys(d, crossply_selection(), crossply_own_keys()));
  const std::string name = c.name();
  const std::string origin = c.path().string();
  std::vector<std::string> layups = c.strings("layups", {"[0/90]s", "[0/90_2]s", "[0/90_4]s"});
  if (context.quick) layups = c.strings("quick.layups", layups);
  require(!layups.empty(), fmt::format("{}: layups is empty", origin));
  std::vector<std::pair<int, int>> counts;
  for (const std::string& text : layups) {
    try {
      counts.push_back(crossply_counts(parse_layup(text), text));
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", origin, e.what()));
    }
  }
  StrengthSettings base = crossply_defaults(context);
  // Every case is a laminate: the interface keys apply (the conditions see the first one).
  base.layup = parse_layup(layups.front());
  read_config_settings(c, d, crossply_selection(), context.quick, base);
  base.layup.clear();  // each case sets its own
  FemSettings fem;
  fem.mesh.element_size = c.number("fem.element_mm", 0) * kMetresPerMm;
  fem.mesh.elements_per_ply = static_cast<int>(c.integer("fem.elements_per_ply", 2));
  fem.threads = static_cast<int>(c.integer("fem.threads", 1));
  if (fem.mesh.element_size == 0) fem.mesh.element_size = 0.5 * base.coupon.particle_diameter;
  fem.validate();
  const std::string scatter = c.string("scatter", "90");
  require(scatter == "90" || scatter == "all",
          fmt::format("{}: scatter must be \"90\" (the 90° plies only) or \"all\", got \"{}\"",
                      origin, scatter));
  require_strengths(base.coupon.material, fmt::format("{} (kind crossply)", origin));
  return {name, base, fem, scatter == "90", layups, counts};
}

KindSettings crossply_kind_settings() {
  ExperimentContext context;
  return {strength_settings_description().rows(crossply_defaults(context), crossply_selection()),
          crossply_own_keys()};
}

// One laminate pulled to failure, its 90° plies' cracks at the peak and CalculiX with them cut in.
struct LaminateRun {
  std::string text;  ///< the layup as written
  int m = 0, n = 0;
  StrengthSettings settings;
  StrengthResult result;
  double x_begin = 0, x_end = 0;  ///< the free length between the grips
  std::vector<int> ninety;        ///< the 90° plies
  FemCrackedStiffness fem_same;
  double dem_grips = NAN;  ///< the DEM's secant between the grips at the peak, over the intact one
  double traction_free_density = 0;  ///< of the 90° plies' crack planes at the peak [1/m]
};

LaminateRun run_laminate(const CrossplySettings& cs, std::size_t k, SpecimenBuilder& builder,
                         const CalculixAvailability& ccx) {
  LaminateRun run;
  run.text = cs.layups[k];
  const std::string& text = run.text;
  std::tie(run.m, run.n) = cs.counts[k];
  const int m = run.m, n = run.n;
  StrengthSettings& s = run.settings;
  s = cs.base;
  s.layup = parse_layup(text);
  if (cs.scatter_ninety)
    for (int p = m; p < m + 2 * n; ++p) s.scatter_plies.push_back(p);
  s.validate();
  spdlog::info("{}: {} in tension to failure", cs.name, text);
  StrengthTest test(s);
  test.on_progress([&](const EventProgress& p) {
    spdlog::info("{}: {} events, {} broken, peak {:.4g} N, {:.0f} s", text, p.events, p.broken,
                 p.peak_reaction, p.elapsed_seconds);
  });
  run.result = test.run(builder);
  const StrengthResult& r = run.result;
  const Model& model = *r.model;
  const Material& material = cs.base.coupon.material;
  const double t = cs.base.coupon.thickness;
  const double grip = s.grip_length > 0 ? s.grip_length : 2.0 * s.coupon.particle_diameter;
  run.x_begin = model.particles.reference_position.col(0).minCoeff() + grip;
  run.x_end = model.particles.reference_position.col(0).maxCoeff() - grip;
  const double x_begin = run.x_begin, x_end = run.x_end;
  std::vector<int>& ninety = run.ninety;
  for (int p = m; p < m + 2 * n; ++p) ninety.push_back(p);
  if (r.peak >= 0 && static_cast<std::size_t>(r.peak) + 1 < r.stress.size()) {
    const std::size_t e = static_cast<std::size_t>(r.peak) + 1;
    run.dem_grips = (r.stress[e] / r.nominal_strain[e]) / (r.stress[1] / r.nominal_strain[1]);
  }
  std::vector<BondBreak> at_peak;
  for (const BondBreak& br : r.breaks)
    if (br.at < static_cast<double>(r.peak + 1)) at_peak.push_back(br);
  const std::vector<std::vector<CrackPlane>> peak_planes =
      ninety_planes(model, at_peak, ninety, x_begin, x_end, s.coupon.width);
  run.traction_free_density = ninety_density(peak_planes, x_begin, x_end, true);
  if (!ccx.available) {
    run.fem_same.skipped = ccx.message;
  } else {
    FemSpecimen specimen;
    for (double angle : s.layup) specimen.plies.push_back({material, angle, t});
    specimen.length = x_end - x_begin;
    specimen.width = s.coupon.width;
    spdlog::info("{}: {}: CalculiX with the peak's transverse cracks cut in", cs.name, text);
    run.fem_same = fem_cracked_stiffness(peak_planes, ninety, specimen, x_begin,
                                         s.coupon.particle_diameter, cs.fem);
  }
  return run;
}

std::vector<LaminateRun> run_crossply(const CrossplySettings& cs, const ExperimentContext&) {
  const std::unique_ptr<Strategy> strategy = default_registry().create(cs.base.strategy);
  for (const auto& [option, value] : cs.base.strategy_options) strategy->set_option(option, value);
  SpecimenBuilder builder(*strategy);
  const CalculixAvailability ccx = calculix_availability();
  std::vector<LaminateRun> runs;
  for (std::size_t k = 0; k < cs.layups.size(); ++k)
    runs.push_back(run_laminate(cs, k, builder, ccx));
  return runs;
}

// The secant stiffness (the path unloads to the origin) against the 90° crack density at up to
// kStiffnessSamples critical states, over the free length between the grips.
struct StiffnessSamples {
  Curve dem;
  std::string csv;                          ///< STEM_crack_planes.csv
  double last_density = 0, last_ratio = 1;  ///< at the last sample up to the peak
};

StiffnessSamples sample_stiffness(const LaminateRun& run) {
  const std::string& text = run.text;
  const StrengthSettings& s = run.settings;
  const StrengthResult& r = run.result;
  const Model& model = *r.model;
  const double x_begin = run.x_begin, x_end = run.x_end;
  const std::vector<int>& ninety = run.ninety;
  const std::size_t events = r.strain.size() - 1;
  Curve dem{fmt::format("DEM {}", text), {}, {}, true};
  const double e0 = r.stress[1] / r.strain[1];
  std::vector<BondBreak> so_far;
  std::size_t next = 0;
  double last_density = 0, last_ratio = 1;
  std::size_t last_event = 0;
  std::string planes_csv =
      "event,strain,stress_MPa,crack_planes_per_mm,traction_free_per_mm,E_over_E0\n";
  for (std::size_t j = 1; j <= kStiffnessSamples; ++j) {
    const std::size_t e = std::max<std::size_t>(1, events * j / kStiffnessSamples);
    if (e == last_event) continue;
    last_event = e;
    while (next < r.breaks.size() && r.breaks[next].at < static_cast<double>(e))
      so_far.push_back(r.breaks[next++]);
    // At critical state e the bonds broken before it are gone: its secant is theirs.
    if (r.strain[e] <= 0) continue;
    const std::vector<std::vector<CrackPlane>> planes =
        ninety_planes(model, so_far, ninety, x_begin, x_end, s.coupon.width);
    const double density = ninety_density(planes, x_begin, x_end);
    const double free_density = ninety_density(planes, x_begin, x_end, true);
    const double ratio = r.stress[e] / r.strain[e] / e0;
    planes_csv += fmt::format("{},{:.8g},{:.6g},{:.6g},{:.6g},{:.6g}\n", e, r.strain[e],
                              r.stress[e] * kMPaPerPa, density * kMetresPerMm,
                              free_density * kMetresPerMm, ratio);
    dem.x.push_back(density * kMetresPerMm);
    dem.y.push_back(ratio);
    // Up to the peak: after it the 0° plies break and the laminate is failing.
    if (static_cast<long>(e) <= r.peak + 1) {
      last_density = density;
      last_ratio = ratio;
    }
  }
  return {dem, planes_csv, last_density, last_ratio};
}

// One laminate's part of the report: its strength test's section, its row of the summary table,
// its curves of the stiffness figure, the crack planes' CSV and results.csv's rows.
void report_laminate(const CrossplySettings& cs, const LaminateRun& run, const fs::path& out_dir,
                     ExperimentOutput& out, std::string& table, std::string& fem_notes,
                     std::string& sections, std::vector<Curve>& curves) {
  const std::string& name = cs.name;
  const std::string& text = run.text;
  const int m = run.m, n = run.n;
  const StrengthResult& r = run.result;
  const Material& material = cs.base.coupon.material;
  const double t = cs.base.coupon.thickness;
  const FemCrackedStiffness& fem_same = run.fem_same;
  const double dem_grips = run.dem_grips, traction_free_density = run.traction_free_density;
  const std::string stem = file_stem(fmt::format("{}_{}", name, text));
  const ExperimentOutput one = strength_output(r, out_dir, name, text, stem);
  out.rows.insert(out.rows.end(), one.rows.begin(), one.rows.end());
  out.files.insert(out.files.end(), one.files.begin(), one.files.end());
  sections += one.report_markdown;
  const double b = m * t, d = n * t;
  const StiffnessSamples samples = sample_stiffness(run);
  const double last_density = samples.last_density, last_ratio = samples.last_ratio;
  curves.push_back(samples.dem);
  const fs::path planes_file = fs::path(stem + "_crack_planes.csv");
  {
    std::ofstream file(out_dir / planes_file, std::ios::binary);
    file << samples.csv;
    require(static_cast<bool>(file),
            fmt::format("crossply: could not write {}", (out_dir / planes_file).string()));
  }
  out.files.push_back(planes_file);
  Curve lag{fmt::format("shear lag {}", text), {}, {}, false};
  const double top = std::max(2.0 * last_density, 1.0 / (2.0 * t * (m + n)));
  for (int j = 0; j <= 60; ++j) {
    const double density = top * j / 60;
    lag.x.push_back(density * kMetresPerMm);
    lag.y.push_back(shear_lag_stiffness_ratio(material, b, d, density));
  }
  curves.push_back(lag);
  const double discount = ply_discount_stiffness_ratio(material, b, d);
  curves.push_back(
      {fmt::format("ply discount {}", text), {0, top * kMetresPerMm}, {discount, discount}, false});
  const double lag_ratio = shear_lag_stiffness_ratio(material, b, d, last_density);
  if (!fem_same.skipped.empty()) fem_notes += fmt::format("- {}: {}\n", text, fem_same.skipped);
  double fpf = NAN;
  for (const CriterionStrength& cs : r.theory)
    if (cs.criterion == FailureCriterion::kMaxStress && cs.strength) fpf = *cs.strength;
  table += markdown_row({text, fmt::format("{:.2f}", r.first_failure_stress * kMPaPerPa),
                         fmt::format("{:.2f}", fpf * kMPaPerPa),
                         fmt::format("{:+.2f}%", 100 * (r.first_failure_stress / fpf - 1)),
                         fmt::format("{:.1f}", r.strength * kMPaPerPa),
                         fmt::format("{:.3f}", r.strain_at_peak * 100),
                         fmt::format("{:.3g}", last_density * kMetresPerMm),
                         fmt::format("{:.3g}", traction_free_density * kMetresPerMm),
                         fmt::format("{:.3f}", last_ratio), fmt::format("{:.3f}", lag_ratio),
                         fmt::format("{:.3f}", discount), fmt::format("{:.3f}", dem_grips),
                         fem_same.skipped.empty() ? fmt::format("{:.3f}", fem_same.ratio) : "-",
                         fmt::format("{}", fem_same.cracks), fmt::format("{}", r.events)});
  auto row = [&](const std::string& quantity, const std::string& source, double value,
                 const std::string& unit) {
    if (std::isfinite(value)) out.rows.push_back({name, text, quantity, source, value, unit});
  };
  row("first ply failure stress", "clt max-stress", fpf * kMPaPerPa, "MPa");
  row("crack density 90 at peak", fmt::format("dem {}", r.strategy), last_density * kMetresPerMm,
      "1/mm");
  row("stiffness ratio at peak", fmt::format("dem {}", r.strategy), last_ratio, "1");
  row("stiffness ratio at peak", "shear lag", lag_ratio, "1");
  row("stiffness ratio", "ply discount", discount, "1");
  row("stiffness ratio at peak between grips", fmt::format("dem {}", r.strategy), dem_grips, "1");
  row("traction-free crack density 90 at peak", fmt::format("dem {}", r.strategy),
      traction_free_density * kMetresPerMm, "1/mm");
  if (fem_same.skipped.empty()) {
    row("stiffness ratio at peak between grips", "calculix same cracks", fem_same.ratio, "1");
    row("cracks cut in calculix", "calculix same cracks", fem_same.cracks, "1");
  }
}

ExperimentOutput report_crossply(const CrossplySettings& cs, const std::vector<LaminateRun>& runs,
                                 const ExperimentContext& context) {
  const std::string& name = cs.name;
  const StrengthSettings& base = cs.base;
  const FemSettings& fem = cs.fem;
  const Material& material = base.coupon.material;
  const double t = base.coupon.thickness;
  ExperimentOutput out;
  out.title =
      fmt::format("Transverse cracking of cross-plies: {} ({})", material.name, base.strategy);
  std::string table =
      markdown_row({"laminate", "first failure DEM (MPa)", "first-ply failure, max-stress (MPa)",
                    "DEM vs it", "strength (MPa)", "strain at peak (%)",
                    "90° transverse cracks per mm at the peak", "of which traction-free, per mm",
                    "E/E0 DEM", "E/E0 shear lag", "E/E0 ply discount", "E/E0 DEM between the grips",
                    "E/E0 CalculiX, same cracks", "cracks cut in CalculiX", "events"}) +
      "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
  std::string fem_notes;
  std::string sections;
  std::vector<Curve> curves;
  for (const LaminateRun& run : runs)
    report_laminate(cs, run, context.out_dir, out, table, fem_notes, sections, curves);
  PlotAxes axes;
  axes.key = "right top";
  const Figure figure =
      plot_curves(curves, context.out_dir, fmt::format("{}_stiffness", file_stem(name)),
                  fmt::format("{}: secant stiffness against the 90° crack density", material.name),
                  "cracks per mm in the 90° layer", "E / E0", axes);
  out.files.insert(out.files.end(), figure.files.begin(), figure.files.end());

  std::string& md = out.report_markdown;
  md += fmt::format(
      "Cross-ply laminates of {} on {:g} × {:g} mm coupons, {:g} mm plies, {:g} mm particles, "
      "strategy {}, Weibull strength scatter m = {:g} (seed {}) in {}, uniform grips, events "
      "(sequentially linear: each point a critical state, the path unloading to the origin, so "
      "stress / strain there is the damaged laminate's secant stiffness). {}\n\n",
      material.name, base.coupon.length / kMetresPerMm, base.coupon.width / kMetresPerMm,
      t / kMetresPerMm, base.coupon.particle_diameter / kMetresPerMm, base.strategy,
      base.effective_weibull_modulus(), base.seed,
      cs.scatter_ninety ? "the 90° plies (the 0° plies at their calibrated strengths)"
                        : "every ply",
      base.interface_strength.given()
          ? "The interfaces break at the strengths given."
          : "The interfaces do not break (no interface strengths given).");
  md += fmt::format(
      "## Summary\n\n*First failure* is the first break, beside the closed-form first-ply "
      "failure of CLT (max-stress on each ply's stress under the mean sigma_x); the crack "
      "density is the 90° plies' mean number of transverse cracks per mm between the grips at "
      "the peak: gaps between particle columns with broken bonds across at least {:.0f}% of the "
      "width (solvers/cracks.hpp transverse_crack_planes: cracks one spacing apart stay apart); "
      "*traction-free* ones have that fraction of the bonds across them broken too (the others "
      "still bridge, through the lattice's diagonal bonds); E/E0 is the "
      "secant stiffness there over the intact one, beside the shear-lag model (Garrett & "
      "Bailey 1977) at the same density and the ply-discount limit "
      "(core/transverse_cracking.hpp). *Between the grips* is the same secant with the grips' "
      "separation as the strain, the measure CalculiX gives: its column is CalculiX of the same "
      "laminate between the grips (C3D8I, {:g} mm elements, {} per ply, ends moved along x and "
      "free laterally) with the DEM's transverse crack planes at the peak cut in "
      "(traction-free; planes of different 90° plies within a quarter diameter of each other "
      "one crack through them), over the intact laminate's. {}\n\n{}{}\n{}\n",
      100 * kSpanningFraction, fem.mesh.element_size / kMetresPerMm, fem.mesh.elements_per_ply,
      base.interface.transverse_shear
          ? "The plies carry the laminate's transverse shear (G13, G23; interface "
            "transverse_shear, strategies/laminate.hpp)."
          : "The plies do not carry transverse shear (interface transverse_shear = false): the "
            "DEM loses too much stiffness per crack (strategies/laminate.hpp).",
      table, fem_notes.empty() ? "" : "\nCalculiX not run:\n\n" + fem_notes,
      figure_markdown(figure, "Secant stiffness against crack density"));
  md += "## Each laminate\n\n" + sections;
  return out;
}

}  // namespace

void register_crossply_experiment(ExperimentRegistry& registry) {
  registry.add("crossply",
               "cross-ply laminates in tension to failure: first-ply failure, transverse crack "
               "density and stiffness beside shear lag and ply discount",
               parse_crossply, run_crossply, report_crossply);
  registry.set_settings("crossply", crossply_kind_settings);
}

}  // namespace plydem
