// A test plug-in that registers an experiment kind, `plugin_clt`: a ply's Ex from CLT at the
// config's angles, no simulation (ctest: cli_plugin_kind, tests/data/plugin_kind.toml).
#include <fmt/format.h>

#include <numbers>
#include <string>
#include <vector>

#include "core/elasticity.hpp"
#include "core/material.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/plugin.hpp"

namespace {

struct CltSettings {
  plydem::Material material;
  std::vector<double> angles_deg;
};

CltSettings parse_clt(const plydem::ExperimentConfig& config, const plydem::ExperimentContext&) {
  config.require_known_keys({"experiment", "description", "material", "angles_deg"});
  return {plydem::load_material(config.string("material", "eglass-my750")),
          config.numbers("angles_deg", {0, 90})};
}

std::vector<double> run_clt(const CltSettings& s, const plydem::ExperimentContext&) {
  std::vector<double> ex;
  for (const double degrees : s.angles_deg) {
    const Eigen::Matrix3d q_bar = plydem::rotate_reduced_stiffness(
        plydem::reduced_stiffness(s.material), degrees * std::numbers::pi / 180);
    ex.push_back(plydem::in_plane_constants(q_bar).Ex);
  }
  return ex;
}

plydem::ExperimentOutput report_clt(const CltSettings& s, const std::vector<double>& ex,
                                    const plydem::ExperimentContext&) {
  plydem::ExperimentOutput out;
  out.title = "Ex from CLT (a plug-in's kind)";
  for (std::size_t k = 0; k < ex.size(); ++k) {
    const std::string angle = fmt::format("{:g} deg", s.angles_deg[k]);
    out.report_markdown += fmt::format("- {}: Ex {:.3f} GPa\n", angle, ex[k] * 1e-9);
    out.rows.push_back({"plugin_clt", angle, "Ex", "clt", ex[k] * 1e-9, "GPa"});
  }
  return out;
}

void register_clt_kind(plydem::PluginRegistries& registries) {
  registries.experiments.add("plugin_clt", "a ply's Ex from CLT (a test plug-in)", parse_clt,
                             run_clt, report_clt);
}

}  // namespace

PLYDEM_PLUGIN(register_clt_kind)
