#include "experiments/runner/paper_tables.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/stopwatch.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/report_text.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace paper_tables {

double radians(double degrees) {
  return degrees * std::numbers::pi / 180.0;
}

// ---- configs ---------------------------------------------------------------------------------

namespace {

// The keys every kind reads besides the coupon's (coupon_config_keys): FEM settings, figures,
// the paper's data.
const std::vector<std::string> kCommonKeys = {
    "fem.run",           "fem.element",   "fem.elements_per_ply", "fem.element_size_mm",
    "fem.edge_band_mm",  "fem.length_mm", "fem.width_mm",         "fem.same_coupon",
    "figures.window_mm", "paper"};

}  // namespace

std::vector<std::string> known_keys(std::vector<std::string> extra) {
  extra.insert(extra.end(), kCommonKeys.begin(), kCommonKeys.end());
  for (const std::string& key : coupon_config_keys()) extra.push_back(key);
  return extra;
}

KindSettings paper_kind_settings(const SettingsSelection& selection,
                                 std::vector<std::pair<std::string, std::string>> own) {
  const SettingsDescription<TensionSettings>& d = tension_settings_description();
  const std::vector<std::pair<std::string, std::string>> common{
      {"fem.run", "run CalculiX beside the DEM; default true"},
      {"fem.element", "CalculiX's element, C3D8I (default) or C3D20R"},
      {"fem.elements_per_ply", "CalculiX's elements through each ply; default 1"},
      {"fem.element_size_mm", "CalculiX's in-plane element size [mm]; 0 = W / 8"},
      {"fem.edge_band_mm", "CalculiX's gauge nodes this close to a free edge are left out [mm]"},
      {"fem.length_mm", "CalculiX of a wider coupon: its length [mm]"},
      {"fem.width_mm", "CalculiX of a wider coupon: its width [mm]"},
      {"fem.same_coupon", "CalculiX of the DEM's own coupon (laminate); default true"},
      {"figures.window_mm", "how much of the coupon the bond figures show [mm]"},
      {"paper", "the paper's values, cited from its tables"}};
  own.insert(own.end(), common.begin(), common.end());
  return {d.rows(d.defaults(), selection), own};
}

std::string grips_sentence(GripCondition grips) {
  return grips == GripCondition::kFree
             ? "free grips: only the axial displacement is prescribed on the grip particles, so "
               "the ends contract and shear freely (uniaxial stress); CalculiX uses the same end "
               "condition"
             : "clamped grips: the grip particles are also held laterally (no end shear or "
               "contraction); CalculiX uses the same end condition";
}

FemSettings fem_settings_from(const ExperimentConfig& c, const ExperimentContext& context,
                              double default_edge_band) {
  FemSettings s;
  s.executable = context.calculix;
  const std::string element = c.string("fem.element", "C3D8I");
  if (element == "C3D8I")
    s.mesh.element = FemElement::kC3D8I;
  else if (element == "C3D20R")
    s.mesh.element = FemElement::kC3D20R;
  else
    throw Error(fmt::format("{}: fem.element must be C3D8I or C3D20R", c.path().string()));
  s.mesh.elements_per_ply = static_cast<int>(c.integer("fem.elements_per_ply", 1));
  s.mesh.element_size = c.number("fem.element_size_mm", 0) * kMetresPerMm;
  s.edge_band = c.number("fem.edge_band_mm", default_edge_band / kMetresPerMm) * kMetresPerMm;
  s.loading.grips = grips_from_config(c);
  s.validate();
  return s;
}

// ---- values and tables -----------------------------------------------------------------------

Values values_of(const InPlaneConstants& k, bool with_gxy) {
  return {k.Ex, k.Ey, k.nu_xy, k.nu_yx, with_gxy && k.Gxy > 0 ? k.Gxy : kNaN, k.shear_coupling_x};
}

// The paper's values under `key` (an inline table with E1, E2, nu12, nu21 [GPa]; missing entries
// are NaN). nullopt when the config has no such key.
std::optional<Values> paper_values(const ExperimentConfig& c, const std::string& key) {
  if (!c.contains(key)) return std::nullopt;
  Values v;
  v.Ex = c.number(key + ".E1", kNaN) * kPaPerGPa;
  v.Ey = c.number(key + ".E2", kNaN) * kPaPerGPa;
  v.nu_xy = c.number(key + ".nu12", kNaN);
  v.nu_yx = c.number(key + ".nu21", kNaN);
  v.Gxy = c.number(key + ".G12", kNaN) * kPaPerGPa;
  return v;
}

bool off_by(double value, double reference, double tolerance) {
  return std::isfinite(value) && std::isfinite(reference) &&
         std::abs(value / reference - 1.0) > tolerance;
}

bool paper_theory_off(const Values& paper, const Values& clt) {
  return off_by(paper.Ex, clt.Ex, kPaperTheoryTolerance) ||
         off_by(paper.Ey, clt.Ey, kPaperTheoryTolerance) ||
         off_by(paper.nu_xy, clt.nu_xy, kPaperTheoryTolerance) ||
         off_by(paper.nu_yx, clt.nu_yx, kPaperTheoryTolerance);
}

std::string number_cell(double value, const char* format, double scale) {
  if (!std::isfinite(value)) return "–";
  return fmt::format(fmt::runtime(format), value * scale);
}

std::string constants_header() {
  return "| source | Ex (GPa) | rel. err. | Ey (GPa) | rel. err. | νxy | rel. err. | νyx | rel. "
         "err. | Gxy "
         "(GPa) | rel. err. | γxy/εx |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
}

// A table line with relative errors against `clt`; `flag` marks paper theory values that differ
// from correct CLT by more than kPaperTheoryTolerance.
std::string constants_line(const std::string& label, const Values& v, const Values& clt,
                           bool flag) {
  auto cell = [&](double value, double reference, const char* format, double scale) {
    std::string text = number_cell(value, format, scale);
    if (flag && off_by(value, reference, kPaperTheoryTolerance)) text += " ✗";
    return text;
  };
  return fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", label,
                     cell(v.Ex, clt.Ex, "{:.3f}", 1e-9), percent_change(v.Ex, clt.Ex),
                     cell(v.Ey, clt.Ey, "{:.3f}", 1e-9), percent_change(v.Ey, clt.Ey),
                     cell(v.nu_xy, clt.nu_xy, "{:.4f}", 1), percent_change(v.nu_xy, clt.nu_xy),
                     cell(v.nu_yx, clt.nu_yx, "{:.4f}", 1), percent_change(v.nu_yx, clt.nu_yx),
                     cell(v.Gxy, clt.Gxy, "{:.3f}", 1e-9), percent_change(v.Gxy, clt.Gxy),
                     number_cell(v.coupling, "{:+.4f}", 1));
}

std::string message_line(const std::string& label, const std::string& message) {
  return fmt::format("| {} | {} | | | | | | | | | | |\n", label, message);
}

void add_rows(std::vector<ResultRow>& rows, const std::string& experiment,
              const std::string& case_name, const std::string& source, const Values& v) {
  auto add = [&](const char* quantity, double value, const char* unit, double scale) {
    if (std::isfinite(value))
      rows.push_back({experiment, case_name, quantity, source, value * scale, unit});
  };
  add("Ex", v.Ex, "GPa", 1e-9);
  add("Ey", v.Ey, "GPa", 1e-9);
  add("nu_xy", v.nu_xy, "1", 1);
  add("nu_yx", v.nu_yx, "1", 1);
  add("Gxy", v.Gxy, "GPa", 1e-9);
  add("shear coupling gamma_xy/eps_x", v.coupling, "1", 1);
}

std::string paper_theory_note() {
  return "✗: the paper's theory value differs from correct CLT by more than 1%. ERRATA §1: the "
         "paper used orthotropic formulas on Q̄ (A for laminates) and dropped Q̄16, Q̄26: that is "
         "the modulus with shear strain held at zero, not the uniaxial modulus 1/S̄11.\n";
}

// ---- DEM models: solved state, VTU, bond figure ------------------------------------------------

// Writes vtu/STEM.pvd (+ particles and bonds .vtu) and STEM_bonds.png; returns the report lines.
std::string write_model(const Model& model, const fs::path& out_dir, const std::string& stem,
                        const std::string& caption, double window, ExperimentOutput& out,
                        const std::vector<std::string>& ply_labels) {
  fs::create_directories(out_dir / "vtu");
  VtkSeries series((out_dir / "vtu" / fmt::format("{}.pvd", stem)).string());
  series.add_model(0.0, model);
  out.files.push_back(fs::path("vtu") / fmt::format("{}.pvd", stem));
  for (const std::string& file : series.files()) out.files.push_back(fs::path("vtu") / file);
  const Figure figure = plot_bonds_by_stiffness(model, out_dir, fmt::format("{}_bonds", stem),
                                                caption, window, ply_labels);
  out.files.insert(out.files.end(), figure.files.begin(), figure.files.end());
  return figure_markdown(figure, caption);
}

double figure_window(const ExperimentConfig& c, const CouponSpec& coupon) {
  return c.number("figures.window_mm", std::min(coupon.length / kMetresPerMm, 2.0)) * kMetresPerMm;
}

// Static stress-strain points of a pull [%, MPa].
Curve pull_curve(const std::string& label, const PullResult& pull) {
  Curve curve{label, {}, {}, true};
  for (std::size_t i = 0; i < pull.strain.size(); ++i) {
    curve.x.push_back(pull.strain[i] * 100);
    curve.y.push_back(pull.stress[i] * 1e-6);
  }
  return curve;
}

Curve theory_line(const std::string& label, double modulus, double max_strain) {
  return {label, {0.0, max_strain * 100}, {0.0, modulus * max_strain * 1e-6}, false};
}

std::string degrees_label(double degrees) {
  return fmt::format("{:g} deg", degrees);
}

}  // namespace paper_tables
}  // namespace plydem
