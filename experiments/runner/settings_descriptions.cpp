#include "experiments/runner/settings_descriptions.hpp"

#include <fmt/format.h>

#include <map>

#include "core/material.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "solvers/device_backend.hpp"
#include "solvers/linear_solver.hpp"
#include "strategies/laminate.hpp"

namespace plydem {

namespace {

namespace units = setting_units;

// Why a setting of a test is not at an edge.
constexpr char kRunForce[] = "`plydem run --force` (the config's coupons)";
constexpr char kOneRunPerCheckpoint[] =
    "a config may run several tests; a checkpoint holds one run (the command line or Python)";

// ---- the coupon --------------------------------------------------------------------------------

CouponSpec default_coupon() {
  CouponSpec c;
  c.material = load_material("eglass-my750");
  return c;
}

// The coupon's size: edge unit mm, the same key under [quick] in a quick run.
SettingField<CouponSpec>& add_size(SettingsDescription<CouponSpec>& d, const std::string& name,
                                   const std::string& flag, const std::string& key,
                                   const std::string& python, const std::string& help,
                                   double CouponSpec::*member) {
  return d
      .number(
          name, [member](auto& s) -> auto& { return s.*member; })
      .with_flag(flag)
      .with_key("coupon." + key)
      .with_quick_key("quick." + key)
      .with_python(python)
      .with_unit(units::millimetres())
      .validated("> 0 (CouponSpec::validate)")
      .with_help(help);
}

SettingsDescription<CouponSpec> make_coupon_settings() {
  SettingsDescription<CouponSpec> d(default_coupon);
  d.add(
       "material", SettingType::kText,
       [](const CouponSpec& s) -> SettingValue { return s.material.name; },
       [](CouponSpec& s, const SettingValue& v, const std::string&) {
         s.material = load_material(std::get<std::string>(v));
       })
      .with_flag("--material")
      .with_key("material")
      .with_python("material")
      .python_as("Material (plydem.load_material(name) or plydem.Material(...))")
      .with_help("built-in material name or a TOML file with name, E1, E2, G12, nu12, nu23 (Pa)");
  d.number(
       "angle", [](auto& s) -> auto& { return s.ply_angle; })
      .with_flag("--angle")
      .with_key("angle_deg")
      .with_python("ply_angle")
      .with_unit(units::degrees())
      .must_be_finite()
      .with_help("ply (fibre) angle from the loading axis x");
  add_size(d, "length", "--length-mm", "length_mm", "length", "coupon length along x",
           &CouponSpec::length)
      .note("calibrate",
            "lattice calibrates each coupon's own packing; the other strategies do not depend on "
            "it");
  add_size(d, "width", "--width-mm", "width_mm", "width", "coupon width along y",
           &CouponSpec::width)
      .note("calibrate", "lattice");
  add_size(d, "thickness", "--thickness-mm", "thickness_mm", "thickness", "ply thickness delta",
           &CouponSpec::thickness);
  add_size(d, "diameter", "--diameter-mm", "diameter_mm", "particle_diameter", "particle diameter",
           &CouponSpec::particle_diameter)
      .note("calibrate", "lattice");
  d.boolean(
       "raw_edges", [](auto& s) -> auto& { return s.complete_boundary_cells; })
      .with_flag("--raw-edges")
      .with_key("coupon.raw_edges")
      .with_python("complete_boundary_cells")
      .inverted_at_edges()
      .with_help(
          "do not complete the boundary cells of free edges (edge bonds keep bulk stiffness); "
          "Python's complete_boundary_cells is its negation");
  return d;
}

// ---- what the tension and strength tests share -------------------------------------------------

// The strategy and its options (every test struct has both members).
template <class S>
void add_strategy(SettingsDescription<S>& d) {
  d.text(
       "strategy", [](auto& s) -> auto& { return s.strategy; })
      .with_flag("--strategy")
      .with_key("strategy")
      .with_python("strategy")
      .with_help("packing strategy (see `plydem strategies`)");
  d.add(
       "strategy_options", SettingType::kTexts,
       [](const S& s) -> SettingValue {
         std::vector<std::string> entries;
         for (const auto& [name, value] : s.strategy_options)
           entries.push_back(fmt::format("{}={:g}", name, value));
         return entries;
       },
       [](S& s, const SettingValue& v, const std::string& what) {
         s.strategy_options = parse_strategy_options(std::get<std::vector<std::string>>(v), what);
       })
      .with_flag("--strategy-option")
      .with_key("strategy_options")
      .with_python("strategy_options")
      .python_as("list of (name, value), applied in order before calibration")
      .with_help(
          "a strategy's own parameter, NAME=VALUE (repeatable; `plydem strategies` lists them)");
}

constexpr char kNeedsLaminate[] =
    "interface bonds join the plies of a laminate, and one ply has no interface (give {layup})";

// The laminate (its layup turned by the ply angle, as --angle turns it) and its interfaces'
// stiffness.
template <class S>
void add_laminate(SettingsDescription<S>& d) {
  d.add(
       "layup", SettingType::kText,
       [](const S& s) -> SettingValue { return s.layup.empty() ? "" : format_layup(s.layup); },
       [](S& s, const SettingValue& v, const std::string&) {
         const std::string& text = std::get<std::string>(v);
         s.layup = text.empty() ? std::vector<double>{} : parse_layup(text);
         for (double& angle : s.layup) angle += s.coupon.ply_angle;
       })
      .with_flag("--layup")
      .with_key("layup")
      .with_python("layup")
      .python_as("list of ply angles [rad], bottom to top; empty = one ply")
      .with_help(
          "a laminate instead of one ply, bottom ply first: [0/90/0], [0/30/45]s, [45/-45]s, "
          "[0/90]2s ({angle} then turns the whole laminate)");
  const auto laminate = [](const S& s) { return !s.layup.empty(); };
  d.number(
       "interface_normal", [](auto& s) -> auto& { return s.interface.normal; })
      .with_flag("--interface-normal")
      .with_key("interface.normal")
      .with_python("interface_normal")
      .with_unit(units::same("N/m^3"))
      .with_help(
          "normal stiffness per unit area of the interface bonds between plies {unit}; 0 = 10 E2/t "
          "(see strategies/laminate.hpp); the paper used 1e14")
      .only_if(laminate, kNeedsLaminate);
  d.number(
       "interface_shear", [](auto& s) -> auto& { return s.interface.shear; })
      .with_flag("--interface-shear")
      .with_key("interface.shear")
      .with_python("interface_shear")
      .with_unit(units::same("N/m^3"))
      .with_help(
          "shear stiffness per unit area of the interface bonds between plies {unit}; 0 = 10 G12/t "
          "(100 G12/t with {interface_transverse_shear}); the paper used 1e13")
      .only_if(laminate, kNeedsLaminate);
  d.boolean(
       "interface_transverse_shear", [](auto& s) -> auto& { return s.interface.transverse_shear; })
      .with_flag("--interface-transverse-shear")
      .with_key("interface.transverse_shear")
      .with_python("interface_transverse_shear")
      .with_help(
          "the plies carry the laminate's transverse shear (G13, G23) in their in-plane bonds, the "
          "interface bonds are a stiff penalty (shear default 100 G12/t): interlaminar load "
          "transfer around cracks as in a layerwise plate theory; single-layer strategies (square, "
          "hex2d), static and events solvers only (see strategies/laminate.hpp)")
      .only_if(laminate, kNeedsLaminate);
}

// The grips' length, the gauge section and its edge band.
template <class S>
void add_gauge(SettingsDescription<S>& d) {
  d.number(
       "grip_length", [](auto& s) -> auto& { return s.grip_length; })
      .with_flag("--grip-mm")
      .with_key("coupon.grip_mm")
      .with_quick_key("quick.grip_mm")
      .with_python("grip_length")
      .with_unit(units::millimetres())
      .with_help(std::is_same_v<S, StrengthSettings>
                     ? "grip length at each end {unit}; 0 = two diameters (at the material point, "
                       "--failure-criterion other than bond: the edge strips' depth plus the "
                       "longest bond, so that the strips' corners lie in the grips)"
                     : "grip length at each end {unit}; 0 = two diameters");
  d.number(
       "gauge_fraction", [](auto& s) -> auto& { return s.gauge_fraction; })
      .with_flag("--gauge-fraction")
      .with_key("coupon.gauge_fraction")
      .with_python("gauge_fraction")
      .validated("(0, 1)")
      .with_help("central fraction of the length measured");
  d.number(
       "edge_band_diameters", [](auto& s) -> auto& { return s.edge_band_diameters; })
      .with_flag("--edge-band-diameters")
      .with_key("coupon.edge_band_diameters")
      .with_python("edge_band_diameters")
      .with_help(
          "gauge particles closer than this many particle diameters to a free edge (at most a "
          "quarter of the width) are left out of the strain fit");
}

std::vector<std::string> linear_solver_names() {
  return {"auto", "direct", "cholmod", "petsc"};
}

// The static solves' linear solver and --force.
template <class S>
void add_solves(SettingsDescription<S>& d) {
  d.add(
       "linear_solver", SettingType::kText,
       [](const S& s) -> SettingValue { return std::string(linear_solver_name(s.linear_solver)); },
       [](S& s, const SettingValue& v, const std::string&) {
         s.linear_solver = parse_linear_solver(std::get<std::string>(v));
       })
      .with_flag("--linear-solver")
      .with_key("linear_solver")
      .with_python("linear_solver")
      .with_choices(linear_solver_names)
      .parsed_by_setter(true)
      .with_help(
          "linear solver of the static solves: auto (by the factor's fill and memory, and the MPI "
          "ranks; bench/README.md, \"Static solves with PETSc\"), direct (plydem's supernodal "
          "Cholesky), "
          "cholmod "
          "(SuiteSparse) or petsc (CG + algebraic multigrid; distributed under mpiexec -n N; a "
          "build with PETSc)");
  d.boolean(
       "force", [](auto& s) -> auto& { return s.force; })
      .with_flag("--force")
      .without_key(kRunForce)
      .with_python("force")
      .with_help(
          "build the coupon even when its memory estimate exceeds the machine's available memory "
          "(without it such a coupon is refused, with the estimate, before building)");
}

// Checkpoint and restart (docs/restart.md, "Checkpoint and restart"), every `unit` of the run.
template <class S>
void add_checkpoint(SettingsDescription<S>& d, const std::string& unit) {
  d.integer(
       "checkpoint_every", [](auto& s) -> auto& { return s.checkpoint.every; })
      .with_flag("--checkpoint-every")
      .without_key(kOneRunPerCheckpoint)
      .with_python("checkpoint_every")
      .at_least(0)
      .with_help(
          fmt::format("write the run's state to {{checkpoint}} every N {} (0 = never)", unit));
  d.text(
       "checkpoint", [](auto& s) -> auto& { return s.checkpoint.file; })
      .with_flag("--checkpoint")
      .without_key(kOneRunPerCheckpoint)
      .with_python("checkpoint")
      .hide_default()
      .with_help("the checkpoint file {checkpoint_every} writes (replaced whole each time)");
  d.text(
       "restart", [](auto& s) -> auto& { return s.checkpoint.restart; })
      .with_flag("--restart")
      .without_key(kOneRunPerCheckpoint)
      .with_python("restart")
      .hide_default()
      .with_help(
          "continue the run from this checkpoint file (same settings) to the result of a run that "
          "was not stopped");
}

// ---- the tension test --------------------------------------------------------------------------

TensionSettings default_tension() {
  TensionSettings s;
  s.coupon.material = load_material("eglass-my750");
  return s;
}

constexpr char kExplicitOnly[] =
    "it is a setting of explicit dynamics, and the static solver ({solver=static}, the default) "
    "solves once at the target strain (add {solver=explicit})";
constexpr char kNotFixedCycles[] =
    "the fixed-cycle mode ({fixed_cycles} N) moves the grips for exactly N cycles in one stage, "
    "without relaxing";

bool explicit_solver(const TensionSettings& s) {
  return s.solver == TensionSolver::kExplicit;
}
bool staged(const TensionSettings& s) {
  return s.fixed_cycles == 0;
}

// The explicit integrator's damping and backend, as the tension and strength tests name them;
// `applies` says where they do something (`why` where they do not).
template <class S>
void add_explicit_dynamics(SettingsDescription<S>& d, const std::string& backend_help,
                           bool (*applies)(const S&), const char* why) {
  d.number(
       "damping", [](auto& s) -> auto& { return s.explicit_settings.local_damping; })
      .with_flag("--damping")
      .with_key("explicit.damping")
      .with_python("damping")
      .with_help("PFC local damping coefficient")
      .only_if(applies, why);
  d.add(
       "backend", SettingType::kText,
       [](const S& s) -> SettingValue {
         return std::string(to_string(s.explicit_settings.backend));
       },
       [](S& s, const SettingValue& v, const std::string&) {
         s.explicit_settings.backend = parse_backend_choice(std::get<std::string>(v));
       })
      .with_flag("--backend")
      .with_key("explicit.backend")
      .with_python("backend")
      .with_choices(backend_choices)
      .parsed_by_setter(false)
      .with_help(backend_help + backend_choices_help(false))
      .only_if(applies, why);
}

// The tension test's loading: strain, stages, the explicit solver's cycles and tolerance.
void add_tension_loading(SettingsDescription<TensionSettings>& d) {
  d.number(
       "target_strain", [](auto& s) -> auto& { return s.target_strain; })
      .with_flag("--target-strain")
      .with_key("target_strain")
      .with_python("target_strain")
      .with_help("nominal strain at the last load stage");
  d.integer(
       "load_stages", [](auto& s) -> auto& { return s.load_stages; })
      .with_flag("--stages")
      .with_key("explicit.load_stages")
      .with_python("load_stages")
      .with_help("load stages (points of the stress-strain fit)")
      .only_if(explicit_solver, kExplicitOnly)
      .only_if(staged, kNotFixedCycles);
  d.integer(
       "ramp_cycles", [](auto& s) -> auto& { return s.ramp_cycles; })
      .with_flag("--ramp-cycles")
      .with_key("explicit.ramp_cycles")
      .with_python("ramp_cycles")
      .with_help("cycles to move the grips through one stage")
      .only_if(explicit_solver, kExplicitOnly)
      .only_if(staged, kNotFixedCycles)
      .only_if([](const TensionSettings& s) { return !(s.grip_velocity > 0); },
               "{grip_velocity} sets the grips' speed, which {ramp_cycles} would derive");
  d.integer(
       "fixed_cycles", [](auto& s) -> auto& { return s.fixed_cycles; })
      .with_flag("--cycles")
      .with_key("explicit.cycles")
      .with_python("fixed_cycles")
      .with_help(
          "fixed-cycle mode: move the grips for exactly N cycles (paper: 200000); 0 = stop when "
          "quasi-static")
      .only_if(explicit_solver, kExplicitOnly);
  d.integer(
       "max_cycles", [](auto& s) -> auto& { return s.max_cycles; })
      .with_flag("--max-cycles")
      .with_key("explicit.max_cycles")
      .with_python("max_cycles")
      .with_help("give up after this many cycles per coupon")
      .only_if(explicit_solver, kExplicitOnly)
      .only_if(staged, kNotFixedCycles);
  d.number(
       "tolerance", [](auto& s) -> auto& { return s.tolerance; })
      .with_flag("--tolerance")
      .with_key("explicit.tolerance")
      .with_python("tolerance")
      .with_help("quasi-static when mean unbalanced force / mean bond force falls below this")
      .only_if(explicit_solver, kExplicitOnly);
}

// The explicit integrator's settings and the solver.
void add_tension_solver(SettingsDescription<TensionSettings>& d) {
  add_explicit_dynamics(d, "where explicit dynamics run ({solver=explicit}): ", explicit_solver,
                        kExplicitOnly);
  d.number(
       "safety", [](auto& s) -> auto& { return s.explicit_settings.safety_factor; })
      .with_flag("--safety")
      .with_key("explicit.safety")
      .with_python("safety")
      .with_help("time step as a fraction of the critical time step")
      .only_if(explicit_solver, kExplicitOnly);
  d.number(
       "grip_velocity", [](auto& s) -> auto& { return s.grip_velocity; })
      .with_flag("--grip-velocity-mm-s")
      .with_key("explicit.grip_velocity_mm_s")
      .with_python("grip_velocity")
      .with_unit(units::millimetres_per_second())
      .with_help("grip velocity {unit}; 0 = derived from {ramp_cycles}")
      .only_if(explicit_solver, kExplicitOnly);
  d.add(
       "solver", SettingType::kText,
       [](const TensionSettings& s) -> SettingValue {
         return std::string(s.solver == TensionSolver::kStatic ? "static" : "explicit");
       },
       [](TensionSettings& s, const SettingValue& v, const std::string&) {
         s.solver = std::get<std::string>(v) == "static" ? TensionSolver::kStatic
                                                         : TensionSolver::kExplicit;
       })
      .with_flag("--solver")
      .with_key("solver")
      .with_python("solver")
      .with_choices(std::vector<std::string>{"explicit", "static"})
      .with_help("static (one sparse linear solve) or explicit (damped dynamics to quasi-static)");
  d.boolean(
       "measure_specimen_stiffness", [](auto& s) -> auto& { return s.measure_specimen_stiffness; })
      .without_flag("the command line always measures Gxy")
      .with_key("measure_specimen_stiffness")
      .with_python("measure_specimen_stiffness")
      .with_help(
          "also measure the specimen's membrane stiffness and Gxy (three more static solves on "
          "the coupon along x)");
}

SettingsDescription<TensionSettings> make_tension_settings() {
  SettingsDescription<TensionSettings> d(default_tension);
  add_strategy(d);
  d.include(
      coupon_settings_description(), [](auto& s) -> auto& { return s.coupon; }, "coupon");
  add_gauge(d);
  add_laminate(d);
  d.add(
       "grips", SettingType::kText,
       [](const TensionSettings& s) -> SettingValue {
         return std::string(s.grips == GripCondition::kClamped ? "clamped" : "free");
       },
       [](TensionSettings& s, const SettingValue& v, const std::string&) {
         s.grips =
             std::get<std::string>(v) == "clamped" ? GripCondition::kClamped : GripCondition::kFree;
       })
      .with_flag("--grips")
      .with_key("coupon.grips")
      .with_python("grips")
      .with_choices(std::vector<std::string>{"free", "clamped"})
      .with_help("free (uniaxial stress) or clamped (ends held laterally)");
  add_solves(d);
  add_tension_loading(d);
  add_tension_solver(d);
  add_checkpoint(d, "cycles ({solver=explicit})");
  return d;
}

// ---- the tension command's CalculiX ------------------------------------------------------------

constexpr char kFemOnly[] = "it is a setting of the CalculiX run of the same coupon (add {fem})";
constexpr char kNoFemInPython[] = "Python's tension_test runs the DEM only";

SettingsDescription<TensionRun> make_tension_run() {
  SettingsDescription<TensionRun> d([] {
    TensionRun r;
    r.test = default_tension();
    return r;
  });
  d.include(
      tension_settings_description(), [](auto& r) -> auto& { return r.test; });
  const auto fem = [](const TensionRun& r) { return r.fem; };
  d.boolean(
       "fem", [](auto& r) -> auto& { return r.fem; })
      .with_flag("--fem")
      .with_key("fem.same_coupon")
      .without_python(kNoFemInPython)
      .with_help(
          "also run CalculiX on the same coupon (plies, size, grips; strains at the DEM's gauge "
          "particles) and show the DEM against it beside CLT");
  d.text(
       "ccx", [](auto& r) -> auto& { return r.twin.executable; })
      .with_flag("--ccx")
      .without_key("`plydem run --ccx`")
      .without_python(kNoFemInPython)
      .with_help("the CalculiX executable ({fem})")
      .only_if(fem, kFemOnly);
  d.number(
       "fem_element_size", [](auto& r) -> auto& { return r.twin.mesh.element_size; })
      .with_flag("--fem-element-mm")
      .with_key("fem.element_mm")
      .without_python(kNoFemInPython)
      .with_unit(units::millimetres())
      .at_least(0)
      .with_help(
          "in-plane element size of {fem} {unit}; 0 = two particle diameters (at most an eighth of "
          "the width)")
      .only_if(fem, kFemOnly);
  d.integer(
       "fem_elements_per_ply", [](auto& r) -> auto& { return r.twin.mesh.elements_per_ply; })
      .with_flag("--fem-elements-per-ply")
      .with_key("fem.elements_per_ply")
      .without_python(kNoFemInPython)
      .at_least(1)
      .at_most(16)
      .with_help("C3D8I elements through each ply's thickness ({fem})")
      .only_if(fem, kFemOnly);
  d.integer(
       "fem_threads", [](auto& r) -> auto& { return r.twin.threads; })
      .with_flag("--fem-threads")
      .with_key("fem.threads")
      .without_python(kNoFemInPython)
      .at_least(1)
      .at_most(1024)
      .with_help("threads CalculiX may use ({fem})")
      .only_if(fem, kFemOnly);
  return d;
}

// ---- the strength test -------------------------------------------------------------------------

StrengthSettings default_strength() {
  StrengthSettings s;
  s.coupon.material = load_material("eglass-my750");
  return s;
}

constexpr char kSofteningOnly[] =
    "it is a setting of softening bonds, and the bonds are brittle (add {softening})";
constexpr char kStrengthNeedsLaminate[] =
    "interface strengths and fracture energies need a laminate ({layup}): one ply has no interface";

bool softening(const StrengthSettings& s) {
  return s.strength_options.softening;
}

// The interface bonds' strengths and fracture energies; `strength` adds the strength test's
// conditions (a laminate; softening bonds for the energies).
template <class S>
void add_interface_strength(SettingsDescription<S>& d, bool conditions) {
  struct Entry {
    const char* name;
    const char* key;
    double InterfaceStrength::*member;
    const char* unit;
    bool energy;
    const char* help;
  };
  const Entry entries[] = {
      {"interface_strength_normal", "strength_normal", &InterfaceStrength::normal, "Pa", false,
       "tensile strength of the interface bonds between plies {unit}; 0 = the interfaces do not "
       "break"},
      {"interface_strength_shear", "strength_shear", &InterfaceStrength::shear, "Pa", false,
       "shear strength (cohesion) of the interface bonds"},
      {"interface_GIc", "GIc", &InterfaceStrength::GIc, "J/m^2", true,
       "mode I fracture energy of the interface {unit} (softening bonds)"},
      {"interface_GIIc", "GIIc", &InterfaceStrength::GIIc, "J/m^2", true,
       "mode II fracture energy of the interface {unit} (softening bonds; 0 = GIc)"},
      {"interface_bk_exponent", "bk_exponent", &InterfaceStrength::bk_exponent, "", true,
       "Benzeggagh-Kenane exponent eta of the interface's mixed-mode fracture energy GIc + (GIIc "
       "- GIc) B^eta (softening bonds)"},
  };
  for (const Entry& e : entries) {
    auto& f = d.number(
                   e.name, [m = e.member](auto& s) -> auto& { return s.interface_strength.*m; })
                  .with_key(std::string("interface.") + e.key)
                  .with_unit(units::same(e.unit))
                  .with_help(e.help);
    std::string flag = std::string("--") + e.name;
    for (char& c : flag)
      if (c == '_') c = '-';
    f.with_flag(flag).with_python(e.name);
    if constexpr (std::is_same_v<S, StrengthSettings>) {
      if (conditions) {
        f.only_if([](const S& s) { return !s.layup.empty(); }, kStrengthNeedsLaminate);
        if (e.energy) f.only_if(softening, kSofteningOnly);
      }
    }
  }
}

// The events solver: its event limit, failure, saw-tooth and updates.
template <class S>
void add_events(SettingsDescription<S>& d) {
  d.integer(
       "max_events", [](auto& s) -> auto& { return s.events.max_events; })
      .with_flag("--max-events")
      .with_key("events.max_events")
      .with_python("max_events")
      .with_help("stop after this many events");
  d.number(
       "stop_fraction", [](auto& s) -> auto& { return s.events.stop_fraction; })
      .with_flag("--stop-fraction")
      .with_key("events.stop_fraction")
      .with_python("stop_fraction")
      .with_help(
          "the coupon has failed when, after the peak, the stress falls below this fraction of the "
          "peak (at the material point, and its stiffness below this fraction of the intact "
          "coupon's)");
  auto& tooth =
      d.number(
           "tooth_stiffness_ratio", [](auto& s) -> auto& { return s.events.tooth_stiffness_ratio; })
          .with_flag("--tooth-stiffness-ratio")
          .with_key("events.tooth_stiffness_ratio")
          .with_python("tooth_stiffness_ratio")
          .with_help(
              "softening bonds: the fraction of its stiffness a bond keeps at each tooth of its "
              "saw-tooth");
  if constexpr (std::is_same_v<S, StrengthSettings>) tooth.only_if(softening, kSofteningOnly);
  d.integer(
       "max_update_rank", [](auto& s) -> auto& { return s.events.max_update_rank; })
      .with_flag("--max-update-rank")
      .with_key("events.max_update_rank")
      .with_python("max_update_rank")
      .at_least(0)
      .with_help(
          "low-rank updates of the last factorization up to this rank, then refactor (0: refactor "
          "after every change; 100 to 300 are fastest, bench/events_bench.cpp)");
}

// The method, the strengths' scatter and the bonds' law.
// The cure the test starts from (strategies/cure_stress.hpp).
void add_strength_cure(SettingsDescription<StrengthSettings>& d) {
  d.number(
       "delta_T", [](auto& s) -> auto& { return s.delta_T; })
      .with_flag("--delta-T")
      .with_key("thermal.delta_T")
      .with_python("delta_T")
      .validated(
          "finite, at most 500 K either way, the material's alpha1 and alpha2 given, the events "
          "method (StrengthSettings::validate)")
      .with_help(
          "the temperature change from stress-free to test [K] (cure cooling: negative; 0 = "
          "none): each bond's free offset is its plies' thermal strain, the grips hold the coupon "
          "where its free cure left it, and the load adds to that state; strains are measured "
          "from it");
}

void add_strength_law(SettingsDescription<StrengthSettings>& d) {
  d.add(
       "method", SettingType::kText,
       [](const StrengthSettings& s) -> SettingValue {
         return std::string(strength_method_name(s.method));
       },
       [](StrengthSettings& s, const SettingValue& v, const std::string&) {
         s.method = parse_strength_method(std::get<std::string>(v));
       })
      .with_flag("--method")
      .with_key("method")
      .with_python("method")
      .with_choices(std::vector<std::string>{"events", "explicit"})
      .with_help(
          "events (quasi-static, one bond at a time: sequentially linear analysis) or explicit "
          "(damped dynamics with breaking bonds)");
  d.add(
       "load", SettingType::kText,
       [](const StrengthSettings& s) -> SettingValue {
         return std::string(strength_load_name(s.load));
       },
       [](StrengthSettings& s, const SettingValue& v, const std::string&) {
         s.load = parse_strength_load(std::get<std::string>(v));
       })
      .with_flag("--load")
      .with_key("load")
      .with_python("load")
      .with_choices(std::vector<std::string>{"tension", "compression", "shear"})
      .validated(
          "compression and shear need a material-point failure criterion "
          "(StrengthSettings::validate)")
      .with_help(
          "tension (the grips move apart), compression (together; failure at the material "
          "point, XC and YC given; stresses and strains reported positive in compression) or "
          "shear (in-plane, the coupon held in a frame at the uniform state under tau_xy; failure "
          "at the material point; tau_xy against gamma_xy)");
  d.add(
       "weibull_modulus", SettingType::kNumber,
       [](const StrengthSettings& s) -> SettingValue {
         if (s.weibull_modulus) return *s.weibull_modulus;
         return std::monostate{};
       },
       [](StrengthSettings& s, const SettingValue& v, const std::string&) {
         if (const double* m = std::get_if<double>(&v)) {
           s.weibull_modulus = *m;
         } else {
           s.weibull_modulus.reset();
         }
       })
      .with_flag("--weibull-modulus")
      .with_key("weibull_modulus")
      .with_python("weibull_modulus")
      .unset_means("the material's weibull_modulus")
      .validated(">= 0 (StrengthSettings::validate)")
      .with_help("Weibull modulus m of the bonds' strength scatter; 0 = none");
  d.integer(
       "seed", [](auto& s) -> auto& { return s.seed; })
      .with_flag("--seed")
      .with_key("seed")
      .with_python("seed")
      .with_help("random stream of the strength scatter (the same seed, the same strengths)")
      .needs([](const StrengthSettings& s) { return s.effective_weibull_modulus() > 0; },
             "strength scatter: give {weibull_modulus} m > 0, or a material with "
             "weibull_modulus");
  d.add(
       "scatter_per", SettingType::kText,
       [](const StrengthSettings& s) -> SettingValue {
         return std::string(s.scatter_per_crack_site ? "site" : "bond");
       },
       [](StrengthSettings& s, const SettingValue& v, const std::string&) {
         s.scatter_per_crack_site = std::get<std::string>(v) == "site";
       })
      .with_flag("--scatter-per")
      .with_key("scatter_per")
      .with_python("scatter_per")
      .with_choices(std::vector<std::string>{"bond", "site"})
      .with_help(
          "draw the strength scatter per bond, or per crack site (a band between particle rows "
          "along the fibre, shared by the bonds that cross it: transverse cracks as a cross-ply's)")
      .only_if([](const StrengthSettings& s) { return s.effective_weibull_modulus() > 0; },
               "there is no strength scatter (give {weibull_modulus} m > 0)");
  d.number(
       "friction", [](auto& s) -> auto& { return s.strength_options.friction_coefficient; })
      .with_flag("--friction")
      .with_key("friction")
      .with_python("friction")
      .validated(">= 0 (StrengthOptions::validate)")
      .with_help("friction coefficient tan(phi) of the bonds' shear strength c - sigma tan(phi)");
  d.add(
       "failure_criterion", SettingType::kText,
       [](const StrengthSettings& s) -> SettingValue {
         return std::string(failure_model_name(s.effective_failure_criterion()));
       },
       [](StrengthSettings& s, const SettingValue& v, const std::string&) {
         s.failure_criterion = failure_model_named(std::get<std::string>(v));
       })
      .with_flag("--failure-criterion")
      .with_key("failure_criterion")
      .with_python("failure_criterion")
      .with_choices(std::vector<std::string>{"bond", "hashin", "puck", "max-stress", "tsai-wu"})
      .with_help(
          "how the ply fails: bond (bond by bond, the parallel-bond law) or a lamina criterion "
          "decided at the material point, each site's crack opening every bond across it "
          "(default: the material's failure_criterion)");
  d.boolean(
       "softening", [](auto& s) -> auto& { return s.strength_options.softening; })
      .with_flag("--softening")
      .with_key("softening")
      .with_python("softening")
      .with_help(
          "linear-softening bonds dissipating the fracture energies G_fibre, G_matrix; at the "
          "material point, each site's crack softens so (default: brittle)");
}

// How a ply's matrix cracks open at the material point: site by site, or through a layer.
void add_crack_criterion(SettingsDescription<StrengthSettings>& d) {
  d.boolean(
       "coupled_criterion", [](auto& s) -> auto& { return s.coupled_criterion; })
      .with_flag("--coupled-criterion")
      .with_key("coupled_criterion")
      .with_python("coupled_criterion")
      .with_help(
          "matrix cracks at the material point by Leguillon's coupled criterion: each opens "
          "through its whole layer at once, when its weakest site meets the lamina criterion and "
          "the layer's crack releases G_matrix per unit area at fixed grips (the in-situ effect; "
          "default: each site's crack opens alone at its strength)")
      .only_if(
          [](const StrengthSettings& s) {
            return s.effective_failure_criterion() != PlyFailureModel::kBond;
          },
          "it is a setting of failure at the material point, and the plies fail bond by bond "
          "(give {failure_criterion} puck, hashin, max-stress or tsai-wu)")
      .only_if([](const StrengthSettings& s) { return !s.strength_options.softening; },
               "the coupled criterion opens brittle cracks, and {softening} makes them soften "
               "(leave out one of the two)");
}

// The grips, the edges' strengths, a hole, and what the strength test records.
void add_strength_coupon(SettingsDescription<StrengthSettings>& d) {
  d.add(
       "grips", SettingType::kText,
       [](const StrengthSettings& s) -> SettingValue {
         return std::string(strength_grips_name(s.grips));
       },
       [](StrengthSettings& s, const SettingValue& v, const std::string&) {
         s.grips = parse_strength_grips(std::get<std::string>(v));
       })
      .with_flag("--grips")
      .with_key("coupon.grips")
      .with_python("grips")
      .with_choices(std::vector<std::string>{"uniform", "free", "clamped"})
      .with_help(
          "uniform (held at the bulk's uniform state under sigma_x: uniform uniaxial stress up to "
          "the grips), free or clamped (the tension test's rigid grips, which break the ply next "
          "to them)");
  d.add(
       "edge_strengths", SettingType::kText,
       [](const StrengthSettings& s) -> SettingValue {
         return std::string(s.consistent_edges ? "bulk" : "weighted");
       },
       [](StrengthSettings& s, const SettingValue& v, const std::string&) {
         s.consistent_edges = std::get<std::string>(v) == "bulk";
       })
      .with_flag("--edge-strengths")
      .with_key("edge_strengths")
      .with_python("edge_strengths")
      .with_choices(std::vector<std::string>{"bulk", "weighted"})
      .with_help(
          "bulk (bonds that the coupon's edges or grips load beyond the relaxed bulk get strengths "
          "to fail with the bulk: edges of a turned lattice do not set the strength) or weighted "
          "(strengths from the stiffness weights alone)")
      .only_if([](const StrengthSettings& s) { return s.grips == StrengthGrips::kUniform; },
               "the edge strengths are made consistent with the bulk under uniform grips only "
               "({grips=uniform}, the default)");
  d.number(
       "hole_diameter", [](auto& s) -> auto& { return s.hole_diameter; })
      .with_flag("--hole-diameter-mm")
      .with_key("coupon.hole_diameter_mm")
      .with_quick_key("quick.hole_diameter_mm")
      .with_python("hole_diameter")
      .with_unit(units::millimetres())
      .validated(">= one particle diameter, < 0.9 of the width, clear of the grips, or 0")
      .with_help(
          "a central circular hole of this diameter {unit}, its edge completed as a free edge "
          "(experiments/protocols/plate_hole.hpp); 0 = none");
  d.number(
       "progress_seconds", [](auto& s) -> auto& { return s.events.progress_seconds; })
      .without_flag("--progress-interval (every command) sets it")
      .without_key("a config's runs report at the default interval")
      .with_python("progress_seconds")
      .with_unit(units::same("s"))
      .with_help("seconds between progress reports (strength_test's progress callback)");
  d.boolean(
       "record_snapshots", [](auto& s) -> auto& { return s.record_snapshots; })
      .without_flag("--out writes the VTU series")
      .with_key("output.vtu_series")
      .without_python("strength_test returns the result's dict only")
      .with_help(
          "VTU files of selected critical states (first failure, events 2^k, the peak, the final "
          "state), not only the last");
}

constexpr char kExplicitMethodOnly[] =
    "it is a setting of the explicit method, and the events method ({method=events}, the default) "
    "has no dynamics (add {method=explicit})";

bool explicit_method(const StrengthSettings& s) {
  return s.method == StrengthMethod::kExplicit;
}

// The explicit method: its loading, the integrator's damping and where it runs.
void add_strength_explicit(SettingsDescription<StrengthSettings>& d) {
  d.integer(
       "cycles_to_failure", [](auto& s) -> auto& { return s.explicit_loading.cycles_to_failure; })
      .with_flag("--cycles-to-failure")
      .with_key("explicit.cycles_to_failure")
      .with_python("cycles_to_failure")
      .at_least(100)
      .with_help(
          "the grips move at the rate that reaches the classical criteria's strength of the coupon "
          "in this many cycles (the loading rate; not where the coupon fails)")
      .only_if(explicit_method, kExplicitMethodOnly);
  d.integer(
       "check_cycles", [](auto& s) -> auto& { return s.explicit_loading.check_cycles; })
      .with_flag("--check-cycles")
      .with_key("explicit.check_cycles")
      .with_python("check_cycles")
      .at_least(1)
      .with_help("cycles between the sites' judgements (failure at the material point) and checks")
      .only_if(explicit_method, kExplicitMethodOnly);
  d.integer(
       "explicit_max_cycles", [](auto& s) -> auto& { return s.explicit_loading.max_cycles; })
      .with_flag("--max-cycles")
      .with_key("explicit.max_cycles")
      .with_python("max_cycles")
      .with_help("give up after this many cycles")
      .only_if(explicit_method, kExplicitMethodOnly);
  add_explicit_dynamics(d, "where the explicit method's dynamics run: ", explicit_method,
                        kExplicitMethodOnly);
}

SettingsDescription<StrengthSettings> make_strength_settings() {
  SettingsDescription<StrengthSettings> d(default_strength);
  add_strategy(d);
  d.include(
      coupon_settings_description(), [](auto& s) -> auto& { return s.coupon; }, "coupon");
  add_gauge(d);
  add_laminate(d);
  add_strength_coupon(d);
  add_solves(d);
  add_strength_law(d);
  add_crack_criterion(d);
  add_strength_cure(d);
  add_interface_strength(d, true);
  add_events(d);
  add_strength_explicit(d);
  add_checkpoint(d, "events");
  return d;
}

// ---- the DCB -----------------------------------------------------------------------------------

constexpr char kDcbKindOnly[] = "the DCB runs from a config (kind dcb) only";

// The beam's size [mm], also under [quick] (ply_thickness under [laminate]).
void add_dcb_size(SettingsDescription<DcbSettings>& d, const std::string& name,
                  const std::string& table, const std::string& key, double DcbSettings::*member,
                  const std::string& help) {
  d.number(
       name, [member](auto& s) -> auto& { return s.*member; })
      .with_key(table + "." + key)
      .with_quick_key("quick." + key)
      .with_unit(units::millimetres())
      .with_help(help);
}

SettingsDescription<DcbSettings> make_dcb_settings() {
  SettingsDescription<DcbSettings> d;
  add_strategy(d);
  d.add(
       "material", SettingType::kText,
       [](const DcbSettings& s) -> SettingValue { return s.material.name; },
       [](DcbSettings& s, const SettingValue& v, const std::string&) {
         s.material = load_material(std::get<std::string>(v));
       })
      .with_key("material")
      .with_help("built-in material name or a TOML file with name, E1, E2, G12, nu12, nu23 (Pa)");
  d.add(
       "layup", SettingType::kText,
       [](const DcbSettings& s) -> SettingValue { return format_layup(s.layup); },
       [](DcbSettings& s, const SettingValue& v, const std::string&) {
         s.layup = parse_layup(std::get<std::string>(v));
       })
      .with_key("laminate.layup")
      .with_quick_key("quick.layup")
      .with_help("the unidirectional laminate, an even number of 0° plies");
  add_dcb_size(d, "ply_thickness", "laminate", "ply_thickness_mm", &DcbSettings::ply_thickness,
               "ply thickness");
  add_dcb_size(d, "length", "coupon", "length_mm", &DcbSettings::length, "beam length L");
  add_dcb_size(d, "width", "coupon", "width_mm", &DcbSettings::width, "beam width b");
  add_dcb_size(d, "crack", "coupon", "crack_mm", &DcbSettings::crack,
               "starter delamination a0, from the load line");
  add_dcb_size(d, "diameter", "coupon", "diameter_mm", &DcbSettings::particle_diameter,
               "particle diameter");
  add_dcb_size(d, "max_crack", "coupon", "max_crack_mm", &DcbSettings::max_crack,
               "the run stops when the crack reaches this length");
  d.number(
       "interface_normal", [](auto& s) -> auto& { return s.interface.normal; })
      .with_key("interface.normal")
      .with_unit(units::same("N/m^3"))
      .with_help("normal stiffness of the interface bonds per unit area; 0 = E2 / g");
  d.number(
       "interface_shear", [](auto& s) -> auto& { return s.interface.shear; })
      .with_key("interface.shear")
      .with_unit(units::same("N/m^3"))
      .with_help("shear stiffness of the interface bonds per unit area; 0 = G12 / g");
  add_interface_strength(d, false);
  add_events(d);
  d.boolean(
       "record_snapshots", [](auto& s) -> auto& { return s.record_snapshots; })
      .with_key("output.vtu_series")
      .with_help("VTU files of selected critical states, not only the last");
  for (SettingField<DcbSettings>& f : d.edit_fields()) {
    f.flag.clear();
    f.python.clear();
    f.no_flag = kDcbKindOnly;
    f.no_python = kDcbKindOnly;
  }
  return d;
}

}  // namespace

std::string backend_choices_help(bool quoted) {
  return backend_help(quoted ? "'" : "");
}

const SettingsDescription<CouponSpec>& coupon_settings_description() {
  static const SettingsDescription<CouponSpec> d = make_coupon_settings();
  return d;
}

const SettingsDescription<TensionSettings>& tension_settings_description() {
  static const SettingsDescription<TensionSettings> d = make_tension_settings();
  return d;
}

const SettingsDescription<TensionRun>& tension_run_description() {
  static const SettingsDescription<TensionRun> d = make_tension_run();
  return d;
}

const SettingsDescription<StrengthSettings>& strength_settings_description() {
  static const SettingsDescription<StrengthSettings> d = make_strength_settings();
  return d;
}

const SettingsDescription<DcbSettings>& dcb_settings_description() {
  static const SettingsDescription<DcbSettings> d = make_dcb_settings();
  return d;
}

SettingsSelection calibrate_selection() {
  return {{"strategy", "strategy_options", "material", "angle", "length", "width", "thickness",
           "diameter"},
          {}};
}

}  // namespace plydem
