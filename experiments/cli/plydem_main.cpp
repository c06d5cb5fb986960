// plydem: particle models of FRP composite laminae, from the command line.
//
// Sample runs:
//   plydem                                   # the paper's 0 deg E-glass/MY750 lamina, Hex2D
//   plydem tension --strategy hex2d --angle 30 --json
//   plydem tension --material my_ply.toml --angle 0 --grips clamped
//   plydem calibrate --strategy hex2d --angle 30 --json
//   plydem strength --angle 30               # tension test to failure beside the criteria
//   plydem strength --layup "[0/90]s" --out results/strength   # report, figures, VTU series
//   plydem strategies                        # registered strategies
//   plydem materials                         # built-in materials
//   plydem run experiments/table4.toml       # the paper's Table 4 into results/table4/
//   plydem run --list                        # the experiment configs
#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/progress.hpp"
#include "experiments/cli/python_plugin.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/output/report.hpp"
#include "experiments/output/strength_report.hpp"
#include "experiments/protocols/coupon.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/run_experiment.hpp"
#include "experiments/runner/strength_experiment.hpp"
#include "solvers/linear_solver.hpp"
#include "strategies/registry.hpp"

namespace {

// What every command that builds a coupon takes: the ply, the coupon, the laminate, the grips.
struct CouponOptions {
  std::string strategy = "hex2d";
  std::string material = "eglass-my750";
  double angle_deg = 0;
  double length_mm = 10, width_mm = 0.83, thickness_mm = 0.2, diameter_mm = 0.05;
  double grip_mm = 0;
  double gauge_fraction = 0.5;
  std::string grips = "free";
  std::string layup;
  double interface_normal = 0, interface_shear = 0;
  bool interface_transverse_shear = false;
  std::string linear_solver = "auto";
  std::string petsc_options;
  std::vector<std::string> strategy_options;
  bool json = false;
  bool raw_edges = false;
  bool force = false;
};

// Checkpoint and restart (README, "Checkpoint and restart"): the flags of `tension --solver
// explicit` and `strength`.
struct CheckpointFlags {
  long every = 0;
  std::string file, restart;
};

void add_checkpoint_options(CLI::App& app, CheckpointFlags& o, const std::string& unit) {
  app.add_option("--checkpoint-every", o.every,
                 "write the run's state to --checkpoint FILE every N " + unit + " (0 = never)")
      ->capture_default_str();
  app.add_option("--checkpoint", o.file,
                 "the checkpoint file --checkpoint-every writes (replaced whole each time)");
  app.add_option("--restart", o.restart,
                 "continue the run from this checkpoint file (same settings) to the result of a "
                 "run that was not stopped");
}

plydem::CheckpointOptions to_checkpoint(const CheckpointFlags& o) {
  plydem::CheckpointOptions c;
  c.every = o.every;
  c.file = o.file;
  c.restart = o.restart;
  c.validate();
  return c;
}

struct TensionOptions : CouponOptions {
  double target_strain = 1e-3;
  int stages = 2;
  long ramp_cycles = 2000;
  long cycles = 0;
  long max_cycles = 5'000'000;
  double tolerance = 1e-5;
  double damping = 0.7;
  double safety = 0.8;
  double grip_velocity_mm_s = 0;
  std::string solver = "static";
  std::string backend = "cpu";  // --backend: where explicit dynamics run
  CheckpointFlags checkpoint;
  bool fem = false;  // CalculiX of the same coupon beside the DEM
  std::string ccx = "ccx";
  double fem_element_mm = 0;
  int fem_elements_per_ply = plydem::FemTwinSettings{}.mesh.elements_per_ply;
  int fem_threads = 1;
};

struct StrengthCommandOptions : CouponOptions {
  StrengthCommandOptions() {
    strategy = plydem::StrengthSettings{}.strategy;
    grips = "uniform";
  }
  std::string method = "events";
  double weibull_modulus = 0;
  std::uint64_t seed = 1;
  CLI::Option* weibull_option = nullptr;  // given or not (not given: the material's modulus)
  CLI::Option* seed_option = nullptr;
  double interface_strength_normal = 0, interface_strength_shear = 0;
  double interface_GIc = 0, interface_GIIc = 0;
  double interface_bk_exponent = plydem::InterfaceStrength{}.bk_exponent;
  double friction = 0;
  bool softening = false;
  std::string edge_strengths = "bulk";
  long max_events = plydem::StrengthSettings{}.events.max_events;
  double stop_fraction = plydem::StrengthSettings{}.events.stop_fraction;
  double tooth_stiffness_ratio = plydem::StrengthSettings{}.events.tooth_stiffness_ratio;
  std::string out;
  CheckpointFlags checkpoint;
};

// Options every command that builds a ply takes: strategy, its options, material, angle.
void add_ply_options(CLI::App& app, CouponOptions& o) {
  app.add_option("--strategy", o.strategy, "packing strategy (see `plydem strategies`)")
      ->capture_default_str();
  app.add_option("--strategy-option", o.strategy_options,
                 "a strategy's own parameter, NAME=VALUE (repeatable; `plydem strategies` lists "
                 "them)");
  app.add_option("--material", o.material,
                 "built-in material name or a TOML file with name, E1, E2, G12, nu12, nu23 (Pa)")
      ->capture_default_str();
  app.add_option("--angle", o.angle_deg, "ply (fibre) angle from the loading axis x [deg]")
      ->capture_default_str();
}

// The coupon a tension-type test pulls: its size, grips, gauge, laminate and interfaces.
void add_coupon_options(CLI::App& app, CouponOptions& o, const std::string& grips_help,
                        const std::vector<std::string>& grips) {
  add_ply_options(app, o);
  app.add_option("--length-mm", o.length_mm, "coupon length along x [mm]")->capture_default_str();
  app.add_option("--width-mm", o.width_mm, "coupon width along y [mm]")->capture_default_str();
  app.add_option("--thickness-mm", o.thickness_mm, "ply thickness delta [mm]")
      ->capture_default_str();
  app.add_option("--diameter-mm", o.diameter_mm, "particle diameter [mm]")->capture_default_str();
  app.add_option("--grip-mm", o.grip_mm, "grip length at each end [mm]; 0 = two diameters")
      ->capture_default_str();
  app.add_option("--gauge-fraction", o.gauge_fraction, "central fraction of the length measured")
      ->capture_default_str();
  app.add_option(
      "--layup", o.layup,
      "a laminate instead of one ply, bottom ply first: [0/90/0], [0/30/45]s, [45/-45]s, "
      "[0/90]2s (--angle then turns the whole laminate)");
  app.add_option("--interface-normal", o.interface_normal,
                 "normal stiffness per unit area of the interface bonds between plies [N/m^3]; 0 = "
                 "10 E2/t (see strategies/laminate.hpp); the paper used 1e14")
      ->capture_default_str();
  app.add_option("--interface-shear", o.interface_shear,
                 "shear stiffness per unit area of the interface bonds between plies [N/m^3]; 0 = "
                 "10 G12/t; the paper used 1e13")
      ->capture_default_str();
  app.add_flag("--interface-transverse-shear", o.interface_transverse_shear,
               "the plies carry the laminate's transverse shear (G13, G23) in their in-plane "
               "bonds, the interface bonds are a stiff penalty (shear default 100 G12/t): "
               "interlaminar load transfer around cracks as in a layerwise plate theory; "
               "single-layer strategies (square, hex2d), static and events solvers only (see "
               "strategies/laminate.hpp)");
  app.add_option("--grips", o.grips, grips_help)
      ->check(CLI::IsMember(grips))
      ->capture_default_str();
  app.add_option("--linear-solver", o.linear_solver,
                 "linear solver of the static solves: auto (by the factor's fill and memory, "
                 "and the MPI ranks; README, Static solves with PETSc), direct (plydem's "
                 "supernodal Cholesky), cholmod (SuiteSparse) or petsc (CG + algebraic multigrid; "
                 "distributed under mpiexec -n N)")
      ->capture_default_str();
  app.add_option("--petsc-options", o.petsc_options,
                 "PETSc options for --linear-solver petsc, e.g. \"-ksp_rtol 1e-10 -pc_type "
                 "hypre\" (they override plydem's defaults: CG, GAMG threshold -1, Chebyshev-"
                 "Jacobi smoothing, rtol 1e-12)");
  app.add_flag("--raw-edges", o.raw_edges,
               "do not complete the boundary cells of free edges (edge bonds keep bulk stiffness)");
  app.add_flag("--json", o.json, "print one JSON object (SI units) instead of the table");
  app.add_flag("--force", o.force,
               "build the coupon even when its memory estimate exceeds the machine's available "
               "memory (without it such a coupon is refused, with the estimate, before building)");
}

// What every command takes: how much it says on stderr.
struct LogOptions {
  bool quiet = false;
  double progress_interval = 2;
};

void add_log_options(CLI::App& app, LogOptions& o) {
  app.add_flag("--quiet", o.quiet,
               "no progress or statistics on stderr (warnings and errors stay)");
  app.add_option("--progress-interval", o.progress_interval,
                 "seconds before a long phase first reports its progress, and between reports")
      ->capture_default_str();
}

// An option given where it would change nothing is refused, with the reason.
void refuse_given(const CLI::App& app, const std::vector<std::string>& names,
                  const std::string& reason) {
  for (const std::string& name : names) {
    if (app.count(name) > 0) {
      // Positional arguments by their name: "the config".
      const std::string what = name.front() == '-' ? name : "the " + name;
      throw plydem::Error(fmt::format("{} does nothing here: {}", what, reason));
    }
  }
}

void refuse_inapplicable(const CLI::App& app, const CouponOptions& o) {
  if (o.layup.empty()) {
    refuse_given(app, {"--interface-normal", "--interface-shear", "--interface-transverse-shear"},
                 "interface bonds join the plies of a laminate, and one ply has no interface "
                 "(give --layup)");
  }
}

void refuse_inapplicable(const CLI::App& app, const TensionOptions& o) {
  refuse_inapplicable(app, static_cast<const CouponOptions&>(o));
  if (o.solver == "static") {
    refuse_given(app,
                 {"--stages", "--ramp-cycles", "--cycles", "--max-cycles", "--tolerance",
                  "--damping", "--safety", "--grip-velocity-mm-s", "--backend"},
                 "it is a setting of explicit dynamics, and the static solver (--solver static, "
                 "the default) solves once at the target strain (add --solver explicit)");
  } else if (o.cycles > 0) {
    refuse_given(app, {"--stages", "--ramp-cycles", "--max-cycles"},
                 "the fixed-cycle mode (--cycles N) moves the grips for exactly N cycles in one "
                 "stage, without relaxing");
  } else if (o.grip_velocity_mm_s > 0) {
    refuse_given(app, {"--ramp-cycles"},
                 "--grip-velocity-mm-s sets the grips' speed, which --ramp-cycles would derive");
  }
  if (!o.fem) {
    refuse_given(app, {"--ccx", "--fem-element-mm", "--fem-elements-per-ply", "--fem-threads"},
                 "it is a setting of the CalculiX run of the same coupon (add --fem)");
  }
}

void refuse_inapplicable(const CLI::App& app, const StrengthCommandOptions& o) {
  refuse_inapplicable(app, static_cast<const CouponOptions&>(o));
  if (o.layup.empty()) {
    refuse_given(app,
                 {"--interface-strength-normal", "--interface-strength-shear", "--interface-GIc",
                  "--interface-GIIc", "--interface-bk-exponent"},
                 "interface strengths and fracture energies need a laminate (--layup): one ply has "
                 "no interface");
  }
  if (!o.softening) {
    refuse_given(app,
                 {"--tooth-stiffness-ratio", "--interface-GIc", "--interface-GIIc",
                  "--interface-bk-exponent"},
                 "it is a setting of softening bonds, and the bonds are brittle (add --softening)");
  }
  if (o.grips != "uniform") {
    refuse_given(app, {"--edge-strengths"},
                 "the edge strengths are made consistent with the bulk under uniform grips only "
                 "(--grips uniform, the default)");
  }
}

// --backend cpu|cuda: where the explicit integrator's kernel runs (solvers/device_backend.hpp).
void add_backend_option(CLI::App& app, std::string& backend, const std::string& needs) {
  app.add_option("--backend", backend,
                 "where explicit dynamics run (" + needs + "): " + plydem::backend_help())
      ->check(CLI::IsMember(plydem::backend_choices()))
      ->capture_default_str();
}

void add_tension_options(CLI::App& app, TensionOptions& o) {
  add_coupon_options(app, o, "free (uniaxial stress) or clamped (ends held laterally)",
                     {"free", "clamped"});
  app.add_option("--target-strain", o.target_strain, "nominal strain at the last load stage")
      ->capture_default_str();
  app.add_option("--stages", o.stages, "load stages (points of the stress-strain fit)")
      ->capture_default_str();
  app.add_option("--ramp-cycles", o.ramp_cycles, "cycles to move the grips through one stage")
      ->capture_default_str();
  app.add_option("--cycles", o.cycles,
                 "fixed-cycle mode: move the grips for exactly N cycles (paper: 200000); 0 = stop "
                 "when quasi-static")
      ->capture_default_str();
  app.add_option("--max-cycles", o.max_cycles, "give up after this many cycles per coupon")
      ->capture_default_str();
  app.add_option("--tolerance", o.tolerance,
                 "quasi-static when mean unbalanced force / mean bond force falls below this")
      ->capture_default_str();
  app.add_option("--damping", o.damping, "PFC local damping coefficient")->capture_default_str();
  app.add_option("--safety", o.safety, "time step as a fraction of the critical time step")
      ->capture_default_str();
  app.add_option("--grip-velocity-mm-s", o.grip_velocity_mm_s,
                 "grip velocity [mm/s]; 0 = derived from --ramp-cycles")
      ->capture_default_str();
  app.add_option("--solver", o.solver,
                 "static (one sparse linear solve) or explicit (damped dynamics to quasi-static)")
      ->check(CLI::IsMember({"explicit", "static"}))
      ->capture_default_str();
  add_checkpoint_options(app, o.checkpoint, "cycles (--solver explicit)");
  app.add_flag("--fem", o.fem,
               "also run CalculiX on the same coupon (plies, size, grips; strains at the DEM's "
               "gauge particles) and show the DEM against it beside CLT");
  app.add_option("--ccx", o.ccx, "the CalculiX executable (--fem)")->capture_default_str();
  app.add_option(
         "--fem-element-mm", o.fem_element_mm,
         "in-plane element size of --fem [mm]; 0 = two particle diameters (at most an eighth of "
         "the width)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--fem-elements-per-ply", o.fem_elements_per_ply,
                 "C3D8I elements through each ply's thickness (--fem)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app.add_option("--fem-threads", o.fem_threads, "threads CalculiX may use (--fem)")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  add_backend_option(app, o.backend, "--solver explicit");
}

void add_strength_options(CLI::App& app, StrengthCommandOptions& o) {
  add_coupon_options(app, o,
                     "uniform (held at the bulk's uniform state under sigma_x: uniform uniaxial "
                     "stress up to the grips), free or clamped (the tension test's rigid grips, "
                     "which break the ply next to them)",
                     {"uniform", "free", "clamped"});
  app.add_option("--method", o.method,
                 "events (quasi-static, one bond at a time: sequentially linear analysis) or "
                 "explicit (damped dynamics with breaking bonds)")
      ->check(CLI::IsMember({"events", "explicit"}))
      ->capture_default_str();
  o.weibull_option = app.add_option(
      "--weibull-modulus", o.weibull_modulus,
      "Weibull modulus m of the bonds' strength scatter; 0 = none; default: the material's");
  o.seed_option = app.add_option("--seed", o.seed,
                                 "random stream of the strength scatter (needs scatter: "
                                 "--weibull-modulus, or a material with weibull_modulus)");
  app.add_option("--interface-strength-normal", o.interface_strength_normal,
                 "tensile strength of the interface bonds between plies [Pa]; 0 = the interfaces "
                 "do not break")
      ->capture_default_str();
  app.add_option("--interface-strength-shear", o.interface_strength_shear,
                 "shear strength (cohesion) of the interface bonds [Pa]")
      ->capture_default_str();
  app.add_option("--interface-GIc", o.interface_GIc,
                 "mode I fracture energy of the interface [J/m^2] (softening bonds)")
      ->capture_default_str();
  app.add_option("--interface-GIIc", o.interface_GIIc,
                 "mode II fracture energy of the interface [J/m^2] (softening bonds; 0 = GIc)")
      ->capture_default_str();
  app.add_option("--interface-bk-exponent", o.interface_bk_exponent,
                 "Benzeggagh-Kenane exponent eta of the interface's mixed-mode fracture energy "
                 "GIc + (GIIc - GIc) B^eta (softening bonds)")
      ->capture_default_str();
  app.add_option("--friction", o.friction,
                 "friction coefficient tan(phi) of the bonds' shear strength c - sigma tan(phi)")
      ->capture_default_str();
  app.add_option("--edge-strengths", o.edge_strengths,
                 "bulk (bonds that the coupon's edges or grips load beyond the relaxed bulk get "
                 "strengths to fail with the bulk: edges of a turned lattice do not set the "
                 "strength) or weighted (strengths from the stiffness weights alone)")
      ->check(CLI::IsMember({"bulk", "weighted"}));
  app.add_flag("--softening", o.softening,
               "linear-softening bonds dissipating the fracture energies G_fibre, G_matrix "
               "(default: brittle)");
  app.add_option("--max-events", o.max_events, "stop after this many events")
      ->capture_default_str();
  app.add_option("--stop-fraction", o.stop_fraction,
                 "the coupon has failed when, after the peak, the stress falls below this "
                 "fraction of the peak")
      ->capture_default_str();
  app.add_option("--tooth-stiffness-ratio", o.tooth_stiffness_ratio,
                 "softening bonds: the fraction of its stiffness a bond keeps at each tooth of its "
                 "saw-tooth")
      ->capture_default_str();
  app.add_option("--out", o.out,
                 "also write report.md, results.csv, the stress-strain and crack-pattern PNGs and "
                 "a VTU series into this folder");
  add_checkpoint_options(app, o.checkpoint, "events");
}

// The strategy named by the options, with its options set (unknown names fail here).
std::unique_ptr<plydem::Strategy> make_strategy(const CouponOptions& o) {
  std::unique_ptr<plydem::Strategy> strategy = plydem::default_registry().create(o.strategy);
  for (const auto& [name, value] :
       plydem::parse_strategy_options(o.strategy_options, "--strategy-option")) {
    strategy->set_option(name, value);
  }
  return strategy;
}

// The coupon part of a test's settings (TensionSettings, StrengthSettings: the same fields).
template <class Settings>
void set_coupon(const CouponOptions& o, Settings& s) {
  constexpr double mm = 1e-3;
  s.strategy = o.strategy;
  s.strategy_options = plydem::parse_strategy_options(o.strategy_options, "--strategy-option");
  plydem::require(std::isfinite(o.angle_deg), "--angle is not a finite number");
  s.coupon.material = plydem::load_material(o.material);
  s.coupon.ply_angle = o.angle_deg * std::numbers::pi / 180.0;
  s.coupon.length = o.length_mm * mm;
  s.coupon.width = o.width_mm * mm;
  s.coupon.thickness = o.thickness_mm * mm;
  s.coupon.particle_diameter = o.diameter_mm * mm;
  s.coupon.complete_boundary_cells = !o.raw_edges;
  if (!o.layup.empty()) {
    s.layup = plydem::parse_layup(o.layup);
    for (double& angle : s.layup) angle += s.coupon.ply_angle;
  }
  s.interface.normal = o.interface_normal;
  s.interface.shear = o.interface_shear;
  s.interface.transverse_shear = o.interface_transverse_shear;
  s.grip_length = o.grip_mm * mm;
  s.gauge_fraction = o.gauge_fraction;
  s.linear_solver = plydem::parse_linear_solver(o.linear_solver);
  if (!o.petsc_options.empty()) plydem::set_petsc_options(o.petsc_options);
  s.force = o.force;
  make_strategy(o);  // unknown strategies and options fail here, before any work
}

plydem::TensionSettings to_settings(const TensionOptions& o) {
  constexpr double mm = 1e-3;
  plydem::TensionSettings s;
  set_coupon(o, s);
  s.grips = o.grips == "clamped" ? plydem::GripCondition::kClamped : plydem::GripCondition::kFree;
  s.target_strain = o.target_strain;
  s.load_stages = o.stages;
  s.ramp_cycles = o.ramp_cycles;
  s.fixed_cycles = o.cycles;
  s.max_cycles = o.max_cycles;
  s.tolerance = o.tolerance;
  s.grip_velocity = o.grip_velocity_mm_s * mm;
  s.solver =
      o.solver == "static" ? plydem::TensionSolver::kStatic : plydem::TensionSolver::kExplicit;
  s.explicit_settings.local_damping = o.damping;
  s.explicit_settings.safety_factor = o.safety;
  s.explicit_settings.backend = plydem::parse_backend(o.backend);
  s.checkpoint = to_checkpoint(o.checkpoint);
  s.validate();  // checkpoints with the static solver fail here, before any work
  return s;
}

plydem::StrengthSettings to_settings(const StrengthCommandOptions& o) {
  plydem::StrengthSettings s;
  set_coupon(o, s);
  s.grips = plydem::parse_strength_grips(o.grips);
  s.method = plydem::parse_strength_method(o.method);
  if (o.weibull_option->count() > 0) s.weibull_modulus = o.weibull_modulus;
  s.seed = o.seed;
  s.interface_strength.normal = o.interface_strength_normal;
  s.interface_strength.shear = o.interface_strength_shear;
  s.interface_strength.GIc = o.interface_GIc;
  s.interface_strength.GIIc = o.interface_GIIc;
  s.interface_strength.bk_exponent = o.interface_bk_exponent;
  s.strength_options.friction_coefficient = o.friction;
  s.strength_options.softening = o.softening;
  s.events.max_events = o.max_events;
  s.events.stop_fraction = o.stop_fraction;
  s.events.tooth_stiffness_ratio = o.tooth_stiffness_ratio;
  s.events.progress_seconds = std::max(1e-9, plydem::progress_interval());
  s.record_snapshots = !o.out.empty();
  s.consistent_edges = o.edge_strengths == "bulk";
  s.checkpoint = to_checkpoint(o.checkpoint);
  s.validate();  // NaN and negative values fail here, before any work
  if (o.seed_option->count() > 0 && !(s.effective_weibull_modulus() > 0)) {
    throw plydem::Error(fmt::format(
        "--seed needs strength scatter: give --weibull-modulus m > 0 (the material {} has no "
        "weibull_modulus)",
        s.coupon.material.name));
  }
  return s;
}

// What the run calibrated and built, on stderr.
void log_build_statistics() {
  const plydem::BuildStatistics work = plydem::build_statistics();
  spdlog::info("{} ply calibration{}, {} coupon build{} (each laminate ply counts as one)",
               work.calibrations, work.calibrations == 1 ? "" : "s", work.builds,
               work.builds == 1 ? "" : "s");
}

// `plydem tension --fem`: CalculiX of the coupons the DEM pulled (experiments/fem/calculix.hpp).
plydem::SameCouponReference same_coupon_fem(const TensionOptions& o,
                                            const plydem::TensionSettings& settings,
                                            const plydem::TensionResult& result) {
  const plydem::CalculixAvailability ccx = plydem::calculix_availability(o.ccx);
  if (!ccx.available) {
    throw plydem::Error(
        fmt::format("--fem: {} (Debian: apt-get install calculix-ccx)", ccx.message));
  }
  plydem::FemTwinSettings twin;
  twin.mesh.element_size = o.fem_element_mm * 1e-3;
  twin.mesh.elements_per_ply = o.fem_elements_per_ply;
  twin.executable = ccx.executable;
  twin.threads = o.fem_threads;
  spdlog::info("CalculiX of the same coupon (two runs)");
  const plydem::FemTensionResult fem = plydem::fem_twin_tension_test(settings, result, twin);
  plydem::SameCouponReference reference;
  reference.name = "CalculiX";
  reference.description = fmt::format(
      "{} + {} {} elements, {:g} mm in plane, {} per ply, grips {:g} mm; strains at the DEM's "
      "gauge particles",
      fem.along_x.elements, fem.along_y.elements, plydem::fem_element_name(fem.along_x.element),
      plydem::fem_twin_element_size(settings, twin) * 1e3, twin.mesh.elements_per_ply,
      plydem::TensionTest(settings).grip_length() * 1e3);
  reference.constants = fem.fem;
  reference.wall_seconds = fem.along_x.wall_seconds + fem.along_y.wall_seconds;
  return reference;
}

int run_tension(const TensionOptions& o) {
  const plydem::TensionSettings settings = to_settings(o);
  const std::string narrow = plydem::narrow_laminate_warning(
      settings.coupon.width, settings.coupon.thickness, settings.layup);
  if (!narrow.empty()) spdlog::warn("warning: {}", narrow);
  plydem::TensionTest test(settings);
  test.on_progress([](const plydem::TensionProgress& p) {
    const std::string left =
        p.seconds_left >= 0 ? fmt::format(", about {:.0f} s left", p.seconds_left) : "";
    spdlog::info("{}: {} cycles, unbalanced-force ratio {:.3g}, {:.0f} s{}", p.phase, p.cycles,
                 p.ratio, p.elapsed_seconds, left);
  });
  plydem::TensionResult result;
  try {
    result = test.run();
  } catch (const plydem::UnreachableStiffness& e) {
    if (o.json)
      std::cout << nlohmann::json{{"refused", plydem::refusal_json(e.refusal())}}.dump(2) << "\n";
    throw;
  }
  log_build_statistics();
  std::optional<plydem::SameCouponReference> fem;
  if (o.fem) fem = same_coupon_fem(o, settings, result);
  if (o.json) {
    nlohmann::json j = plydem::tension_json(result, settings);  // with "warnings"
    if (fem) j["fem"] = plydem::same_coupon_json(result, *fem);
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << plydem::format_tension_table(result, settings);
    if (fem) std::cout << plydem::format_same_coupon_table(result, *fem);
    if (!narrow.empty()) std::cout << "\nwarning: " << narrow << "\n";
  }
  return 0;
}

int run_strength(const StrengthCommandOptions& o, const std::string& command_line) {
  const auto start = std::chrono::steady_clock::now();
  const plydem::StrengthSettings settings = to_settings(o);
  std::filesystem::path out_dir;
  if (!o.out.empty()) {
    // The folder must be writable before the run, not after it.
    out_dir = o.out;
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    plydem::require(!ec && std::filesystem::is_directory(out_dir),
                    fmt::format("cannot create the output folder '{}': {}", o.out,
                                ec ? ec.message() : "not a folder"));
  }
  plydem::StrengthTest test(settings);
  test.on_progress([](const plydem::EventProgress& p) {
    spdlog::info("{} events, {} bonds broken, load factor {:.4g}, peak reaction {:.4g} N, {:.0f} s",
                 p.events, p.broken, p.load_factor, p.peak_reaction, p.elapsed_seconds);
  });
  const plydem::StrengthResult result = test.run();
  log_build_statistics();
  if (o.json) {
    std::cout << plydem::strength_json(result, settings).dump(2) << "\n";
  } else {
    std::cout << plydem::format_strength_table(result, settings);
  }
  if (!out_dir.empty()) {
    const std::string case_name =
        result.layup.empty()
            ? fmt::format("{:g} deg", o.angle_deg)
            : fmt::format("{} at {:g} deg", plydem::format_layup(result.layup), o.angle_deg);
    plydem::ExperimentOutput output =
        plydem::strength_output(result, out_dir, "strength", case_name, "strength");
    output.title =
        fmt::format("Strength: the {} {} ({}, {})", result.material.name,
                    result.layup.empty() ? "ply" : "laminate", case_name, result.strategy);
    output.report_markdown =
        fmt::format("Coupon {:g} × {:g} mm, ply thickness {:g} mm, particle diameter {:g} mm. ",
                    settings.coupon.length * 1e3, settings.coupon.width * 1e3,
                    settings.coupon.thickness * 1e3, settings.coupon.particle_diameter * 1e3) +
        plydem::strength_model_note(settings) + "\n\n" + output.report_markdown;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const plydem::RunReportFiles files =
        plydem::write_run_report(out_dir, output, "strength", "",
                                 fmt::format("command: `{}`", command_line), false, seconds);
    spdlog::info("wrote {} and {} ({} more files) into {}", files.report.filename().string(),
                 files.results.filename().string(), output.files.size(), out_dir.string());
  }
  return 0;
}

int run_calibrate(const TensionOptions& o, bool json) {
  plydem::require(std::isfinite(o.angle_deg), "--angle is not a finite number");
  const plydem::Material material = plydem::load_material(o.material);
  const double angle = o.angle_deg * std::numbers::pi / 180.0;
  const std::unique_ptr<plydem::Strategy> strategy = make_strategy(o);
  // The calibration the coupon of these options gets, as `plydem tension` builds it: for lattice
  // that of the coupon's own packing (Strategy::calibrate_coupon), not of a calibration sample.
  plydem::CouponSpec coupon;
  coupon.material = material;
  coupon.ply_angle = angle;
  coupon.length = o.length_mm * 1e-3;
  coupon.width = o.width_mm * 1e-3;
  coupon.thickness = o.thickness_mm * 1e-3;
  coupon.particle_diameter = o.diameter_mm * 1e-3;
  coupon.validate();
  plydem::Calibration calibration;
  try {
    calibration = strategy->calibrate_coupon(coupon);
  } catch (const plydem::UnreachableStiffness& e) {
    // The refusal's numbers on stdout; its sentence on stderr and exit status 2 as any error.
    if (json)
      std::cout << nlohmann::json{{"refused", plydem::refusal_json(e.refusal())}}.dump(2) << "\n";
    throw;
  }
  if (json) {
    nlohmann::json j = plydem::calibration_json(calibration);
    j["strategy"] = o.strategy;
    j["material"] = material.name;
    j["angle_deg"] = o.angle_deg;
    j["thickness"] = o.thickness_mm * 1e-3;
    j["coupon"] = {{"length", coupon.length},
                   {"width", coupon.width},
                   {"particle_diameter", coupon.particle_diameter}};
    j["units"] = "SI (N/m, N m/rad, Pa)";
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << plydem::format_calibration(calibration, o.strategy, material, angle);
    std::cout << fmt::format(
        "the calibration a {:g} x {:g} mm coupon of {:g} mm particles gets (what `plydem "
        "tension` with these options builds)\n",
        o.length_mm, o.width_mm, o.diameter_mm);
  }
  return 0;
}

// What plydem_command_line's check_only does after parsing: the settings the command would run
// with, and for a test its coupon's estimate (refused as the run would refuse it).
int check_command(const TensionOptions& tension, bool strength_given,
                  const StrengthCommandOptions& strength, bool calibrate_given,
                  const TensionOptions& calibrate, bool run_given, bool run_list,
                  const std::string& run_config) {
  if (calibrate_given) {
    plydem::require(std::isfinite(calibrate.angle_deg), "--angle is not a finite number");
    (void)plydem::load_material(calibrate.material);
    (void)make_strategy(calibrate);
  } else if (strength_given) {
    const plydem::StrengthSettings settings = to_settings(strength);
    const plydem::StrengthTest test(settings);
    plydem::check_resources(test.estimate(*make_strategy(strength)), settings.force, "--force");
  } else if (run_given) {
    if (!run_list && !run_config.empty()) (void)plydem::ExperimentConfig::load(run_config);
  } else {
    const plydem::TensionSettings settings = to_settings(tension);
    const plydem::TensionTest test(settings);
    plydem::check_resources(test.estimate(*make_strategy(tension)), settings.force, "--force");
  }
  return 0;
}

struct CalibrateCommand {
  TensionOptions options;
  bool json = false;
};

CLI::App* add_calibrate_command(CLI::App& app, CalibrateCommand& c) {
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "bond stiffness of each family, lattice orientation, and the stiffness the model has as "
      "simulated beside the target");
  TensionOptions& o = c.options;
  add_ply_options(*calibrate, o);
  calibrate->add_option("--thickness-mm", o.thickness_mm, "ply thickness [mm]")
      ->capture_default_str();
  calibrate
      ->add_option("--length-mm", o.length_mm,
                   "length of the coupon calibrated [mm] (lattice calibrates each coupon's own "
                   "packing; the other strategies do not depend on it)")
      ->capture_default_str();
  calibrate->add_option("--width-mm", o.width_mm, "coupon width [mm] (lattice)")
      ->capture_default_str();
  calibrate->add_option("--diameter-mm", o.diameter_mm, "particle diameter [mm] (lattice)")
      ->capture_default_str();
  calibrate->add_flag("--json", c.json, "print one JSON object (SI units)");
  return calibrate;
}

struct RunCommand {
  plydem::RunOptions options;
  std::string config, out;
  bool list = false;
};

CLI::App* add_run_command(CLI::App& app, RunCommand& c) {
  CLI::App* run = app.add_subcommand(
      "run",
      "run an experiment config (experiments/NAME.toml): report.md, results.csv, figures and VTU "
      "files in the output folder");
  run->add_option("config", c.config, "the experiment's TOML file, e.g. experiments/table4.toml");
  run->add_option("--out", c.out, "output folder; default results/NAME");
  run->add_flag("--quick", c.options.quick,
                "smaller coupons and fewer cycles (seconds instead of minutes)");
  run->add_option("--ccx", c.options.calculix, "the CalculiX executable")->capture_default_str();
  run->add_flag("--list", c.list,
                "list the configs in ./experiments (else the source tree's) with their "
                "descriptions");
  run->add_flag("--force", c.options.force,
                "build coupons even when their memory estimate exceeds the machine's available "
                "memory");
  return run;
}

int print_strategies() {
  const plydem::Registry& registry = plydem::default_registry();
  for (const std::string& name : registry.names()) {
    std::cout << fmt::format("{:<14} {}\n", name, registry.description(name));
    for (const plydem::StrategyOption& option : registry.create(name)->options()) {
      std::cout << fmt::format("{:<14}   --strategy-option {}={:g}: {}\n", "", option.name,
                               option.value, option.description);
    }
  }
  return 0;
}

int print_materials() {
  for (const std::string& name : plydem::builtin_material_names()) {
    const plydem::Material m = plydem::load_material(name);
    std::cout << fmt::format(
        "{:<14} E1 {:g} GPa, E2 {:g} GPa, G12 {:g} GPa, nu12 {:g}, nu23 {:g}, density {:g} "
        "kg/m^3\n",
        m.name, m.E1 * 1e-9, m.E2 * 1e-9, m.G12 * 1e-9, m.nu12, m.nu23, m.density);
  }
  return 0;
}

int run_config_command(RunCommand& c) {
  if (c.list) {
    const std::filesystem::path folder = plydem::default_experiments_folder();
    std::cout << fmt::format("experiment configs in {}:\n", folder.string());
    for (const plydem::ConfigListing& listing : plydem::list_experiment_configs(folder)) {
      std::cout << fmt::format("  {:<10} {}\n", listing.name, listing.description);
    }
    return 0;
  }
  plydem::require(!c.config.empty(),
                  "plydem run needs an experiment config (e.g. experiments/table4.toml) or "
                  "--list");
  c.options.config = c.config;
  c.options.out_dir = c.out;
  const plydem::RunSummary summary = plydem::run_experiment(c.options);
  log_build_statistics();
  std::cout << fmt::format("{} done in {:.1f} s: {} rows in {}, report {}\n",
                           c.options.config.string(), summary.wall_seconds,
                           summary.output.rows.size(), summary.results.string(),
                           summary.report.string());
  return 0;
}

}  // namespace

/// The command line without main(): `check_only` parses, refuses what does not apply, converts
/// the options to the tests' settings and estimates the coupon's memory, and returns there (the
/// fuzz target tests/fuzz/fuzz_command_line.cpp calls it so).
int plydem_command_line(int argc, char** argv, bool check_only) {
  CLI::App app{
      "plydem: particle (DEM and lattice) models of fibre-reinforced composite laminae.\n"
      "With no command it runs the paper's 0 deg E-glass/MY750 lamina with the Hex2D strategy\n"
      "and prints E1, E2, nu12, nu21 beside classical lamination theory."};
  app.require_subcommand(0, 1);
  // Options of the program itself (--plugin) may also stand after the command: the commands
  // (which inherit this) pass them up.
  app.fallthrough();
  // Progress and warnings go to stderr: stdout carries only the table or the JSON object.
  if (!spdlog::get("plydem")) spdlog::set_default_logger(spdlog::stderr_color_mt("plydem"));
  spdlog::set_pattern("[%H:%M:%S] %v");
  LogOptions log_options;
  add_log_options(app, log_options);

  TensionOptions defaults;
  TensionOptions tension_options;
  CLI::App* tension = app.add_subcommand(
      "tension", "virtual uniaxial tension test of one ply: Ex, Ey, nu_xy, nu_yx beside CLT");
  add_tension_options(*tension, tension_options);
  StrengthCommandOptions strength_options;
  CLI::App* strength = app.add_subcommand(
      "strength",
      "tension test to failure: strength, strain at peak, first-failure stress and broken bonds "
      "beside XT, YT, S12 and the max-stress, Tsai-Hill, Tsai-Wu and Hashin criteria");
  add_strength_options(*strength, strength_options);
  CalibrateCommand calibrate_command;
  CLI::App* calibrate = add_calibrate_command(app, calibrate_command);
  TensionOptions& calibrate_options = calibrate_command.options;
  CLI::App* strategies = app.add_subcommand("strategies", "list the registered strategies");
  CLI::App* materials = app.add_subcommand("materials", "list the built-in materials");
  for (CLI::App* command : {tension, strength, calibrate, strategies, materials}) {
    add_log_options(*command, log_options);
  }
  RunCommand run_command;
  CLI::App* run = add_run_command(app, run_command);
  add_log_options(*run, log_options);

  std::vector<std::string> plugins;
  app.add_option("--plugin", plugins,
                 "a Python file run before the command, whose plydem.register_strategy calls add "
                 "strategies for --strategy (repeatable; see README, Python)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  // The command, run after the plug-ins (if any) have registered their strategies.
  const auto command = [&]() -> int {
    plydem::set_progress_interval(log_options.progress_interval);
    spdlog::set_level(!plydem::is_root()  ? spdlog::level::off
                      : log_options.quiet ? spdlog::level::warn
                                          : spdlog::level::info);
    if (*tension) refuse_inapplicable(*tension, tension_options);
    if (*strength) refuse_inapplicable(*strength, strength_options);
    if (*run && run_command.list) {
      refuse_given(*run, {"config", "--out", "--quick", "--ccx", "--force"},
                   "--list only lists the configs");
    }
    if (check_only) {
      return check_command(*tension ? tension_options : defaults, strength->parsed(),
                           strength_options, calibrate->parsed(), calibrate_options, run->parsed(),
                           run_command.list, run_command.config);
    }
    if (*strategies) return print_strategies();
    if (*materials) return print_materials();
    if (*calibrate) return run_calibrate(calibrate_options, calibrate_command.json);
    if (*strength) {
      std::string command_line = "plydem";
      for (int i = 1; i < argc; ++i) command_line += fmt::format(" {}", argv[i]);
      return run_strength(strength_options, command_line);
    }
    if (*run) return run_config_command(run_command);
    return run_tension(*tension ? tension_options : defaults);
  };
  try {
    if (check_only) return command();  // plug-ins are not loaded: nothing runs
    plydem::cli::load_plugins(plugins);
    return plydem::cli::run_with_plugins(command);
  } catch (const plydem::Error& e) {
    std::cerr << "plydem: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "plydem: internal error: " << e.what() << "\n";
    return 3;
  }
}

#ifndef PLYDEM_NO_MAIN
int main(int argc, char** argv) {
  // Under mpiexec -n N every rank runs the command (solvers/linear_solver.hpp, ParallelSession);
  // only rank 0 prints.
  const plydem::ParallelSession session(&argc, &argv);
  if (!plydem::is_root()) {
    std::cout.setstate(std::ios::badbit);
    std::cerr.setstate(std::ios::badbit);
  }
  return plydem_command_line(argc, argv, false);
}
#endif
