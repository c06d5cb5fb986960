/// \file
/// plydem.Particles, plydem.Bonds and plydem.Model: a built specimen whose arrays Python sees as
/// NumPy views of the C++ memory (no copy).
#include "python/export.hpp"

#include <memory>
#include <string>

#include "core/model.hpp"

namespace plydem::python {

namespace {

// A NumPy view of an Eigen array owned by `base` (kept alive by the view): shape (n,) or (n, 3),
// the C++ memory itself. Read-only unless `writable`.
template <class Array>
py::array view(Array& array, py::handle base, bool writable) {
  using Scalar = typename Array::Scalar;
  const py::ssize_t rows = array.rows();
  const py::ssize_t item = sizeof(Scalar);
  py::array result = Array::ColsAtCompileTime == 1
                         ? py::array(py::dtype::of<Scalar>(), {rows}, {item}, array.data(), base)
                         : py::array(py::dtype::of<Scalar>(), {rows, py::ssize_t(array.cols())},
                                     {item, item * rows}, array.data(), base);
  if (!writable) result.attr("setflags")(py::arg("write") = false);
  return result;
}

// The fields a user may write without breaking an invariant of the model (Model::
// check_consistency): the state and the boundary groups, the bonds' stiffnesses and strengths
// (set before an integrator is made from the model). Topology, reference geometry, masses, kinds
// and the bonds' damage and state (the solvers' record) are read-only.
bool writable_particle_field(const std::string& name) {
  return name == "displacement" || name == "velocity" || name == "rotation" ||
         name == "angular_velocity" || name == "force" || name == "torque" || name == "group";
}
bool writable_bond_field(const std::string& name) {
  return name == "normal_stiffness" || name == "shear_stiffness" || name == "bending_stiffness" ||
         name == "twisting_stiffness" || name == "strength_radius" || name == "tensile_strength" ||
         name == "cohesion" || name == "friction_coefficient" || name == "ductility" ||
         name == "mixed_mode_exponent" || name == "fracture_energy_ratio" ||
         name == "peak_energy_ratio";
}

template <class Rows, class Class>
void def_fields(Class& cls, bool (*writable)(const std::string&)) {
  Rows::for_each_field([&](FieldInfo info, auto member) {
    const std::string name = info.name;
    const bool can_write = writable(name);
    cls.def_property_readonly(
        info.name,
        [member, can_write](py::object self) {
          Rows& rows = self.cast<Rows&>();
          return view(rows.*member, self, can_write);
        },
        (std::string("NumPy view (no copy) of the C++ array `") + name + "`" +
         (can_write ? ", writable" : ", read-only") + "; see core/model.hpp for units.")
            .c_str());
  });
}

}  // namespace

void export_model(py::module_& m) {
  py::class_<Particles> particles(
      m, "Particles",
      "The particles of a Model, one row per particle; every field is a NumPy view of the C++ "
      "array (no copy) that keeps the model alive.");
  particles.def("__len__", &Particles::size, "number of particles");
  def_fields<Particles>(particles, writable_particle_field);

  py::class_<Bonds> bonds(m, "Bonds",
                          "The parallel bonds of a Model (paper Sec. 2.2), one row per bond; every "
                          "field is a NumPy view of the C++ array (no copy). first, second and the "
                          "reference geometry are read-only.");
  bonds.def("__len__", &Bonds::size, "number of bonds");
  def_fields<Bonds>(bonds, writable_bond_field);

  py::class_<Model, std::shared_ptr<Model>>(
      m, "Model", "A built specimen: particles and bonds as arrays, and its thickness.")
      .def_property_readonly(
          "particles", [](Model& model) -> Particles& { return model.particles; },
          py::return_value_policy::reference_internal, "the Particles (views, no copy)")
      .def_property_readonly(
          "bonds", [](Model& model) -> Bonds& { return model.bonds; },
          py::return_value_policy::reference_internal, "the Bonds (views, no copy)")
      .def_readonly("thickness", &Model::thickness, "total thickness the layers stand for [m]")
      .def_readonly("description", &Model::description, "what was built")
      .def("check_consistency", &Model::check_consistency,
           "Raises plydem.Error naming the first inconsistency of the arrays.")
      .def("__repr__", [](const Model& model) {
        return "<plydem.Model: " + std::to_string(model.particles.size()) + " particles, " +
               std::to_string(model.bonds.size()) + " bonds>";
      });
}

}  // namespace plydem::python
