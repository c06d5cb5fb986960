/// \file
/// `import plydem`: the library from Python (pybind11). Materials, the strategy registry and its
/// calibrations, strategies written in Python (subclasses of plydem.Strategy, registered by name),
/// ply coupons and laminates built into a Model whose particle and bond arrays are NumPy views of
/// the C++ arrays (no copy), the static solve, explicit runs with a callback, the tension and
/// strength tests (the same dicts as `plydem tension --json` and `plydem strength --json`) and VTU
/// output. Every plydem::Error arrives as plydem.Error with the library's message. The GIL is
/// released while C++ works; a Python strategy's methods take it back when the library calls them.
///
/// Each class or topic is exported by its own function (python/export.hpp); this file calls them
/// in the order the module is built.
#include "python/bindings.hpp"

#include "core/error.hpp"
#include "python/export.hpp"

namespace plydem::python {

void define_module(py::module_& m) {
  m.doc() =
      "plydem: particle (DEM and lattice) models of FRP composite laminae and laminates.\n\n"
      "SI units throughout (m, Pa, N, rad). Arrays of a Model are NumPy views of the C++ arrays.\n"
      "Every error the library raises arrives as plydem.Error with its message.";
  m.attr("__version__") = PLYDEM_VERSION;
  auto& error = py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  error.attr("__doc__") =
      "Bad input or an impossible request (plydem::Error): the message names the problem in the "
      "user's terms, as the command line prints it.";

  export_material(m);
  export_coupon(m);
  export_model(m);
  export_strategy_option(m);
  export_bond_families(m);
  export_calibration(m);
  export_unit_cell(m);
  export_strategy(m);
  export_registry(m);
  export_homogenization(m);
  export_specimen(m);
  export_laminate(m);
  export_dof_constraints(m);
  export_static_solve(m);
  export_prescribed_motion(m);
  export_explicit_integrator(m);
  export_tension_test(m);
  export_strength_settings(m);
  export_strength_test(m);
  export_settings_reference(m);
  export_output(m);
}

}  // namespace plydem::python
