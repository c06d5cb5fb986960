#pragma once
/// \file
/// The pieces of define_module (python/bindings.hpp): one `export_<topic>(module)` per class or
/// topic, as HOOMD-blue exports its classes, which python/bindings.cpp calls in order (a class
/// before any function whose signature names it), and the helpers several of them share. Internal
/// to python/: the hosts include python/bindings.hpp only.
// Every piece includes this header first, and with it the same type casters (pybind11 asks that a
// type convert alike in every translation unit of a module). GCC 12 warns, depending on how much it
// inlines into a translation unit, that the Eigen caster's fixed-size temporary (Matrix3d,
// Vector3i) "may be used uninitialized" where it is moved into place (pybind11/eigen/matrix.h,
// type_caster::load). The warning is off for the headers of pybind11 and Eigen, which are first
// included here, and stays on for plydem's own code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#pragma GCC diagnostic pop

#include <Eigen/Core>
#include <string>
#include <utility>

#include "core/error.hpp"

namespace plydem::python {

namespace py = pybind11;

// python/export_material.cpp
void export_material(py::module_& m);  // LaminaStrength, Material, load_material, ...
void export_coupon(py::module_& m);    // CouponSpec
// python/export_model.cpp
void export_model(py::module_& m);  // Particles, Bonds, Model
// python/export_calibration.cpp
void export_strategy_option(py::module_& m);  // StrategyOption
void export_bond_families(py::module_& m);    // FamilyStiffness, FamilyCalibration
void export_calibration(py::module_& m);      // CalibrationDetail, Calibration
void export_unit_cell(py::module_& m);        // CellBond, UnitCell, BoundaryCompletion
// python/export_strategies.cpp
void export_strategy(py::module_& m);  // Strategy, subclassed from Python
void export_registry(py::module_& m);  // strategies, create_strategy, register_strategy, ...
// python/export_specimen.cpp
void export_homogenization(py::module_& m);  // reduced_stiffness, affine_stiffness, ...
void export_specimen(py::module_& m);        // assemble_specimen, complete_boundary_cells
void export_laminate(py::module_& m);        // parse_layup, build_laminate
// python/export_solvers.cpp
void export_dof_constraints(py::module_& m);      // DofConstraints, LEFT_GRIP, UX, ...
void export_static_solve(py::module_& m);         // solve_static
void export_prescribed_motion(py::module_& m);    // PrescribedMotion
void export_explicit_integrator(py::module_& m);  // ExplicitIntegrator
// python/export_experiments.cpp
void export_tension_test(py::module_& m);        // TensionSettings, tension_test
void export_strength_settings(py::module_& m);   // StrengthSettings
void export_strength_test(py::module_& m);       // strength_test
void export_settings_reference(py::module_& m);  // settings_reference
void export_output(py::module_& m);              // write_vtu

// A default T with the keyword arguments set as attributes (a TypeError for an unknown one).
template <class T>
T from_kwargs(const py::kwargs& kwargs, T value = T{}) {
  py::object object = py::cast(std::move(value));
  for (const auto& [key, item] : kwargs) {
    if (!py::hasattr(object, key)) {
      throw py::type_error("unexpected keyword argument '" + py::str(key).cast<std::string>() +
                           "' for " +
                           py::str(py::type::of(object).attr("__name__")).cast<std::string>());
    }
    py::setattr(object, key, item);
  }
  return object.cast<T>();
}

// A 3x3 or 6x6 NumPy array (or nested list) as an Eigen matrix; plydem.Error names a wrong shape.
template <int N>
Eigen::Matrix<double, N, N> square_matrix(const py::object& value, const char* what) {
  const py::array_t<double, py::array::c_style | py::array::forcecast> a =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  require(
      a && a.ndim() == 2 && a.shape(0) == N && a.shape(1) == N,
      std::string(what) + " must be a " + std::to_string(N) + "x" + std::to_string(N) + " array");
  Eigen::Matrix<double, N, N> m;
  auto r = a.unchecked<2>();
  for (int i = 0; i < N; ++i)
    for (int k = 0; k < N; ++k) m(i, k) = r(i, k);
  return m;
}

}  // namespace plydem::python
