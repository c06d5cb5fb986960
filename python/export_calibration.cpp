/// \file
/// What a strategy's calibration is made of, from Python: plydem.StrategyOption,
/// plydem.FamilyStiffness, plydem.FamilyCalibration, plydem.Calibration (also readable as the
/// calibration dict), plydem.CellBond, plydem.UnitCell and plydem.BoundaryCompletion.
#include "python/export.hpp"

#include <memory>
#include <string>
#include <utility>

#include "core/homogenizer.hpp"
#include "strategies/strategy.hpp"

namespace plydem::python {

namespace {

// A copy of a fixed-size Eigen matrix as a NumPy array.
py::array matrix(const Eigen::Matrix3d& m) {
  py::array_t<double> result({3, 3});
  auto r = result.mutable_unchecked<2>();
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) r(i, k) = m(i, k);
  return result;
}

py::dict calibration_dict(const Calibration& c) {
  py::dict d;
  d["method"] = c.method;
  d["lattice_angle"] = c.lattice_angle;
  d["target"] = matrix(c.target);
  d["affine"] = matrix(c.affine);
  d["relaxed"] = matrix(c.relaxed);
  d["relaxed_error"] = c.relaxed_error;
  py::list families;
  for (const FamilyCalibration& f : c.families) {
    py::dict family;
    family["label"] = f.label;
    family["direction"] = f.direction;
    family["normal"] = f.stiffness.normal;
    family["shear"] = f.stiffness.shear;
    family["bending"] = f.stiffness.bending;
    family["twisting"] = f.stiffness.twisting;
    families.append(family);
  }
  d["families"] = families;
  return d;
}

// The value of a Calibration that Python reads as a dict (the keys of calibration_dict).
py::object calibration_item(const Calibration& c, const std::string& key) {
  py::dict d = calibration_dict(c);
  if (!d.contains(key)) throw py::key_error(key);
  return d[py::str(key)];
}

}  // namespace

void export_strategy_option(py::module_& m) {
  py::class_<StrategyOption>(m, "StrategyOption", "A strategy's own parameter and its value.")
      .def(py::init([](std::string name, double value, std::string description) {
             return StrategyOption{std::move(name), value, std::move(description)};
           }),
           py::arg("name"), py::arg("value"), py::arg("description") = "",
           "StrategyOption(name, value, description=''): what a Python strategy's options() "
           "returns.")
      .def_readonly("name", &StrategyOption::name, "the option's name, as set_option takes it")
      .def_readonly("value", &StrategyOption::value, "its current value")
      .def_readonly("description", &StrategyOption::description, "one line, with the unit");
}

void export_bond_families(py::module_& m) {
  py::class_<FamilyStiffness>(m, "FamilyStiffness",
                              "The springs of one bond family: normal and shear contact "
                              "stiffness [N/m], bending and twisting [N m/rad].")
      .def(py::init([](double normal, double shear, double bending, double twisting) {
             return FamilyStiffness{normal, shear, bending, twisting};
           }),
           py::arg("normal") = 0.0, py::arg("shear") = 0.0, py::arg("bending") = 0.0,
           py::arg("twisting") = 0.0, "FamilyStiffness(normal, shear, bending=0, twisting=0)")
      .def_readwrite("normal", &FamilyStiffness::normal, "k_n [N/m]")
      .def_readwrite("shear", &FamilyStiffness::shear, "k_s [N/m]")
      .def_readwrite("bending", &FamilyStiffness::bending, "k_b [N m/rad]")
      .def_readwrite("twisting", &FamilyStiffness::twisting, "k_t [N m/rad]")
      .def("__repr__", [](const FamilyStiffness& k) {
        return "FamilyStiffness(normal=" + std::to_string(k.normal) +
               ", shear=" + std::to_string(k.shear) + ", bending=" + std::to_string(k.bending) +
               ", twisting=" + std::to_string(k.twisting) + ")";
      });

  py::class_<FamilyCalibration>(
      m, "FamilyCalibration",
      "One bond family's calibrated springs: its label, its direction from +x in the specimen "
      "frame [rad] and its FamilyStiffness. Also readable as a dict (label, direction, normal, "
      "shear, bending, twisting).")
      .def(py::init([](std::string label, double direction, const FamilyStiffness& stiffness) {
             return FamilyCalibration{std::move(label), direction, stiffness};
           }),
           py::arg("label"), py::arg("direction"), py::arg("stiffness"),
           "FamilyCalibration(label, direction, stiffness)")
      .def_readwrite("label", &FamilyCalibration::label, "e.g. '1 (fibre)'")
      .def_readwrite("direction", &FamilyCalibration::direction, "from +x [rad]")
      .def_readwrite("stiffness", &FamilyCalibration::stiffness, "its FamilyStiffness")
      .def(
          "__getitem__",
          [](const FamilyCalibration& f, const std::string& key) -> py::object {
            if (key == "label") return py::str(f.label);
            if (key == "direction") return py::float_(f.direction);
            if (key == "normal") return py::float_(f.stiffness.normal);
            if (key == "shear") return py::float_(f.stiffness.shear);
            if (key == "bending") return py::float_(f.stiffness.bending);
            if (key == "twisting") return py::float_(f.stiffness.twisting);
            throw py::key_error(key);
          },
          "f['normal'] etc., as in the calibration dict");
}

void export_calibration(py::module_& m) {
  py::class_<CalibrationDetail, std::shared_ptr<CalibrationDetail>>(
      m, "CalibrationDetail", "Strategy-specific data of a built-in strategy's calibration.");
  py::class_<Calibration>(
      m, "Calibration",
      "The outcome of calibrating a ply (strategies/strategy.hpp): the method, the packing's "
      "orientation, each bond family's springs, and the plane-stress stiffnesses target (Q-bar), "
      "affine (eq. 5) and relaxed (the model as simulated, spins relaxed) as 3x3 NumPy arrays "
      "[Pa], with relaxed_error = |relaxed - target|_F / |target|_F. A Python strategy's "
      "calibrate() returns one. Also readable as a dict: c['relaxed'], c['families'][0]['normal'].")
      .def(py::init([](py::kwargs kwargs) { return from_kwargs<Calibration>(kwargs); }),
           "Calibration(method=..., lattice_angle=..., families=[FamilyCalibration...], "
           "target=..., affine=..., relaxed=..., relaxed_error=...)")
      .def_readwrite("method", &Calibration::method, "how the springs were found")
      .def_readwrite("lattice_angle", &Calibration::lattice_angle,
                     "orientation of the packing from +x [rad]")
      .def_readwrite("families", &Calibration::families, "list of FamilyCalibration (a copy)")
      .def_property(
          "target", [](const Calibration& c) { return matrix(c.target); },
          [](Calibration& c, const py::object& v) { c.target = square_matrix<3>(v, "target"); },
          "plane-stress Q-bar of the ply [Pa], 3x3")
      .def_property(
          "affine", [](const Calibration& c) { return matrix(c.affine); },
          [](Calibration& c, const py::object& v) { c.affine = square_matrix<3>(v, "affine"); },
          "eq. (5) lattice sum [Pa], 3x3")
      .def_property(
          "relaxed", [](const Calibration& c) { return matrix(c.relaxed); },
          [](Calibration& c, const py::object& v) { c.relaxed = square_matrix<3>(v, "relaxed"); },
          "stiffness with spins and shifts relaxed [Pa], 3x3: what the engine simulates")
      .def_readwrite("relaxed_error", &Calibration::relaxed_error,
                     "|relaxed - target|_F / |target|_F")
      .def_readwrite("detail", &Calibration::detail,
                     "strategy-specific data (built-in strategies); None for a Python one")
      .def("__getitem__", &calibration_item, py::arg("key"),
           "the calibration dict's entry: method, lattice_angle, target, affine, relaxed, "
           "relaxed_error, families")
      .def(
          "keys", [](const Calibration& c) { return calibration_dict(c).attr("keys")(); },
          "the keys of the calibration dict")
      .def("__repr__", [](const Calibration& c) {
        return "<plydem.Calibration: " + c.method + ", " + std::to_string(c.families.size()) +
               " families, relaxed error " + std::to_string(c.relaxed_error) + ">";
      });
}

void export_unit_cell(py::module_& m) {
  py::class_<UnitCell::Bond>(m, "CellBond",
                             "A bond of a UnitCell: particles first and second (second in the "
                             "cell `image`, in lattice vectors) and its family.")
      .def(py::init([](int first, int second, const Eigen::Vector3i& image, int family) {
             return UnitCell::Bond{first, second, image, family};
           }),
           py::arg("first"), py::arg("second"), py::arg("image") = Eigen::Vector3i::Zero(),
           py::arg("family") = 0, "CellBond(first, second, image=(0, 0, 0), family=0)")
      .def_readwrite("first", &UnitCell::Bond::first, "basis index of one end")
      .def_readwrite("second", &UnitCell::Bond::second, "basis index of the other end")
      .def_readwrite("image", &UnitCell::Bond::image,
                     "the cell of `second`, in lattice vectors (3 ints)")
      .def_readwrite("family", &UnitCell::Bond::family, "its bond family");
  py::class_<UnitCell>(
      m, "UnitCell",
      "A periodic cell of a packing (core/homogenizer.hpp): lattice vectors as the columns of a "
      "3x3 array (for a layer the third is the thickness direction), basis particle positions "
      "and radii [m], the cell volume [m^3] (area x thickness for a layer), its bonds (each "
      "once) and the number of bond families. affine_stiffness and relaxed_stiffness homogenize "
      "it.")
      .def(py::init([](py::kwargs kwargs) { return from_kwargs<UnitCell>(kwargs); }),
           "UnitCell(lattice_vectors=..., basis=[...], radius=[...], volume=..., "
           "bonds=[CellBond...], family_count=...)")
      .def_readwrite("lattice_vectors", &UnitCell::lattice_vectors, "columns: a1, a2, a3 [m]")
      .def_readwrite("basis", &UnitCell::basis, "particle positions in the cell [m]")
      .def_readwrite("radius", &UnitCell::radius, "per basis particle [m]")
      .def_readwrite("volume", &UnitCell::volume, "[m^3]")
      .def_readwrite("bonds", &UnitCell::bonds, "list of CellBond (a copy)")
      .def_readwrite("family_count", &UnitCell::family_count, "number of bond families");

  py::class_<BoundaryCompletion>(
      m, "BoundaryCompletion",
      "How a strategy completes the boundary cells of free edges: every in-ply family has "
      "bulk_bonds bonds per bulk particle; family_count 0 = not redoable on a cut coupon.")
      .def(py::init([](int family_count, int bulk_bonds) {
             return BoundaryCompletion{family_count, bulk_bonds};
           }),
           py::arg("family_count") = 0, py::arg("bulk_bonds") = 0,
           "BoundaryCompletion(family_count=0, bulk_bonds=0)")
      .def_readwrite("family_count", &BoundaryCompletion::family_count,
                     "in-ply bond families; 0 = not redoable")
      .def_readwrite("bulk_bonds", &BoundaryCompletion::bulk_bonds,
                     "bonds of each family per bulk particle");
}

}  // namespace plydem::python
