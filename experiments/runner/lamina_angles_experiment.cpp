// The kind `lamina-angles` (the paper's Table 3, `plydem run experiments/table3.toml`): laminae at
// the config's angles with each listed strategy beside correct CLT, CalculiX and the paper's rows
// (experiments/runner/paper_tables.hpp).
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <map>
#include <optional>

#include "core/error.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/paper_tables.hpp"
#include "experiments/runner/report_text.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace {

using namespace paper_tables;

// The paper's rows of one angle (theory, FEM, DEM), where the config gives them.
struct PaperRows {
  std::optional<Values> theory, fem, dem;
};

// A `lamina-angles` config's settings.
struct LaminaAnglesSettings {
  std::string name;  ///< the config's, naming rows and files
  CouponSpec coupon;
  std::vector<std::string> strategies;
  std::vector<double> angles;  ///< [deg]
  GripCondition grips = GripCondition::kFree;
  bool force = false;   ///< ExperimentContext::force
  bool run_fem = true;  ///< fem.run
  bool ccx_available = false;
  FemSettings fem_settings;
  double fem_length = 0, fem_width = 0;  ///< the FEM coupon [m], where CalculiX runs
  double window = 0;                     ///< of the bond figures [m]
  std::vector<PaperRows> paper;          ///< per angle
};

LaminaAnglesSettings parse_lamina_angles(const ExperimentConfig& c,
                                         const ExperimentContext& context) {
  c.require_known_keys(known_keys({"strategies", "angles_deg"}));
  LaminaAnglesSettings s;
  s.name = c.name();
  s.force = context.force;
  s.coupon = coupon_from_config(c, context.quick);
  s.strategies = c.strings("strategies", {"hex2d", "square"});
  s.angles = c.numbers("angles_deg", {0, 15, 30, 45, 60, 75, 90});
  s.grips = grips_from_config(c);
  s.run_fem = c.boolean("fem.run", true);
  s.fem_settings = fem_settings_from(c, context, 0);
  s.ccx_available = calculix_availability(context.calculix).available;
  s.window = figure_window(c, s.coupon);
  if (s.run_fem && s.ccx_available) {
    s.fem_length = c.number("fem.length_mm", s.coupon.length / kMetresPerMm) * kMetresPerMm;
    s.fem_width = c.number("fem.width_mm", s.coupon.width / kMetresPerMm) * kMetresPerMm;
  }
  for (const double angle_deg : s.angles) {
    const std::string paper_key = fmt::format("paper.{:g}", angle_deg);
    s.paper.push_back({paper_values(c, paper_key + ".theory"), paper_values(c, paper_key + ".fem"),
                       paper_values(c, paper_key + ".dem")});
  }
  return s;
}

// One strategy's tension test at one angle: its result, or why there is none.
struct StrategyFit {
  std::string strategy;
  bool registered = true;
  std::optional<TensionResult> result;
  double seconds = 0;
  std::string refused;  ///< the error, when a registered strategy has no result
};

struct AngleFits {
  std::vector<StrategyFit> fits;
  std::optional<FemTensionResult> fem;  ///< CalculiX, where it ran
};

std::vector<AngleFits> run_lamina_angles(const LaminaAnglesSettings& settings,
                                         const ExperimentContext&) {
  std::vector<AngleFits> angles;
  for (const double angle_deg : settings.angles) {
    AngleFits& at = angles.emplace_back();
    const double angle = radians(angle_deg);
    for (const std::string& strategy_name : settings.strategies) {
      spdlog::info("{}: {} at {:g} deg", settings.name, strategy_name, angle_deg);
      StrategyFit& fit = at.fits.emplace_back();
      fit.strategy = strategy_name;
      if (!default_registry().contains(strategy_name)) {
        fit.registered = false;
        continue;
      }
      try {
        TensionSettings s;
        s.force = settings.force;
        s.strategy = strategy_name;
        s.coupon = settings.coupon;
        s.coupon.ply_angle = angle;
        s.grips = settings.grips;
        const auto start = std::chrono::steady_clock::now();
        fit.result = TensionTest(s).run();
        fit.seconds = seconds_since(start);
      } catch (const Error& e) {
        fit.refused = e.what();
      }
    }
    // CalculiX: the same coupon as a solid.
    if (settings.run_fem && settings.ccx_available) {
      const FemSpecimen specimen{{Ply{settings.coupon.material, angle, settings.coupon.thickness}},
                                 settings.fem_length,
                                 settings.fem_width};
      at.fem = fem_tension_test(specimen, settings.fem_settings);
    }
  }
  return angles;
}

// One angle's table (CLT, each strategy, CalculiX, the paper) and rows; the strategies' bond
// figures are added to `figures`, their curves to `curves`. `flagged`: a paper theory value
// is off correct CLT.
std::string angle_table(const LaminaAnglesSettings& settings, std::size_t k, const AngleFits& at,
                        const std::filesystem::path& out_dir, ExperimentOutput& out,
                        std::string& figures, std::map<std::string, std::vector<Curve>>& curves,
                        bool& flagged) {
  const std::string& name = settings.name;
  const double angle_deg = settings.angles[k];
  const std::string case_name = degrees_label(angle_deg);
  const Values clt = values_of(in_plane_constants(
      rotate_reduced_stiffness(reduced_stiffness(settings.coupon.material), radians(angle_deg))));
  std::string t = fmt::format("### Table 3: {:g}° lamina\n\n", angle_deg) + constants_header() +
                  constants_line("CLT (correct, computed)", clt, clt);
  add_rows(out.rows, name, case_name, "clt", clt);
  for (const StrategyFit& fit : at.fits) {
    const std::string& strategy_name = fit.strategy;
    if (!fit.registered) {
      t += message_line(fmt::format("DEM {}", strategy_name), "not registered");
      continue;
    }
    const auto refused = [&](const std::string& reason) {
      t += message_line(fmt::format("DEM {}", strategy_name), fmt::format("refused: {}", reason));
    };
    if (!fit.result) {
      refused(fit.refused);
      continue;
    }
    // A bond figure that cannot be written refuses the strategy, as a failed test does.
    try {
      const TensionResult& r = *fit.result;
      const Values dem = values_of(r.dem);
      t += constants_line(fmt::format("DEM {}", strategy_name), dem, clt);
      add_rows(out.rows, name, case_name, fmt::format("dem {}", strategy_name), dem);
      out.rows.push_back(
          {name, case_name, "wall time", fmt::format("dem {}", strategy_name), fit.seconds, "s"});
      curves[strategy_name].push_back(pull_curve(fmt::format("{:g}°", angle_deg), r.along_x));
      figures += write_model(
          *r.along_x.model, out_dir,
          file_stem(fmt::format("{}_{}_{:g}deg", name, strategy_name, angle_deg)),
          fmt::format("{} at {:g}°: bonds coloured by normal stiffness (plan view, first {:g} "
                      "mm)",
                      strategy_name, angle_deg, settings.window / kMetresPerMm),
          settings.window, out);
    } catch (const Error& e) {
      refused(e.what());
    }
  }
  if (!settings.run_fem) {
    t += message_line("CalculiX", "not run (fem.run = false)");
  } else if (!settings.ccx_available) {
    t += message_line("CalculiX", "CalculiX not installed");
  } else if (!at.fem->available) {
    t += message_line("CalculiX", at.fem->message);
  } else {
    const FemTensionResult& fem = *at.fem;
    const Values v = values_of(fem.fem, false);
    t += constants_line(
        fmt::format("CalculiX ({}, {} + {} elements)", fem_element_name(fem.along_x.element),
                    fem.along_x.elements, fem.along_y.elements),
        v, clt);
    add_rows(out.rows, name, case_name, "calculix", v);
  }
  const PaperRows& paper = settings.paper[k];
  const std::pair<const char*, const std::optional<Values>*> sources[] = {
      {"theory", &paper.theory}, {"fem", &paper.fem}, {"dem", &paper.dem}};
  for (const auto& [source, values] : sources) {
    if (!*values) continue;
    const bool flag = std::string(source) == "theory";
    t += constants_line(fmt::format("paper {} (Table 3)", source), **values, clt, flag);
    add_rows(out.rows, name, case_name, fmt::format("paper {}", source), **values);
    flagged = flagged || (flag && paper_theory_off(**values, clt));
  }
  return t;
}

ExperimentOutput report_lamina_angles(const LaminaAnglesSettings& settings,
                                      const std::vector<AngleFits>& angles,
                                      const ExperimentContext& context) {
  const std::string& name = settings.name;
  const CouponSpec& coupon = settings.coupon;
  ExperimentOutput out;
  out.title =
      fmt::format("Table 3: {} laminae at {} angles", coupon.material.name, settings.angles.size());
  std::string tables, figures;
  bool any_flag = false;
  std::map<std::string, std::vector<Curve>> curves;
  for (std::size_t k = 0; k < angles.size(); ++k) {
    tables += fmt::format("{}\n", angle_table(settings, k, angles[k], context.out_dir, out, figures,
                                              curves, any_flag));
  }
  std::string stress_strain;
  for (auto& [strategy_name, list] : curves) {
    const Figure f = plot_curves(
        list, context.out_dir, file_stem(fmt::format("{}_{}_stress_strain", name, strategy_name)),
        fmt::format("{}: stress-strain along x, static solve", strategy_name), "strain eps_x [%]",
        "stress sigma_x [MPa]");
    out.files.insert(out.files.end(), f.files.begin(), f.files.end());
    stress_strain +=
        figure_markdown(f, fmt::format("{}: stress-strain along x at each angle", strategy_name)) +
        "\n";
  }
  std::string& md = out.report_markdown;
  md += fmt::format(
      "Coupon {:g} × {:g} mm, ply thickness {:g} mm, particle diameter {:g} mm; {}. DEM: static "
      "tension tests (Ex, νxy along x; Ey, νyx from the ply turned by −90°), Gxy from the "
      "specimen's membrane stiffness. The paper's columns E1, E2, ν12, ν21 of Table 3 are Ex, "
      "Ey, νxy, νyx here. Relative errors against correct CLT (Q̄ of the ply).\n\n",
      coupon.length / kMetresPerMm, coupon.width / kMetresPerMm, coupon.thickness / kMetresPerMm,
      coupon.particle_diameter / kMetresPerMm, grips_sentence(settings.grips));
  md += tables;
  if (any_flag) md += fmt::format("{}\n", paper_theory_note());
  md += fmt::format("## Figures\n\n{}{}", stress_strain, figures);
  return out;
}

}  // namespace

void register_lamina_angles_experiment(ExperimentRegistry& registry) {
  registry.add("lamina-angles",
               "Table 3: laminae at several angles beside CLT, CalculiX and the paper",
               parse_lamina_angles, run_lamina_angles, report_lamina_angles);
  registry.set_settings("lamina-angles", [] {
    return paper_kind_settings(
        coupon_config_selection(),
        {{"strategies", "the strategies; default [\"hex2d\", \"square\"]"},
         {"angles_deg", "the ply angles [deg]; default [0, 15, 30, 45, 60, 75, 90]"}});
  });
}

}  // namespace plydem
