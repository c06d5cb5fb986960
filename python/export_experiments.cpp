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
#include "experiments/protocols/run_settings.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "experiments/runner/settings_reference.hpp"
#include "python/settings_python.hpp"

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

// The attributes bound by hand (python_native in the descriptions: the struct's own members in
// their own types), which TensionSettings and StrengthSettings share.
template <class Settings>
void def_native_settings(py::class_<Settings>& cls) {
  cls.def_readwrite("strategy_options", &Settings::strategy_options,
                    "list of (name, value), applied in order before calibration")
      .def_readwrite("coupon", &Settings::coupon,
                     "material, ply angle and size (plydem.CouponSpec; coupon.* settings)")
      .def_readwrite("layup", &Settings::layup,
                     "ply angles of a laminate, bottom to top [rad]; empty = one ply")
      .def("validate", &Settings::validate, "Raises plydem.Error naming a bad setting.");
}

}  // namespace

void export_tension_test(py::module_& m) {
  py::class_<TensionSettings> tension_settings(
      m, "TensionSettings",
      "The virtual uniaxial tension test (paper Secs. 3.4 and 4), as `plydem tension` sets it "
      "up; keywords set the attributes below (docs/settings.md lists them with the command "
      "line's flags). Angles in radians, sizes in metres.");
  tension_settings.def(py::init([](py::kwargs kwargs) {
                         return from_kwargs<TensionSettings>(
                             kwargs, tension_settings_description().defaults());
                       }),
                       "TensionSettings(**keywords): the command line's defaults, changed by the "
                       "keywords.");
  def_native_settings(tension_settings);
  def_settings(tension_settings, tension_settings_description());

  m.def(
      "tension_test",
      [](py::object settings_or_none, py::kwargs kwargs) {
        const RunSettings run = run_settings_from_kwargs(kwargs);
        TensionSettings settings = tension_settings_description().defaults();
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
          const RunScope scope(run);
          const TensionResult result = test.run();
          json = tension_json(result, settings);
        }
        return to_python(json);
      },
      py::arg("settings") = py::none(),
      "Runs the tension test (TensionSettings, or its keywords) and returns the dict `plydem "
      "tension --json` prints: Ex, Ey, nu_xy, nu_yx, theory, particles, bonds, wall_seconds, ... "
      "The run's keywords threads (OpenMP threads; 0 = OpenMP's default) and petsc_options apply "
      "to this run.");
}

void export_strength_settings(py::module_& m) {
  py::class_<StrengthSettings> strength_settings(
      m, "StrengthSettings",
      "The tension test to failure (`plydem strength`), with the command line's defaults (its "
      "strategy: square); keywords set the attributes below (docs/settings.md lists them with the "
      "command line's flags). Angles in radians, sizes in metres, strengths in Pa.");
  strength_settings.def(py::init([](py::kwargs kwargs) {
                          return from_kwargs<StrengthSettings>(
                              kwargs, strength_settings_description().defaults());
                        }),
                        "StrengthSettings(**keywords): the command line's defaults, changed by "
                        "the keywords.");
  def_native_settings(strength_settings);
  def_settings(strength_settings, strength_settings_description());
}

void export_strength_test(py::module_& m) {
  m.def(
      "strength_test",
      [](py::object settings_or_none, py::object progress, py::kwargs kwargs) {
        const RunSettings run = run_settings_from_kwargs(kwargs);
        StrengthSettings settings = strength_settings_description().defaults();
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
          const RunScope scope(run);
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
      "peak_reaction, elapsed_seconds); Ctrl-C stops the run. The run's keywords threads and "
      "petsc_options apply to this run.");
}

void export_settings_reference(py::module_& m) {
  m.def(
      "settings_reference", [] { return to_python(settings_json()); },
      "Every setting of the commands, the experiment kinds and Python (`plydem settings --json`, "
      "docs/settings.md): a list of tables, each with id, title, command, kind, python and "
      "settings (name, type, flag, key, python, default, unit, choices, help, ...).");
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
