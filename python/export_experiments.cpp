/// \file
/// The experiments from Python: plydem.TensionSettings and tension_test, plydem.StrengthSettings
/// and strength_test (each returning the dict its command prints with --json), and write_vtu.
#include "python/export.hpp"

#include <nlohmann/json.hpp>
#include <string>

#include "core/material.hpp"
#include "experiments/output/report.hpp"
#include "experiments/output/strength_report.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/protocols/tension.hpp"
#include "solvers/device_backend.hpp"
#include "solvers/linear_solver.hpp"

namespace plydem::python {

namespace {

// A nlohmann::json value as the Python object json.loads would give.
py::object to_python(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null:
      return py::none();
    case nlohmann::json::value_t::boolean:
      return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer:
      return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_unsigned:
      return py::int_(j.get<unsigned long long>());
    case nlohmann::json::value_t::number_float:
      return py::float_(j.get<double>());
    case nlohmann::json::value_t::string:
      return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list list;
      for (const nlohmann::json& item : j) list.append(to_python(item));
      return list;
    }
    case nlohmann::json::value_t::object: {
      py::dict dict;
      for (auto it = j.begin(); it != j.end(); ++it)
        dict[py::str(it.key())] = to_python(it.value());
      return dict;
    }
    default:
      throw Error("a JSON value of a kind Python has no equivalent for");
  }
}

std::string grips_name(GripCondition g) {
  return g == GripCondition::kClamped ? "clamped" : "free";
}
std::string solver_name(TensionSolver s) {
  return s == TensionSolver::kStatic ? "static" : "explicit";
}

// The attributes TensionSettings and StrengthSettings share (their fields of the same names):
// the strategy, the coupon, the laminate, the gauge and the static solves' solver.
template <class Settings>
void def_coupon_settings(py::class_<Settings>& cls) {
  cls.def_readwrite("strategy", &Settings::strategy, "registered strategy name")
      .def_readwrite("strategy_options", &Settings::strategy_options,
                     "list of (name, value), applied in order before calibration")
      .def_readwrite("coupon", &Settings::coupon, "material, ply angle and size")
      .def_readwrite("layup", &Settings::layup,
                     "ply angles of a laminate, bottom to top [rad]; empty = one ply")
      .def_property(
          "interface_normal", [](const Settings& s) { return s.interface.normal; },
          [](Settings& s, double v) { s.interface.normal = v; },
          "interface normal stiffness per unit area [N/m^3]; 0 = 10 E2/t")
      .def_property(
          "interface_shear", [](const Settings& s) { return s.interface.shear; },
          [](Settings& s, double v) { s.interface.shear = v; },
          "interface shear stiffness per unit area [N/m^3]; 0 = 10 G12/t (100 G12/t with "
          "interface_transverse_shear)")
      .def_property(
          "interface_transverse_shear",
          [](const Settings& s) { return s.interface.transverse_shear; },
          [](Settings& s, bool v) { s.interface.transverse_shear = v; },
          "the plies carry the laminate's transverse shear G13, G23 (strategies/laminate.hpp); "
          "static and events solvers only")
      .def_readwrite("grip_length", &Settings::grip_length, "[m]; 0 = two diameters")
      .def_readwrite("gauge_fraction", &Settings::gauge_fraction,
                     "central fraction of the length measured")
      .def_readwrite("edge_band_diameters", &Settings::edge_band_diameters,
                     "gauge particles this many diameters from a free edge are left out")
      .def_property(
          "linear_solver", [](const Settings& s) { return linear_solver_name(s.linear_solver); },
          [](Settings& s, const std::string& v) { s.linear_solver = parse_linear_solver(v); },
          "static solves: 'auto' (by the factor's fill and memory, and the MPI ranks), 'direct' "
          "(plydem's supernodal Cholesky), 'cholmod' (SuiteSparse) or 'petsc' (CG + algebraic "
          "multigrid; a build with PETSc)");
}

// The strengths and fracture energies of a laminate's interface bonds (StrengthSettings::
// interface_strength), as attributes of StrengthSettings.
void def_interface_strength(py::class_<StrengthSettings>& cls) {
  cls.def_property(
         "interface_strength_normal",
         [](const StrengthSettings& s) { return s.interface_strength.normal; },
         [](StrengthSettings& s, double v) { s.interface_strength.normal = v; },
         "tensile strength of the interface bonds [Pa]; 0 = the interfaces do not break")
      .def_property(
          "interface_strength_shear",
          [](const StrengthSettings& s) { return s.interface_strength.shear; },
          [](StrengthSettings& s, double v) { s.interface_strength.shear = v; },
          "shear strength (cohesion) of the interface bonds [Pa]")
      .def_property(
          "interface_GIc", [](const StrengthSettings& s) { return s.interface_strength.GIc; },
          [](StrengthSettings& s, double v) { s.interface_strength.GIc = v; },
          "mode I fracture energy of the interface [J/m^2] (softening bonds)")
      .def_property(
          "interface_GIIc", [](const StrengthSettings& s) { return s.interface_strength.GIIc; },
          [](StrengthSettings& s, double v) { s.interface_strength.GIIc = v; },
          "mode II fracture energy of the interface [J/m^2] (softening bonds; 0 = GIc)")
      .def_property(
          "interface_bk_exponent",
          [](const StrengthSettings& s) { return s.interface_strength.bk_exponent; },
          [](StrengthSettings& s, double v) { s.interface_strength.bk_exponent = v; },
          "Benzeggagh-Kenane exponent eta of the interface's mixed-mode fracture energy "
          "GIc + (GIIc - GIc) B^eta (softening bonds)");
}

}  // namespace

void export_tension_test(py::module_& m) {
  py::class_<TensionSettings> tension_settings(
      m, "TensionSettings",
      "The virtual uniaxial tension test (paper Secs. 3.4 and 4), as `plydem tension` sets it "
      "up; keywords set the attributes below. Angles in radians, sizes in metres.");
  def_coupon_settings(tension_settings);
  tension_settings
      .def(py::init([](py::kwargs kwargs) {
             TensionSettings settings;
             settings.coupon.material = load_material("eglass-my750");
             return from_kwargs<TensionSettings>(kwargs, settings);
           }),
           "TensionSettings(**keywords): the command line's defaults, changed by the keywords.")
      .def_readwrite("target_strain", &TensionSettings::target_strain, "nominal final strain")
      .def_readwrite("load_stages", &TensionSettings::load_stages, "points of the fit")
      .def_readwrite("ramp_cycles", &TensionSettings::ramp_cycles, "explicit: cycles per stage")
      .def_readwrite("grip_velocity", &TensionSettings::grip_velocity, "[m/s]; 0 = from ramp")
      .def_readwrite("tolerance", &TensionSettings::tolerance, "quasi-static force ratio")
      .def_readwrite("max_cycles", &TensionSettings::max_cycles, "explicit: per coupon")
      .def_readwrite("fixed_cycles", &TensionSettings::fixed_cycles,
                     "explicit: > 0 = the paper's fixed-cycle mode")
      .def_readwrite("measure_specimen_stiffness", &TensionSettings::measure_specimen_stiffness,
                     "also measure the membrane stiffness and Gxy")
      .def_readwrite("force", &TensionSettings::force,
                     "build even when the coupon's memory estimate exceeds the machine's available "
                     "memory (otherwise refused with plydem.Error before building)")
      .def_property(
          "grips", [](const TensionSettings& s) { return grips_name(s.grips); },
          [](TensionSettings& s, const std::string& v) {
            require(v == "free" || v == "clamped", "grips '" + v + "' is neither free nor clamped");
            s.grips = v == "free" ? GripCondition::kFree : GripCondition::kClamped;
          },
          "'free' (uniaxial stress) or 'clamped'")
      .def_property(
          "solver", [](const TensionSettings& s) { return solver_name(s.solver); },
          [](TensionSettings& s, const std::string& v) {
            require(v == "static" || v == "explicit",
                    "solver '" + v + "' is neither static nor explicit");
            s.solver = v == "static" ? TensionSolver::kStatic : TensionSolver::kExplicit;
          },
          "'static' (one sparse solve) or 'explicit' (damped dynamics)")
      .def_property(
          "damping", [](const TensionSettings& s) { return s.explicit_settings.local_damping; },
          [](TensionSettings& s, double v) { s.explicit_settings.local_damping = v; },
          "explicit: PFC local damping coefficient")
      .def_property(
          "safety", [](const TensionSettings& s) { return s.explicit_settings.safety_factor; },
          [](TensionSettings& s, double v) { s.explicit_settings.safety_factor = v; },
          "explicit: time step as a fraction of the critical one")
      .def_property(
          "backend",
          [](const TensionSettings& s) {
            return std::string(to_string(s.explicit_settings.backend));
          },
          [](TensionSettings& s, const std::string& v) {
            s.explicit_settings.backend = parse_backend_choice(v);
          },
          (std::string("explicit: where the dynamics run: ") + backend_help()).c_str())
      .def("validate", &TensionSettings::validate, "Raises plydem.Error naming a bad setting.");

  m.def(
      "tension_test",
      [](py::object settings_or_none, py::kwargs kwargs) {
        TensionSettings settings;
        settings.coupon.material = load_material("eglass-my750");
        if (!settings_or_none.is_none()) settings = settings_or_none.cast<TensionSettings>();
        settings = from_kwargs<TensionSettings>(kwargs, settings);
        TensionTest test(settings);
        test.on_progress([](const TensionProgress&) {
          py::gil_scoped_acquire acquire;  // to honour Ctrl-C during long explicit runs
          if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        });
        nlohmann::json json;
        {
          py::gil_scoped_release release;
          const TensionResult result = test.run();
          json = tension_json(result, settings);
        }
        return to_python(json);
      },
      py::arg("settings") = py::none(),
      "Runs the tension test (TensionSettings, or its keywords) and returns the dict `plydem "
      "tension --json` prints: Ex, Ey, nu_xy, nu_yx, theory, particles, bonds, wall_seconds, ...");
}

void export_strength_settings(py::module_& m) {
  py::class_<StrengthSettings> strength_settings(
      m, "StrengthSettings",
      "The tension test to failure (`plydem strength`), with the command line's defaults (its "
      "strategy: square); "
      "keywords set the attributes below. Angles in radians, sizes in metres, strengths in Pa.");
  def_coupon_settings(strength_settings);
  strength_settings.def(
      py::init([](py::kwargs kwargs) {
        StrengthSettings settings;
        settings.coupon.material = load_material("eglass-my750");
        return from_kwargs<StrengthSettings>(kwargs, settings);
      }),
      "StrengthSettings(**keywords): the command line's defaults, changed by the keywords.");
  def_interface_strength(strength_settings);
  strength_settings
      .def_property(
          "method", [](const StrengthSettings& s) { return strength_method_name(s.method); },
          [](StrengthSettings& s, const std::string& v) { s.method = parse_strength_method(v); },
          "'events' (sequentially linear analysis, one bond at a time)")
      .def_readwrite("weibull_modulus", &StrengthSettings::weibull_modulus,
                     "Weibull modulus of the bonds' strength scatter; None = the material's, 0 = "
                     "none")
      .def_readwrite("seed", &StrengthSettings::seed, "random stream of the scatter")
      .def_property(
          "friction",
          [](const StrengthSettings& s) { return s.strength_options.friction_coefficient; },
          [](StrengthSettings& s, double v) { s.strength_options.friction_coefficient = v; },
          "friction coefficient tan(phi) of the bonds' shear strength c - sigma tan(phi)")
      .def_property(
          "softening", [](const StrengthSettings& s) { return s.strength_options.softening; },
          [](StrengthSettings& s, bool v) { s.strength_options.softening = v; },
          "linear-softening bonds dissipating G_fibre, G_matrix (else brittle)")
      .def_property(
          "grips", [](const StrengthSettings& s) { return strength_grips_name(s.grips); },
          [](StrengthSettings& s, const std::string& v) { s.grips = parse_strength_grips(v); },
          "'uniform' (held at the bulk's uniform state), 'free' or 'clamped'")
      .def_property(
          "edge_strengths",
          [](const StrengthSettings& s) { return s.consistent_edges ? "bulk" : "weighted"; },
          [](StrengthSettings& s, const std::string& v) {
            require(v == "bulk" || v == "weighted",
                    "edge_strengths '" + v + "' is neither bulk nor weighted");
            s.consistent_edges = v == "bulk";
          },
          "'bulk' (edge bonds fail with the bulk) or 'weighted' (from stiffness weights alone)")
      .def_property(
          "max_events", [](const StrengthSettings& s) { return s.events.max_events; },
          [](StrengthSettings& s, long v) { s.events.max_events = v; },
          "stop after this many events")
      .def_property(
          "stop_fraction", [](const StrengthSettings& s) { return s.events.stop_fraction; },
          [](StrengthSettings& s, double v) { s.events.stop_fraction = v; },
          "failed when the stress after the peak falls below this fraction of it")
      .def_property(
          "tooth_stiffness_ratio",
          [](const StrengthSettings& s) { return s.events.tooth_stiffness_ratio; },
          [](StrengthSettings& s, double v) { s.events.tooth_stiffness_ratio = v; },
          "softening bonds: the stiffness fraction kept at each tooth")
      .def_property(
          "progress_seconds", [](const StrengthSettings& s) { return s.events.progress_seconds; },
          [](StrengthSettings& s, double v) { s.events.progress_seconds = v; },
          "seconds between progress reports (strength_test's progress callback) [s]")
      .def("validate", &StrengthSettings::validate, "Raises plydem.Error naming a bad setting.");
}

void export_strength_test(py::module_& m) {
  m.def(
      "strength_test",
      [](py::object settings_or_none, py::object progress, py::kwargs kwargs) {
        StrengthSettings settings;
        settings.coupon.material = load_material("eglass-my750");
        if (!settings_or_none.is_none()) settings = settings_or_none.cast<StrengthSettings>();
        settings = from_kwargs<StrengthSettings>(kwargs, settings);
        settings.validate();
        StrengthTest test(settings);
        // Every progress report takes the GIL: for the callback, and to honour Ctrl-C.
        test.on_progress([&progress](const EventProgress& p) {
          py::gil_scoped_acquire acquire;
          if (PyErr_CheckSignals() != 0) throw py::error_already_set();
          if (progress.is_none()) return;
          py::dict d;
          d["events"] = p.events;
          d["broken"] = p.broken;
          d["load_factor"] = p.load_factor;
          d["peak_reaction"] = p.peak_reaction;
          d["elapsed_seconds"] = p.elapsed_seconds;
          progress(d);
        });
        nlohmann::json json;
        {
          py::gil_scoped_release release;
          const StrengthResult result = test.run();
          json = strength_json(result, settings);
        }
        return to_python(json);
      },
      py::arg("settings") = py::none(), py::arg("progress") = py::none(),
      "Runs the tension test to failure (StrengthSettings, or its keywords) and returns the dict "
      "`plydem strength --json` prints: strength, strain_at_peak, first_failure_stress, curve, "
      "broken_bonds, theory (max-stress, Tsai-Hill, Tsai-Wu, Hashin), events, ... "
      "progress(dict) is called every 2 s of a long run (events, broken, load_factor, "
      "peak_reaction, elapsed_seconds); Ctrl-C stops the run.");
}

void export_output(py::module_& m) {
  m.def(
      "write_vtu",
      [](const Model& model, const std::string& particles_path, const std::string& bonds_path,
         double displacement_scale, bool include_force) {
        VtkOptions options;
        options.displacement_scale = displacement_scale;
        options.include_force = include_force;
        py::gil_scoped_release release;
        write_particles_vtu(model, particles_path, options);
        if (!bonds_path.empty()) write_bonds_vtu(model, bonds_path, options);
      },
      py::arg("model"), py::arg("particles_path"), py::arg("bonds_path") = "",
      py::arg("displacement_scale") = 1.0, py::arg("include_force") = true,
      "Writes the particles (and, given bonds_path, the bonds) as ParaView .vtu files "
      "(experiments/output/vtk_output.hpp); points at reference + displacement_scale * "
      "displacement.");
}

}  // namespace plydem::python
