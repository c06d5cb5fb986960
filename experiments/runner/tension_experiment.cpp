#include "experiments/runner/tension_experiment.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <optional>

#include "core/error.hpp"
#include "core/units.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/runner/settings_config.hpp"

namespace plydem {

SameCouponReference same_coupon_fem(const TensionRun& run, const TensionResult& result) {
  const CalculixAvailability ccx = calculix_availability(run.twin.executable);
  if (!ccx.available) {
    throw Error(fmt::format("--fem: {} (Debian: apt-get install calculix-ccx)", ccx.message));
  }
  FemTwinSettings twin = run.twin;
  twin.executable = ccx.executable;
  spdlog::info("CalculiX of the same coupon (two runs)");
  const FemTensionResult fem = fem_twin_tension_test(run.test, result, twin);
  SameCouponReference reference;
  reference.name = "CalculiX";
  reference.description = fmt::format(
      "{} + {} {} elements, {:g} mm in plane, {} per ply, grips {:g} mm; strains at the DEM's "
      "gauge particles",
      fem.along_x.elements, fem.along_y.elements, fem_element_name(fem.along_x.element),
      fem_twin_element_size(run.test, twin) * kMmPerMetre, twin.mesh.elements_per_ply,
      TensionTest(run.test).grip_length() * kMmPerMetre);
  reference.constants = fem.fem;
  reference.wall_seconds = fem.along_x.wall_seconds + fem.along_y.wall_seconds;
  return reference;
}

namespace {

// A `tension` config's settings: the command's, and the config's name.
struct TensionExperimentSettings {
  std::string name;
  TensionRun run;
};

TensionRun tension_kind_defaults(const ExperimentContext& context) {
  TensionRun run = tension_run_description().defaults();
  run.test.force = context.force;
  run.twin.executable = context.calculix;
  return run;
}

TensionExperimentSettings parse_tension(const ExperimentConfig& c,
                                        const ExperimentContext& context) {
  const SettingsDescription<TensionRun>& d = tension_run_description();
  c.require_known_keys(config_keys(d));
  TensionExperimentSettings s{c.name(), tension_kind_defaults(context)};
  read_config_settings(c, d, {}, context.quick, s.run);
  try {
    s.run.test.validate();
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", c.path().string(), e.what()));
  }
  return s;
}

struct TensionExperimentResults {
  TensionResult result;
  std::optional<SameCouponReference> fem;
};

TensionExperimentResults run_tension(const TensionExperimentSettings& s, const ExperimentContext&) {
  TensionTest test(s.run.test);
  test.on_progress([&](const TensionProgress& p) {
    spdlog::info("{}: {}: {} cycles, unbalanced-force ratio {:.3g}, {:.0f} s", s.name, p.phase,
                 p.cycles, p.ratio, p.elapsed_seconds);
  });
  TensionExperimentResults results;
  results.result = test.run();
  if (s.run.fem) results.fem = same_coupon_fem(s.run, results.result);
  return results;
}

void add_constant_rows(ExperimentOutput& out, const std::string& experiment,
                       const std::string& case_name, const std::string& source,
                       const InPlaneConstants& k, bool with_gxy) {
  out.rows.push_back({experiment, case_name, "Ex", source, k.Ex * kGPaPerPa, "GPa"});
  out.rows.push_back({experiment, case_name, "Ey", source, k.Ey * kGPaPerPa, "GPa"});
  out.rows.push_back({experiment, case_name, "nu_xy", source, k.nu_xy, "1"});
  out.rows.push_back({experiment, case_name, "nu_yx", source, k.nu_yx, "1"});
  if (with_gxy && k.Gxy > 0)
    out.rows.push_back({experiment, case_name, "Gxy", source, k.Gxy * kGPaPerPa, "GPa"});
}

ExperimentOutput report_tension(const TensionExperimentSettings& s,
                                const TensionExperimentResults& results, const ExperimentContext&) {
  const TensionSettings& settings = s.run.test;
  const TensionResult& r = results.result;
  const std::string case_name = settings.layup.empty()
                                    ? fmt::format("{:g} deg", settings.coupon.ply_angle / kDegree)
                                    : format_layup(settings.layup);
  ExperimentOutput out;
  out.title = fmt::format("Tension test: {} ({}, {})", case_name, r.material.name, r.strategy);
  out.report_markdown = fmt::format("```\n{}```\n\n", format_tension_table(r, settings));
  if (results.fem) {
    out.report_markdown +=
        fmt::format("CalculiX of the same coupon: {}.\n\n```\n{}```\n\n", results.fem->description,
                    format_same_coupon_table(r, *results.fem));
  }
  add_constant_rows(out, s.name, case_name, fmt::format("dem {}", r.strategy), r.dem, true);
  add_constant_rows(out, s.name, case_name, "clt", r.theory, true);
  if (results.fem)
    add_constant_rows(out, s.name, case_name, "calculix", results.fem->constants, false);
  out.rows.push_back(
      {s.name, case_name, "wall time", fmt::format("dem {}", r.strategy), r.wall_seconds, "s"});
  return out;
}

KindSettings tension_kind_settings() {
  ExperimentContext context;
  const SettingsDescription<TensionRun>& d = tension_run_description();
  return {d.rows(tension_kind_defaults(context)), {}};
}

}  // namespace

void register_tension_experiment(ExperimentRegistry& registry) {
  registry.add("tension",
               "one tension test as `plydem tension` runs it (its settings as config keys), "
               "beside CLT and CalculiX of the same coupon",
               parse_tension, run_tension, report_tension);
  registry.set_settings("tension", tension_kind_settings);
}

}  // namespace plydem
