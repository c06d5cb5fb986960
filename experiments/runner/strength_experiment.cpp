#include "experiments/runner/strength_experiment.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "core/units.hpp"
#include "experiments/output/crack_report.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/output/strength_report.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/report_text.hpp"
#include "experiments/runner/settings_config.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

std::string mpa_cell(double pascals) {
  return std::isfinite(pascals) ? fmt::format("{:.2f}", pascals * kMPaPerPa) : "–";
}

const char* source_name(FailureCriterion c) {
  switch (c) {
    case FailureCriterion::kMaxStress:
      return "max-stress";
    case FailureCriterion::kTsaiHill:
      return "tsai-hill";
    case FailureCriterion::kTsaiWu:
      return "tsai-wu";
    case FailureCriterion::kHashin:
      return "hashin";
    case FailureCriterion::kPuck:
      return "puck";
  }
  return "?";
}

}  // namespace

// How the ply fails in the run: bond by bond, or at the material point.
std::string failure_model_note(const StrengthSettings& s) {
  const PlyFailureModel model = s.effective_failure_criterion();
  if (model == PlyFailureModel::kBond) {
    return fmt::format(
        "The bonds are {} parallel bonds (PFC's criterion, core/bond_failure.hpp) whose strengths "
        "are calibrated so that the relaxed bulk without scatter first breaks exactly at XT, YT "
        "and S12 in the ply's axes (strategies/strength_calibration.hpp). The model is linear up "
        "to each break: it does not represent the ply's non-linear in-plane shear response "
        "(E-glass reaches S12 at about 4% shear strain, a linear bond at 1.25%), and XC, YC only "
        "through the bonds' shear mode.",
        s.strength_options.softening ? "linear-softening" : "brittle");
  }
  return fmt::format(
      "Failure is decided at the material point: each particle's site stress, in its ply's axes, "
      "is judged by {}'s criterion with the lamina strengths, and a failed site opens every bond "
      "across its crack plane at once ({}; contacts/site_failure.hpp). The model is linear up to "
      "each crack{}.",
      failure_model_name(model),
      s.strength_options.softening ? "softening to dissipate G_matrix or G_fibre per unit area"
                                   : "brittle",
      s.coupon.material.shear_curve.empty() || s.load != StrengthLoad::kShear
          ? ""
          : " but in in-plane shear, which follows the material's shear_curve by plastic shear "
            "strain (solvers/plastic_shear.hpp)");
}

std::string strength_model_note(const StrengthSettings& s) {
  return fmt::format(
      "{} Loading: {} ({}). Grips {}; {}.", failure_model_note(s), strength_method_name(s.method),
      s.method == StrengthMethod::kEvents
          ? "sequentially linear analysis: each critical state is one point, no damping, no "
            "loading rate"
          : "damped dynamics, the grips moving at a constant rate: solvers/explicit_failure.hpp",
      s.grips == StrengthGrips::kUniform
          ? "uniform (held at the relaxed bulk's uniform state under sigma_x: uniform uniaxial "
            "stress up to the grips)"
      : s.grips == StrengthGrips::kFree
          ? "free (rigid along x, the ends contract and shear freely; they restrain the ply "
            "near the grips)"
          : "clamped (rigid along x and held laterally)",
      s.load == StrengthLoad::kShear
          ? "in shear a frame holds the coupon; stress is the gauge particles' mean virial tau_xy, "
            "strain their fitted gamma_xy"
          : "stress is the right grip's reaction over the gauge cross-section, strain the gauge "
            "particles' fitted strain");
}

ExperimentOutput strength_output(const StrengthResult& r, const fs::path& out_dir,
                                 const std::string& experiment, const std::string& case_name,
                                 const std::string& stem) {
  ExperimentOutput out;
  const std::string dem = fmt::format("dem {}", r.strategy);
  auto row = [&](const std::string& quantity, const std::string& source, double value,
                 const std::string& unit) {
    if (std::isfinite(value))
      out.rows.push_back({experiment, case_name, quantity, source, value, unit});
  };
  row("strength", dem, r.strength * kMPaPerPa, "MPa");
  row("strain at peak", dem, r.strain_at_peak * 100, "%");
  row("first failure stress", dem, r.first_failure_stress * kMPaPerPa, "MPa");
  row("first failure stress", fmt::format("{} calibrated bulk", dem),
      r.model_first_failure * kMPaPerPa, "MPa");
  row("broken bonds in tension", dem, r.broken_tension, "1");
  row("broken bonds in shear", dem, r.broken_shear, "1");
  for (const BrokenBonds& b : r.broken) {
    row(fmt::format("broken bonds {} tension", b.family), dem, b.tension, "1");
    row(fmt::format("broken bonds {} shear", b.family), dem, b.shear, "1");
  }
  // How far past the peak the run went (events): the coupon's stiffness after the last event
  // over the intact coupon's.
  row("final stiffness over intact", dem, r.final_stiffness_ratio, "1");
  row("events", dem, static_cast<double>(r.events), "1");
  row("energy released", dem, r.dissipated_energy, "J");
  row("wall time", dem, r.wall_seconds, "s");
  for (const CriterionStrength& t : r.theory) {
    if (t.strength) row("strength", source_name(t.criterion), *t.strength * kMPaPerPa, "MPa");
  }

  std::string& md = out.report_markdown;
  md += fmt::format("### {}\n\n", case_name);
  md += markdown_row({"quantity", "DEM", "unit"}) + "|---|---|---|\n";
  md += markdown_row({"strength (peak stress)", mpa_cell(r.strength), "MPa"});
  md += markdown_row({"strain at peak", fmt::format("{:.4f}", r.strain_at_peak * 100), "%"});
  md += markdown_row({"first-failure stress", mpa_cell(r.first_failure_stress), "MPa"});
  md += markdown_row({"calibrated bulk's first failure (no edges, no scatter)",
                      mpa_cell(r.model_first_failure), "MPa"});
  md += markdown_row({"events (stopped: " + r.stop + ")", fmt::format("{}", r.events), ""});
  md += markdown_row(
      {"energy released by breaking", fmt::format("{:.4g}", r.dissipated_energy), "J"});
  md += "\n";
  md += markdown_row({r.layup.empty() ? "criterion" : "criterion (first-ply failure, CLT)",
                      "strength (MPa)",
                      fmt::format("DEM {} relative to it", criteria_compared_name(r))});
  md += "|---|---|---|\n";
  for (const CriterionStrength& t : r.theory) {
    md +=
        markdown_row({criterion_label(t.criterion),
                      t.strength ? mpa_cell(*t.strength) : fmt::format("– ({})", t.missing),
                      t.strength ? percent_change(criteria_compared_stress(r), *t.strength) : "–"});
  }
  md += "\n";
  md += markdown_row({"broken bonds (family)", "tension", "shear"});
  md += "|---|---|---|\n";
  for (const BrokenBonds& b : r.broken)
    md += markdown_row({b.family, fmt::format("{}", b.tension), fmt::format("{}", b.shear)});
  md +=
      markdown_row({"all", fmt::format("{}", r.broken_tension), fmt::format("{}", r.broken_shear)});
  if (!r.ply_strengths.empty()) {
    const StrengthCalibration& c = r.ply_strengths.front();
    md += fmt::format(
        "\nStrength calibration of the {}ply at {:g}°: the model's first failure under each "
        "target's loading (bulk, no scatter) beside the target.\n\n",
        r.layup.empty() ? "" : "bottom ", c.ply_angle / kDegree);
    md += markdown_row({"target", "lamina (MPa)", "model first failure (MPa)", "calibrated",
                        "breaks first"}) +
          "|---|---|---|---|---|\n";
    for (const StrengthTarget& t : c.targets) {
      md +=
          markdown_row({t.name, t.target > 0 ? mpa_cell(t.target) : "not given", mpa_cell(t.model),
                        t.calibrated ? "yes" : "reported only",
                        t.family.empty() ? "–" : fmt::format("family {} ({})", t.family, t.mode)});
    }
  }
  md += "\n";
  const Figure curve = plot_strength_curve(
      r, out_dir, fmt::format("{}_stress_strain", stem),
      fmt::format("{}: stress-strain to failure beside the criteria", case_name));
  out.files.insert(out.files.end(), curve.files.begin(), curve.files.end());
  md += figure_markdown(curve, fmt::format("{}: stress-strain to failure, the classical criteria "
                                           "as horizontal lines",
                                           case_name)) +
        "\n";
  const Figure cracks = plot_crack_pattern(r, out_dir, fmt::format("{}_cracks", stem),
                                           fmt::format("{}: broken bonds by mode", case_name));
  out.files.insert(out.files.end(), cracks.files.begin(), cracks.files.end());
  md += figure_markdown(cracks,
                        fmt::format("{}: crack pattern (bonds by state, plan view)", case_name)) +
        "\n";
  const std::vector<fs::path> vtu = write_strength_vtu(r, out_dir, stem);
  out.files.insert(out.files.end(), vtu.begin(), vtu.end());
  md += fmt::format("ParaView: `{}` ({} states; bond cell data `state`, `damage`).\n\n",
                    vtu.front().generic_string(), (vtu.size() - 1) / 2);
  const CrackReport crack_summary = crack_report(*r.model, r.breaks, r.strain, out_dir, stem,
                                                 fmt::format("{}: cracks", case_name));
  out.files.insert(out.files.end(), crack_summary.files.begin(), crack_summary.files.end());
  md += crack_summary.markdown;
  row("cracks", dem, static_cast<double>(crack_summary.cracks.size()), "1");
  for (const CrackCount& n : crack_summary.counts) {
    const std::string where = crack_place(n.interface, n.ply);
    row(fmt::format("cracks {}", where), dem, n.cracks, "1");
    row(fmt::format("crack density {}", where), dem, n.density * kMetresPerMm, "1/mm");
  }
  return out;
}

namespace {

// A `strength` config's settings: the test common to every angle, and the angles.
struct StrengthExperimentSettings {
  std::string name;        ///< the config's, naming rows and files
  std::string layup_text;  ///< "" for one ply
  StrengthSettings base;
  std::vector<double> angles;  ///< [deg]
};

// The kind's settings: the strength command's (strength_settings_description(), with its
// defaults), but the ply angle, which each case sets (angle_deg, angles_deg).
SettingsSelection strength_kind_selection() {
  return {{}, {"angle"}};
}

const std::vector<std::pair<std::string, std::string>>& strength_own_keys() {
  static const std::vector<std::pair<std::string, std::string>> keys{
      {"angle_deg", "the ply angle of the one case [deg] when angles_deg is not given; default 0"},
      {"angles_deg", "the ply angles of the cases [deg] (a laminate's layup turned by each)"}};
  return keys;
}

StrengthExperimentSettings parse_strength(const ExperimentConfig& c,
                                          const ExperimentContext& context) {
  const SettingsDescription<StrengthSettings>& d = strength_settings_description();
  c.require_known_keys(config_keys(d, strength_kind_selection(), strength_own_keys()));
  const std::string origin = c.path().string();
  StrengthSettings base = d.defaults();
  base.force = context.force;
  read_config_settings(c, d, strength_kind_selection(), context.quick, base);
  const std::string layup_text = c.string("layup", "");  // as written, naming the cases
  std::vector<double> angles = c.numbers("angles_deg", {c.number("angle_deg", 0)});
  require(!angles.empty(), fmt::format("{}: angles_deg is empty", origin));
  base.validate();  // a bad setting fails before the first coupon is built
  base.require_strengths_for(fmt::format("{} (kind strength)", origin));
  return {c.name(), layup_text, base, angles};
}

KindSettings strength_kind_settings() {
  const SettingsDescription<StrengthSettings>& d = strength_settings_description();
  return {d.rows(d.defaults(), strength_kind_selection()), strength_own_keys()};
}

// One angle's test, or why it was refused.
struct AngleRun {
  double angle_deg = 0;
  std::string case_name;
  std::optional<StrengthResult> result;
  std::string refused;  ///< the error, when result is empty
};

std::vector<AngleRun> run_strength(const StrengthExperimentSettings& settings,
                                   const ExperimentContext&) {
  const std::string& name = settings.name;
  const std::string& layup_text = settings.layup_text;
  const StrengthSettings& base = settings.base;
  const std::unique_ptr<Strategy> strategy = default_registry().create(base.strategy);
  for (const auto& [option, value] : base.strategy_options) strategy->set_option(option, value);
  SpecimenBuilder builder(*strategy);
  std::vector<AngleRun> runs;
  for (double angle_deg : settings.angles) {
    AngleRun& run = runs.emplace_back();
    run.angle_deg = angle_deg;
    run.case_name = layup_text.empty() ? fmt::format("{:g} deg", angle_deg)
                                       : fmt::format("{} at {:g} deg", layup_text, angle_deg);
    StrengthSettings s = base;
    s.coupon.ply_angle = angle_deg * kDegree;
    for (double& a : s.layup) a += s.coupon.ply_angle;
    spdlog::info("{}: strength at {:g} deg", name, angle_deg);
    try {
      StrengthTest test(s);
      test.on_progress([&](const EventProgress& p) {
        spdlog::info("{:g} deg: {} events, {} broken, peak {:.4g} N, {:.0f} s", angle_deg, p.events,
                     p.broken, p.peak_reaction, p.elapsed_seconds);
      });
      run.result = test.run(builder);
    } catch (const Error& e) {
      run.refused = e.what();
    }
  }
  return runs;
}

std::string refused_row(double angle_deg, const std::string& reason) {
  return markdown_row({fmt::format("{:g}°", angle_deg), fmt::format("refused: {}", reason), "", "",
                       "", "", "", "", "", "", "", ""});
}

// The criteria as curves over 0..90 deg (every degree), the DEM points on them.
std::vector<Curve> strength_curves(const StrengthExperimentSettings& settings,
                                   const Curve& dem_points, const Curve& dem_first) {
  const std::string& name = settings.name;
  const StrengthSettings& base = settings.base;
  std::vector<Curve> curves;
  if (!dem_points.x.empty()) {
    curves.push_back(dem_points);
    curves.push_back(dem_first);
  }
  for (FailureCriterion criterion : all_criteria()) {
    Curve line{criterion_label(criterion), {}, {}, false};
    try {
      for (int degree = 0; degree <= 90; ++degree) {
        std::vector<Ply> plies;
        if (base.layup.empty()) {
          plies.push_back({base.coupon.material, degree * kDegree, base.coupon.thickness});
        } else {
          for (double a : base.layup)
            plies.push_back({base.coupon.material, a + degree * kDegree, base.coupon.thickness});
        }
        line.x.push_back(degree);
        line.y.push_back(first_ply_failure_stress(criterion, plies, base.coupon.material.strength) *
                         kMPaPerPa);
      }
    } catch (const Error& e) {
      spdlog::warn("{}: no {} curve: {}", name, criterion_label(criterion), e.what());
      continue;
    }
    curves.push_back(line);
  }
  return curves;
}

ExperimentOutput report_strength(const StrengthExperimentSettings& settings,
                                 const std::vector<AngleRun>& runs,
                                 const ExperimentContext& context) {
  const std::string& name = settings.name;
  const std::string& layup_text = settings.layup_text;
  const StrengthSettings& base = settings.base;
  const std::string specimen = layup_text.empty() ? "ply" : fmt::format("{} laminate", layup_text);

  ExperimentOutput out;
  out.title = fmt::format("Strength against angle: the {} {} ({})", base.coupon.material.name,
                          specimen, base.strategy);
  std::string table =
      markdown_row({"angle", "DEM strength (MPa)", "first failure (MPa)",
                    "bulk first failure (MPa)", "strain at peak (%)", "broken T / S", "events",
                    "max-stress", "Tsai-Hill", "Tsai-Wu", "Hashin",
                    base.layup.empty() ? "DEM vs Tsai-Wu" : "first failure vs Tsai-Wu (FPF)"}) +
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::string sections;
  Curve dem_points{fmt::format("DEM {} strength", base.strategy), {}, {}, true};
  Curve dem_first{fmt::format("DEM {} first failure", base.strategy), {}, {}, true};
  for (const AngleRun& run : runs) {
    const double angle_deg = run.angle_deg;
    if (!run.result) {
      table += refused_row(angle_deg, run.refused);
      continue;
    }
    const StrengthResult& r = *run.result;
    std::vector<std::string> cells{fmt::format("{:g}°", angle_deg),
                                   mpa_cell(r.strength),
                                   mpa_cell(r.first_failure_stress),
                                   mpa_cell(r.model_first_failure),
                                   fmt::format("{:.4f}", r.strain_at_peak * 100),
                                   fmt::format("{} / {}", r.broken_tension, r.broken_shear),
                                   fmt::format("{}", r.events)};
    double tsai_wu = NAN;
    for (const CriterionStrength& t : r.theory) {
      cells.push_back(t.strength ? mpa_cell(*t.strength) : "–");
      if (t.criterion == FailureCriterion::kTsaiWu && t.strength) tsai_wu = *t.strength;
    }
    cells.push_back(percent_change(criteria_compared_stress(r), tsai_wu));
    table += markdown_row(cells);
    dem_points.x.push_back(angle_deg);
    dem_points.y.push_back(r.strength * kMPaPerPa);
    dem_first.x.push_back(angle_deg);
    dem_first.y.push_back(r.first_failure_stress * kMPaPerPa);
    // A figure or file that cannot be written refuses the angle, as a failed test does.
    try {
      const std::string stem = file_stem(fmt::format("{}_{:g}deg", name, angle_deg));
      const ExperimentOutput one = strength_output(r, context.out_dir, name, run.case_name, stem);
      out.rows.insert(out.rows.end(), one.rows.begin(), one.rows.end());
      out.files.insert(out.files.end(), one.files.begin(), one.files.end());
      sections += one.report_markdown;
    } catch (const Error& e) {
      table += refused_row(angle_deg, e.what());
    }
  }
  const std::vector<Curve> curves = strength_curves(settings, dem_points, dem_first);
  std::string figure_md;
  if (!curves.empty()) {
    PlotAxes axes;
    axes.log_y = true;
    axes.key = "right top";
    const Figure figure = plot_curves(
        curves, context.out_dir, fmt::format("{}_strength", file_stem(name)),
        fmt::format("{} {}: uniaxial strength against angle", base.coupon.material.name, specimen),
        "angle between fibre and load [deg]", "strength sigma_x [MPa]", axes);
    out.files.insert(out.files.end(), figure.files.begin(), figure.files.end());
    figure_md = figure_markdown(figure, "Strength against angle: DEM beside the four criteria");
  }

  std::string& md = out.report_markdown;
  const LaminaStrength& ls = base.coupon.material.strength;
  md += fmt::format(
      "Coupon {:g} × {:g} mm, ply thickness {:g} mm, particle diameter {:g} mm; strategy {}; "
      "lamina strengths XT {:g}, XC {:g}, YT {:g}, YC {:g}, S12 {:g} MPa; {}.\n\n",
      base.coupon.length / kMetresPerMm, base.coupon.width / kMetresPerMm,
      base.coupon.thickness / kMetresPerMm, base.coupon.particle_diameter / kMetresPerMm,
      base.strategy, ls.XT * kMPaPerPa, ls.XC * kMPaPerPa, ls.YT * kMPaPerPa, ls.YC * kMPaPerPa,
      ls.S12 * kMPaPerPa,
      base.effective_weibull_modulus() > 0
          ? fmt::format("Weibull strength scatter m = {:g}, seed {}",
                        base.effective_weibull_modulus(), base.seed)
          : "no strength scatter");
  md += strength_model_note(base) + "\n\n";
  md += fmt::format(
      "## Strength against angle\n\nThe criteria are {}, computed in closed form from the "
      "lamina strengths (core/failure_criteria.hpp; Tsai-Wu with F12* = -1/2). *First failure* "
      "is the coupon's first break, *bulk first failure* the calibrated bulk's under the same "
      "stress (no edges, no scatter): where the coupon's lies below it, a free edge or a grip "
      "broke first (free edges that cut the lattice obliquely are weaker than the bulk: an "
      "artefact of the discrete edge, not of the calibration).\n\n{}\n{}\n",
      base.layup.empty() ? "the ply's off-axis strengths"
                         : "first-ply failure of classical lamination theory",
      table, figure_md);
  md += "## Each angle\n\n" + sections;
  return out;
}

}  // namespace

void register_strength_experiment(ExperimentRegistry& registry) {
  registry.add("strength",
               "tension tests to failure at several angles: strength beside max-stress, "
               "Tsai-Hill, Tsai-Wu, Hashin and Puck",
               parse_strength, run_strength, report_strength);
  registry.set_settings("strength", strength_kind_settings);
}

}  // namespace plydem
