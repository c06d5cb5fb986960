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
#include "experiments/fem/calculix.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/report_text.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMm = 1e-3;
constexpr double kGPa = 1e9;
/// A paper theory value further than this from correct CLT is flagged (ERRATA §1).
constexpr double kPaperTheoryTolerance = 0.01;

double radians(double degrees) {
  return degrees * std::numbers::pi / 180.0;
}

// ---- configs ---------------------------------------------------------------------------------

// The keys every kind reads (coupon, quick overrides, FEM settings, the paper's data).
const std::vector<std::string> kCommonKeys = {"experiment",
                                              "description",
                                              "material",
                                              "coupon.length_mm",
                                              "coupon.width_mm",
                                              "coupon.thickness_mm",
                                              "coupon.diameter_mm",
                                              "coupon.grips",
                                              "quick.length_mm",
                                              "quick.width_mm",
                                              "quick.thickness_mm",
                                              "quick.diameter_mm",
                                              "fem.run",
                                              "fem.element",
                                              "fem.elements_per_ply",
                                              "fem.element_size_mm",
                                              "fem.edge_band_mm",
                                              "fem.length_mm",
                                              "fem.width_mm",
                                              "fem.same_coupon",
                                              "figures.window_mm",
                                              "paper"};

std::vector<std::string> known_keys(std::vector<std::string> extra) {
  extra.insert(extra.end(), kCommonKeys.begin(), kCommonKeys.end());
  return extra;
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
  s.mesh.element_size = c.number("fem.element_size_mm", 0) * kMm;
  s.edge_band = c.number("fem.edge_band_mm", default_edge_band / kMm) * kMm;
  s.loading.grips = grips_from_config(c);
  s.validate();
  return s;
}

// ---- values and tables -----------------------------------------------------------------------

// One line of a constants table; NaN = not available.
struct Values {
  double Ex = kNaN, Ey = kNaN, nu_xy = kNaN, nu_yx = kNaN, Gxy = kNaN, coupling = kNaN;
};

Values values_of(const InPlaneConstants& k, bool with_gxy = true) {
  return {k.Ex, k.Ey, k.nu_xy, k.nu_yx, with_gxy && k.Gxy > 0 ? k.Gxy : kNaN, k.shear_coupling_x};
}

// The paper's values under `key` (an inline table with E1, E2, nu12, nu21 [GPa]; missing entries
// are NaN). nullopt when the config has no such key.
std::optional<Values> paper_values(const ExperimentConfig& c, const std::string& key) {
  if (!c.contains(key)) return std::nullopt;
  Values v;
  v.Ex = c.number(key + ".E1", kNaN) * kGPa;
  v.Ey = c.number(key + ".E2", kNaN) * kGPa;
  v.nu_xy = c.number(key + ".nu12", kNaN);
  v.nu_yx = c.number(key + ".nu21", kNaN);
  v.Gxy = c.number(key + ".G12", kNaN) * kGPa;
  return v;
}

bool off_by(double value, double reference, double tolerance) {
  return std::isfinite(value) && std::isfinite(reference) &&
         std::abs(value / reference - 1.0) > tolerance;
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
                           bool flag = false) {
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
                        const std::vector<std::string>& ply_labels = {}) {
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
  return c.number("figures.window_mm", std::min(coupon.length / kMm, 2.0)) * kMm;
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

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string degrees_label(double degrees) {
  return fmt::format("{:g} deg", degrees);
}

// ---- Table 2: one lamina, every strategy ------------------------------------------------------

class LaminaStrategiesExperiment : public Experiment {
 public:
  ExperimentOutput run(const ExperimentConfig& c, const ExperimentContext& context) const override {
    c.require_known_keys(
        known_keys({"strategies", "angle_deg", "explicit.cycles", "explicit.quick_cycles",
                    "explicit.tolerance", "explicit.ramp_cycles", "explicit.load_stages",
                    "explicit.max_cycles", "explicit.time_limit_s", "explicit.backend"}));
    const std::string name = c.name();
    const bool quick = context.quick;
    const CouponSpec coupon = coupon_from_config(c, quick);
    const double angle_deg = c.number("angle_deg", 0);
    const std::vector<std::string> strategies =
        c.strings("strategies", {"lattice", "hcp", "hex2d", "square"});
    const long paper_cycles = c.integer("explicit.cycles", 200000);
    const long probe_cycles = std::min(c.integer("explicit.quick_cycles", 500), paper_cycles);
    const double time_limit = c.number("explicit.time_limit_s", 900);
    if (probe_cycles <= 0 || paper_cycles <= 0) {
      throw Error(fmt::format("{}: explicit.cycles and explicit.quick_cycles must be positive",
                              c.path().string()));
    }
    TensionSettings base;
    base.force = context.force;
    base.coupon = coupon;
    base.coupon.ply_angle = radians(angle_deg);
    base.grips = grips_from_config(c);
    base.solver = TensionSolver::kStatic;
    // Where the explicit runs' cycles run: cpu or cuda (solvers/device_backend.hpp).
    base.explicit_settings.backend = parse_backend(c.string("explicit.backend", "cpu"));
    const Values clt = values_of(in_plane_constants(
        rotate_reduced_stiffness(reduced_stiffness(coupon.material), base.coupon.ply_angle)));

    ExperimentOutput out;
    out.title = fmt::format("Table 2: the {:g}° {} lamina with every strategy", angle_deg,
                            coupon.material.name);
    std::string moduli = constants_header();
    moduli += constants_line("CLT (correct, computed)", clt, clt);
    add_rows(out.rows, name, "lamina", "clt", clt);
    if (const auto experiment = paper_values(c, "paper.experiment")) {
      moduli += constants_line("experiment (WWFE-II, paper Table 2)", *experiment, clt);
      add_rows(out.rows, name, "lamina", "experiment", *experiment);
    }
    std::string times =
        markdown_row({"strategy", "particles", "bonds", "static test (s)",
                      fmt::format("{} explicit cycles (s)", paper_cycles),
                      "quasi-static explicit (s)", "quasi-static cycles", "paper time (min)"});
    times += "|---|---|---|---|---|---|---|---|\n";
    std::string explicit_moduli;
    std::string figures;
    std::vector<Curve> curves;
    double max_strain = base.target_strain;

    for (const std::string& strategy_name : strategies) {
      const std::optional<Values> paper =
          paper_values(c, fmt::format("paper.dem.{}", strategy_name));
      const double paper_minutes = c.number(fmt::format("paper.minutes.{}", strategy_name), kNaN);
      auto paper_line = [&] {
        if (!paper) return;
        moduli += constants_line(fmt::format("paper DEM, {}", strategy_name), *paper, clt);
        add_rows(out.rows, name, strategy_name, "paper dem", *paper);
      };
      if (std::isfinite(paper_minutes)) {
        out.rows.push_back(
            {name, strategy_name, "computing time", "paper dem", paper_minutes, "min"});
      }
      const std::string paper_time = number_cell(paper_minutes, "{:g}", 1);
      if (!default_registry().contains(strategy_name)) {
        moduli += message_line(fmt::format("DEM {}", strategy_name), "not registered");
        paper_line();
        times += markdown_row({strategy_name, "not registered", "", "", "", "", "", paper_time});
        continue;
      }
      spdlog::info("{}: strategy {}", name, strategy_name);
      try {
        TensionSettings s = base;
        s.strategy = strategy_name;
        const TensionResult r = TensionTest(s).run();
        const Values dem = values_of(r.dem);
        moduli += constants_line(fmt::format("DEM {} (static)", strategy_name), dem, clt);
        paper_line();
        add_rows(out.rows, name, strategy_name, fmt::format("dem {}", strategy_name), dem);
        const double static_seconds = r.along_x.wall_seconds + r.along_y.wall_seconds;
        out.rows.push_back({name, strategy_name, "particles", fmt::format("dem {}", strategy_name),
                            static_cast<double>(r.along_x.particles), "1"});
        out.rows.push_back({name, strategy_name, "bonds", fmt::format("dem {}", strategy_name),
                            static_cast<double>(r.along_x.bonds), "1"});
        out.rows.push_back({name, strategy_name, "static tension test time (both pulls)",
                            fmt::format("dem {}", strategy_name), static_seconds, "s"});
        curves.push_back(pull_curve(fmt::format("{} static, along x", strategy_name), r.along_x));

        // The paper's fixed-cycle explicit run, one coupon along x. A probe of quick_cycles
        // first: a quick run, or a full one whose extrapolated time exceeds
        // explicit.time_limit_s, reports the extrapolation (building the coupon, timed on its
        // own, counted once) instead of running every cycle.
        // The explicit runs pull the static test's coupon along x again (no new build).
        const Specimen& coupon_x = *r.coupon_x;
        TensionSettings e = s;
        e.solver = TensionSolver::kExplicit;
        e.fixed_cycles = probe_cycles;
        PullResult fixed = TensionTest(e).pull(coupon_x, e.coupon.ply_angle);
        const double build_seconds = fixed.build_seconds;
        const double extrapolated = build_seconds + (fixed.wall_seconds - build_seconds) *
                                                        static_cast<double>(paper_cycles) /
                                                        static_cast<double>(probe_cycles);
        long run_cycles = probe_cycles;
        if (!quick && probe_cycles < paper_cycles && extrapolated <= time_limit) {
          e.fixed_cycles = paper_cycles;
          fixed = TensionTest(e).pull(coupon_x, e.coupon.ply_angle);
          run_cycles = paper_cycles;
        }
        const double fixed_seconds = run_cycles == paper_cycles ? fixed.wall_seconds : extrapolated;
        const std::string fixed_source =
            run_cycles == paper_cycles
                ? fmt::format("dem {}", strategy_name)
                : fmt::format("dem {} extrapolated from {} cycles", strategy_name, run_cycles);
        out.rows.push_back({name, strategy_name,
                            fmt::format("time for {} explicit cycles", paper_cycles), fixed_source,
                            fixed_seconds, "s"});
        if (run_cycles == paper_cycles) {
          explicit_moduli += markdown_row(
              {strategy_name, number_cell(fixed.modulus, "{:.3f}", 1e-9),
               percent_change(fixed.modulus, clt.Ex), number_cell(fixed.poisson, "{:.4f}", 1),
               percent_change(fixed.poisson, clt.nu_xy), fmt::format("{:.3g}", fixed.final_ratio),
               fmt::format("{:.3g}", fixed.loading_transits)});
          out.rows.push_back({name, strategy_name, "Ex (fixed cycles)",
                              fmt::format("dem {} explicit", strategy_name), fixed.modulus * 1e-9,
                              "GPa"});
          Curve history = pull_curve(
              fmt::format("{} explicit, {} cycles (second half)", strategy_name, run_cycles),
              fixed);
          history.points = true;
          curves.push_back(history);
          for (double strain : fixed.strain) max_strain = std::max(max_strain, strain);
        }

        // The staged explicit solver to its quasi-static tolerance, same coupon.
        TensionSettings q = s;
        q.solver = TensionSolver::kExplicit;
        q.tolerance = c.number("explicit.tolerance", q.tolerance);
        q.ramp_cycles = c.integer("explicit.ramp_cycles", q.ramp_cycles);
        q.load_stages = static_cast<int>(c.integer("explicit.load_stages", q.load_stages));
        q.max_cycles = c.integer("explicit.max_cycles", q.max_cycles);
        const PullResult staged = TensionTest(q).pull(coupon_x, q.coupon.ply_angle);
        out.rows.push_back({name, strategy_name, "time to quasi-static",
                            fmt::format("dem {} explicit", strategy_name), staged.wall_seconds,
                            "s"});
        out.rows.push_back({name, strategy_name, "cycles to quasi-static",
                            fmt::format("dem {} explicit", strategy_name),
                            static_cast<double>(staged.cycles), "1"});
        times += markdown_row(
            {strategy_name, fmt::format("{}", r.along_x.particles),
             fmt::format("{}", r.along_x.bonds), fmt::format("{:.2f}", static_seconds),
             run_cycles == paper_cycles
                 ? fmt::format("{:.1f}", fixed_seconds)
                 : fmt::format("{:.1f} (extrapolated from {} cycles)", fixed_seconds, run_cycles),
             fmt::format("{:.1f}", staged.wall_seconds), fmt::format("{}", staged.cycles),
             paper_time});

        // The static pull along x: solved at the target strain under the test's grips.
        figures += write_model(
            *r.along_x.model, context.out_dir, file_stem(fmt::format("{}_{}", name, strategy_name)),
            fmt::format("{}: bonds coloured by normal stiffness (plan view, first {:g} mm)",
                        strategy_name, figure_window(c, coupon) / kMm),
            figure_window(c, coupon), out);
      } catch (const Error& e) {
        moduli += message_line(fmt::format("DEM {}", strategy_name),
                               fmt::format("refused: {}", e.what()));
        paper_line();
        times += markdown_row(
            {strategy_name, fmt::format("refused: {}", e.what()), "", "", "", "", "", paper_time});
      }
    }
    curves.push_back(theory_line("CLT Ex", clt.Ex, max_strain));
    const Figure stress_strain =
        plot_curves(curves, context.out_dir, fmt::format("{}_stress_strain", name),
                    "stress-strain along x", "strain eps_x [%]", "stress sigma_x [MPa]");
    out.files.insert(out.files.end(), stress_strain.files.begin(), stress_strain.files.end());

    std::string& md = out.report_markdown;
    md += fmt::format(
        "Coupon {:g} × {:g} mm, ply thickness {:g} mm, particle diameter {:g} mm; {}.\n\n",
        coupon.length / kMm, coupon.width / kMm, coupon.thickness / kMm,
        coupon.particle_diameter / kMm, grips_sentence(base.grips));
    md +=
        "## Table 2: elastic constants\n\n"
        "DEM moduli from the static tension test (one sparse solve per pull; the state an "
        "explicit run converges to), Gxy from the specimen's membrane stiffness. Relative errors "
        "against correct CLT.\n\n";
    md += fmt::format("{}\n", moduli);
    md += fmt::format(
        "## Table 2: computing time\n\n"
        "Wall-clock seconds on this machine. `{} explicit cycles`: the paper's fixed-cycle run "
        "(one coupon pulled along x); a row marked extrapolated ran only the first cycles (a "
        "quick run, or a full run that would take longer than explicit.time_limit_s = {:g} s) and "
        "extrapolates their time linearly, building the coupon counted once. `quasi-static "
        "explicit`: the staged explicit solver (damped "
        "central differences, one coupon along x) until the unbalanced-force ratio is below its "
        "tolerance. `static test`: both pulls with the static solver, building included. The "
        "paper's times are PFC's, on its machine.\n\n",
        paper_cycles, time_limit);
    md += fmt::format("{}\n", times);
    if (!explicit_moduli.empty()) {
      md += fmt::format(
          "## Table 2: moduli from the fixed-cycle explicit run\n\n"
          "Fitted over the second half of the {} cycles. A final unbalanced-force ratio far above "
          "the tolerance, or fewer than {:g} wave transits, means inertia is part of the "
          "measured stress.\n\n",
          paper_cycles, kQuasiStaticTransits);
      md += fmt::format("{}|---|---|---|---|---|---|---|\n{}\n",
                        markdown_row({"strategy", "Ex (GPa)", "rel. err.", "νxy", "rel. err.",
                                      "final unbalanced-force ratio", "loading wave transits"}),
                        explicit_moduli);
    }
    md += fmt::format("## Figures\n\n{}\n{}",
                      figure_markdown(stress_strain, "Stress-strain along x"), figures);
    return out;
  }
};

// ---- Table 3: laminae at several angles ---------------------------------------------------------

class LaminaAnglesExperiment : public Experiment {
 public:
  ExperimentOutput run(const ExperimentConfig& c, const ExperimentContext& context) const override {
    c.require_known_keys(known_keys({"strategies", "angles_deg"}));
    const std::string name = c.name();
    const CouponSpec coupon = coupon_from_config(c, context.quick);
    const std::vector<std::string> strategies = c.strings("strategies", {"hex2d", "square"});
    const std::vector<double> angles = c.numbers("angles_deg", {0, 15, 30, 45, 60, 75, 90});
    const GripCondition grips = grips_from_config(c);
    const bool run_fem = c.boolean("fem.run", true);
    const FemSettings fem_settings = fem_settings_from(c, context, 0);
    const CalculixAvailability ccx = calculix_availability(context.calculix);
    const double window = figure_window(c, coupon);

    ExperimentOutput out;
    out.title =
        fmt::format("Table 3: {} laminae at {} angles", coupon.material.name, angles.size());
    std::string tables, figures;
    bool any_flag = false;
    std::map<std::string, std::vector<Curve>> curves;
    for (const double angle_deg : angles) {
      const std::string case_name = degrees_label(angle_deg);
      const std::string paper_key = fmt::format("paper.{:g}", angle_deg);
      const double angle = radians(angle_deg);
      const Values clt = values_of(
          in_plane_constants(rotate_reduced_stiffness(reduced_stiffness(coupon.material), angle)));
      std::string t = fmt::format("### Table 3: {:g}° lamina\n\n", angle_deg) + constants_header() +
                      constants_line("CLT (correct, computed)", clt, clt);
      add_rows(out.rows, name, case_name, "clt", clt);
      for (const std::string& strategy_name : strategies) {
        spdlog::info("{}: {} at {:g} deg", name, strategy_name, angle_deg);
        if (!default_registry().contains(strategy_name)) {
          t += message_line(fmt::format("DEM {}", strategy_name), "not registered");
          continue;
        }
        try {
          TensionSettings s;
          s.force = context.force;
          s.strategy = strategy_name;
          s.coupon = coupon;
          s.coupon.ply_angle = angle;
          s.grips = grips;
          const auto start = std::chrono::steady_clock::now();
          const TensionResult r = TensionTest(s).run();
          const Values dem = values_of(r.dem);
          t += constants_line(fmt::format("DEM {}", strategy_name), dem, clt);
          add_rows(out.rows, name, case_name, fmt::format("dem {}", strategy_name), dem);
          out.rows.push_back({name, case_name, "wall time", fmt::format("dem {}", strategy_name),
                              seconds_since(start), "s"});
          curves[strategy_name].push_back(pull_curve(fmt::format("{:g}°", angle_deg), r.along_x));
          figures += write_model(
              *r.along_x.model, context.out_dir,
              file_stem(fmt::format("{}_{}_{:g}deg", name, strategy_name, angle_deg)),
              fmt::format("{} at {:g}°: bonds coloured by normal stiffness (plan view, first {:g} "
                          "mm)",
                          strategy_name, angle_deg, window / kMm),
              window, out);
        } catch (const Error& e) {
          t += message_line(fmt::format("DEM {}", strategy_name),
                            fmt::format("refused: {}", e.what()));
        }
      }
      // CalculiX: the same coupon as a solid.
      if (!run_fem) {
        t += message_line("CalculiX", "not run (fem.run = false)");
      } else if (!ccx.available) {
        t += message_line("CalculiX", "CalculiX not installed");
      } else {
        FemSpecimen specimen{{Ply{coupon.material, angle, coupon.thickness}},
                             c.number("fem.length_mm", coupon.length / kMm) * kMm,
                             c.number("fem.width_mm", coupon.width / kMm) * kMm};
        const FemTensionResult fem = fem_tension_test(specimen, fem_settings);
        if (!fem.available) {
          t += message_line("CalculiX", fem.message);
        } else {
          const Values v = values_of(fem.fem, false);
          t += constants_line(
              fmt::format("CalculiX ({}, {} + {} elements)", fem_element_name(fem.along_x.element),
                          fem.along_x.elements, fem.along_y.elements),
              v, clt);
          add_rows(out.rows, name, case_name, "calculix", v);
        }
      }
      for (const char* source : {"theory", "fem", "dem"}) {
        if (const auto paper = paper_values(c, fmt::format("{}.{}", paper_key, source))) {
          const bool flag = std::string(source) == "theory";
          t += constants_line(fmt::format("paper {} (Table 3)", source), *paper, clt, flag);
          add_rows(out.rows, name, case_name, fmt::format("paper {}", source), *paper);
          any_flag = any_flag || (flag && (off_by(paper->Ex, clt.Ex, kPaperTheoryTolerance) ||
                                           off_by(paper->Ey, clt.Ey, kPaperTheoryTolerance) ||
                                           off_by(paper->nu_xy, clt.nu_xy, kPaperTheoryTolerance) ||
                                           off_by(paper->nu_yx, clt.nu_yx, kPaperTheoryTolerance)));
        }
      }
      tables += fmt::format("{}\n", t);
    }
    std::string stress_strain;
    for (auto& [strategy_name, list] : curves) {
      const Figure f = plot_curves(
          list, context.out_dir, file_stem(fmt::format("{}_{}_stress_strain", name, strategy_name)),
          fmt::format("{}: stress-strain along x, static solve", strategy_name), "strain eps_x [%]",
          "stress sigma_x [MPa]");
      out.files.insert(out.files.end(), f.files.begin(), f.files.end());
      stress_strain += figure_markdown(f, fmt::format("{}: stress-strain along x at each angle",
                                                      strategy_name)) +
                       "\n";
    }
    std::string& md = out.report_markdown;
    md += fmt::format(
        "Coupon {:g} × {:g} mm, ply thickness {:g} mm, particle diameter {:g} mm; {}. DEM: static "
        "tension tests (Ex, νxy along x; Ey, νyx from the ply turned by −90°), Gxy from the "
        "specimen's membrane stiffness. The paper's columns E1, E2, ν12, ν21 of Table 3 are Ex, "
        "Ey, νxy, νyx here. Relative errors against correct CLT (Q̄ of the ply).\n\n",
        coupon.length / kMm, coupon.width / kMm, coupon.thickness / kMm,
        coupon.particle_diameter / kMm, grips_sentence(grips));
    md += tables;
    if (any_flag) md += fmt::format("{}\n", paper_theory_note());
    md += fmt::format("## Figures\n\n{}{}", stress_strain, figures);
    return out;
  }
};

// ---- Tables 4 and 5: laminates ---------------------------------------------------------------

class LaminateExperiment : public Experiment {
 public:
  ExperimentOutput run(const ExperimentConfig& c, const ExperimentContext& context) const override {
    c.require_known_keys(
        known_keys({"layup", "strategy", "interface.normal", "interface.shear", "table"}));
    const std::string name = c.name();
    const std::string layup_text = c.string("layup", "");
    if (layup_text.empty())
      throw Error(fmt::format("{}: the key 'layup' is missing", c.path().string()));
    const std::string table = c.string("table", "Laminate");
    TensionSettings s;
    s.force = context.force;
    s.strategy = c.string("strategy", "hex2d");
    s.coupon = coupon_from_config(c, context.quick);
    s.layup = parse_layup(layup_text);
    s.interface.normal = c.number("interface.normal", 0);
    s.interface.shear = c.number("interface.shear", 0);
    s.grips = grips_from_config(c);
    const std::string case_name = format_layup(s.layup);
    const LaminateSpec spec{s.coupon, s.layup, s.interface};
    const std::vector<Ply> plies = laminate_plies(spec);
    const Values clt = values_of(laminate_constants(plies));

    ExperimentOutput out;
    out.title = fmt::format("{}: the {} laminate", table, layup_text);
    std::string t = fmt::format("## {}: {} laminate\n\n", table, layup_text) + constants_header() +
                    constants_line("CLT (correct, A matrix)", clt, clt);
    add_rows(out.rows, name, case_name, "clt", clt);

    spdlog::info("{}: DEM {} {}", name, s.strategy, layup_text);
    const auto start = std::chrono::steady_clock::now();
    const TensionResult r = TensionTest(s).run();
    const double dem_seconds = seconds_since(start);
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

    const bool run_fem = c.boolean("fem.run", true);
    const double h = s.coupon.thickness * static_cast<double>(s.layup.size());
    double fem_seconds = 0;
    std::string same_coupon_table;
    if (!run_fem) {
      t += message_line("CalculiX", "not run (fem.run = false)");
    } else if (!calculix_availability(context.calculix).available) {
      t += message_line("CalculiX", "CalculiX not installed");
    } else {
      if (c.boolean("fem.same_coupon", true)) {
        // The DEM's own coupons in CalculiX: free edges and grips are physics both share, so the
        // DEM against it is the particle model's error (CLT is an infinitely wide plate).
        spdlog::info("{}: CalculiX of the same coupon", name);
        FemTwinSettings twin;
        twin.executable = context.calculix;
        twin.mesh.element = fem_settings_from(c, context, 0).mesh.element;
        const FemTensionResult same = fem_twin_tension_test(s, r, twin);
        const Values v = values_of(same.fem, false);
        fem_seconds += same.along_x.wall_seconds + same.along_y.wall_seconds;
        t += constants_line(
            fmt::format("CalculiX, the same {:g} × {:g} mm coupon ({}, {} + {} elements, {} per "
                        "ply)",
                        s.coupon.length / kMm, s.coupon.width / kMm,
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
      if (c.contains("fem.length_mm") || c.contains("fem.width_mm")) {
        spdlog::info("{}: CalculiX of a wide coupon", name);
        // The free-edge zone of a laminate is about one thickness wide: left out of the strain
        // fit.
        FemSpecimen specimen{plies, c.number("fem.length_mm", s.coupon.length / kMm) * kMm,
                             c.number("fem.width_mm", s.coupon.width / kMm) * kMm};
        const FemSettings fem_settings =
            fem_settings_from(c, context, std::min(h, 0.25 * specimen.width));
        const FemTensionResult fem = fem_tension_test(specimen, fem_settings);
        if (!fem.available) {
          t += message_line("CalculiX", fem.message);
        } else {
          fem_seconds += fem.along_x.wall_seconds + fem.along_y.wall_seconds;
          const Values v = values_of(fem.fem, false);
          t +=
              constants_line(fmt::format("CalculiX, a {:g} × {:g} mm coupon ({}, {} + {} elements)",
                                         specimen.length / kMm, specimen.width / kMm,
                                         fem_element_name(fem.along_x.element),
                                         fem.along_x.elements, fem.along_y.elements),
                             v, clt);
          add_rows(out.rows, name, case_name, "calculix", v);
        }
      }
      out.rows.push_back({name, case_name, "wall time", "calculix", fem_seconds, "s"});
    }
    bool flagged = false;
    for (const char* source : {"theory", "fem", "dem"}) {
      if (const auto paper = paper_values(c, fmt::format("paper.{}", source))) {
        const bool flag = std::string(source) == "theory";
        t += constants_line(fmt::format("paper {} ({})", source, table), *paper, clt, flag);
        add_rows(out.rows, name, case_name, fmt::format("paper {}", source), *paper);
        flagged = flagged || (flag && (off_by(paper->Ex, clt.Ex, kPaperTheoryTolerance) ||
                                       off_by(paper->Ey, clt.Ey, kPaperTheoryTolerance) ||
                                       off_by(paper->nu_xy, clt.nu_xy, kPaperTheoryTolerance) ||
                                       off_by(paper->nu_yx, clt.nu_yx, kPaperTheoryTolerance)));
      }
    }
    if (flagged) t += fmt::format("\n{}", paper_theory_note());

    // Figures and VTU: the solved coupon pulled along x.
    std::vector<std::string> ply_labels;
    for (std::size_t k = 0; k < s.layup.size(); ++k) {
      ply_labels.push_back(fmt::format("ply {}: {:g}°", k, s.layup[k] * 180 / std::numbers::pi));
    }
    // The static pull along x: solved at the target strain under the test's grips.
    const Model& solved = *r.along_x.model;
    const double window = figure_window(c, s.coupon);
    std::string figures = write_model(
        solved, context.out_dir, file_stem(name),
        fmt::format(
            "{} {}: bonds coloured by normal stiffness, plies side by side (plan view, first "
            "{:g} mm)",
            layup_text, s.strategy, window / kMm),
        window, out, ply_labels);
    {
      const Particles& p = solved.particles;
      std::vector<double> x, y, ux;
      const int top = p.ply.maxCoeff();
      for (int i = 0; i < p.size(); ++i) {
        if (p.ply(i) != top) continue;
        x.push_back(p.reference_position(i, 0) / kMm);
        y.push_back(p.reference_position(i, 1) / kMm);
        ux.push_back(p.displacement(i, 0) / kMm * 1e3);
      }
      const Figure map = plot_field_map(
          x, y, ux, context.out_dir, fmt::format("{}_ux", file_stem(name)),
          fmt::format("{}: ux of the top ply at {:g}% strain", layup_text, s.target_strain * 100),
          "ux [um]");
      out.files.insert(out.files.end(), map.files.begin(), map.files.end());
      figures += fmt::format("\n{}", figure_markdown(map, "ux of the top ply, DEM static solve"));
    }
    const double max_strain = std::max(r.along_x.strain.back(), r.along_y.strain.back());
    const Figure ss = plot_curves(
        {pull_curve("DEM along x", r.along_x), theory_line("CLT Ex", clt.Ex, max_strain),
         pull_curve("DEM along y", r.along_y), theory_line("CLT Ey", clt.Ey, max_strain)},
        context.out_dir, fmt::format("{}_stress_strain", file_stem(name)),
        fmt::format("{}: stress-strain, static solve", layup_text), "strain [%]", "stress [MPa]");
    out.files.insert(out.files.end(), ss.files.begin(), ss.files.end());

    std::string& md = out.report_markdown;
    md += fmt::format(
        "Layup {}{} (bottom ply first), {} plies of {:g} mm; coupon {:g} × {:g} mm, particle "
        "diameter {:g} mm; {} plies joined by interface bonds of normal stiffness {:.3g} N/m³ and "
        "shear stiffness {:.3g} N/m³ per unit area{}.\n\n",
        layup_text, case_name == layup_text ? "" : fmt::format(" = {}", case_name), s.layup.size(),
        s.coupon.thickness / kMm, s.coupon.length / kMm, s.coupon.width / kMm,
        s.coupon.particle_diameter / kMm, s.strategy,
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
};

}  // namespace

void register_paper_tables_experiment(ExperimentRegistry& registry) {
  registry.add("lamina-strategies",
               "Table 2: one lamina with every strategy: moduli, explicit and static run times",
               [] { return std::make_unique<LaminaStrategiesExperiment>(); });
  registry.add("lamina-angles",
               "Table 3: laminae at several angles beside CLT, CalculiX and the paper",
               [] { return std::make_unique<LaminaAnglesExperiment>(); });
  registry.add("laminate",
               "Tables 4 and 5: a laminate beside CLT (A matrix), CalculiX and the paper",
               [] { return std::make_unique<LaminateExperiment>(); });
}

}  // namespace plydem
