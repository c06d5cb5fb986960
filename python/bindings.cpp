/// \file
/// `import plydem`: the library from Python (pybind11). Materials, the strategy registry and its
/// calibrations, strategies written in Python (subclasses of plydem.Strategy, registered by name),
/// ply coupons and laminates built into a Model whose particle and bond arrays are NumPy views of
/// the C++ arrays (no copy), the static solve, explicit runs with a callback, the tension and
/// strength tests (the same dicts as `plydem tension --json` and `plydem strength --json`) and VTU
/// output. Every plydem::Error arrives as plydem.Error with the library's message. The GIL is
/// released while C++ works; a Python strategy's methods take it back when the library calls them.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/homogenizer.hpp"
#include "core/material.hpp"
#include "core/model.hpp"
#include "experiments/output/report.hpp"
#include "experiments/output/strength_report.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/protocols/tension.hpp"
#include "python/bindings.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"
#include "strategies/strategy.hpp"

namespace py = pybind11;
using namespace plydem;

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

std::string grips_name(GripCondition g) {
  return g == GripCondition::kClamped ? "clamped" : "free";
}
std::string solver_name(TensionSolver s) {
  return s == TensionSolver::kStatic ? "static" : "explicit";
}

StaticMethod static_method(const std::string& name) {
  if (name == "auto") return StaticMethod::kAuto;
  if (name == "direct") return StaticMethod::kDirect;
  if (name == "iterative") return StaticMethod::kIterative;
  throw Error("static method '" + name + "' is none of auto, direct, iterative");
}

py::dict check_dict(const RunCheck& c) {
  py::dict d;
  d["cycles"] = c.cycles;
  d["run_cycles"] = c.run_cycles;
  d["strain_energy"] = c.report.strain_energy;
  d["kinetic_energy"] = c.report.kinetic_energy;
  d["unbalanced_force_ratio"] = c.report.unbalanced_force_ratio;
  d["elapsed_seconds"] = c.elapsed_seconds;
  d["seconds_left"] = c.seconds_left;
  return d;
}

// An ExplicitIntegrator with the Model it advances (kept alive by the Python object).
struct PyIntegrator {
  std::shared_ptr<Model> model;
  ExplicitIntegrator integrator;
  PyIntegrator(std::shared_ptr<Model> m, const ExplicitSettings& settings)
      : model(std::move(m)), integrator(*model, settings) {}
};

// The trampoline that lets Python subclass plydem.Strategy: every virtual of Strategy looks for a
// Python override (PYBIND11_OVERRIDE takes the GIL while it calls it). description, calibrate and
// assemble must be overridden; the others keep Strategy's defaults.
class PyStrategy : public Strategy {
 public:
  std::vector<StrategyOption> options() const override {
    PYBIND11_OVERRIDE(std::vector<StrategyOption>, Strategy, options, );
  }
  void set_option(const std::string& name, double value) override {
    PYBIND11_OVERRIDE(void, Strategy, set_option, name, value);
  }
  std::string description() const override {
    PYBIND11_OVERRIDE_PURE(std::string, Strategy, description, );
  }
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override {
    PYBIND11_OVERRIDE_PURE(Calibration, Strategy, calibrate, material, ply_angle, thickness);
  }
  Calibration calibrate_coupon(const CouponSpec& coupon) const override {
    PYBIND11_OVERRIDE(Calibration, Strategy, calibrate_coupon, coupon);
  }
  std::string calibration_key(const CouponSpec& coupon) const override {
    PYBIND11_OVERRIDE(std::string, Strategy, calibration_key, coupon);
  }
  Model assemble(const CouponSpec& coupon, const Calibration& calibration) const override {
    PYBIND11_OVERRIDE_PURE(Model, Strategy, assemble, coupon, calibration);
  }
  BoundaryCompletion boundary_completion() const override {
    PYBIND11_OVERRIDE(BoundaryCompletion, Strategy, boundary_completion, );
  }
  std::optional<UnitCell> unit_cell(const Calibration& calibration,
                                    double thickness) const override {
    PYBIND11_OVERRIDE(std::optional<UnitCell>, Strategy, unit_cell, calibration, thickness);
  }
};

// What the registry hands out for a strategy registered from Python: a C++ Strategy that owns a
// reference to the Python instance (so that its Python half lives as long as the library uses it)
// and forwards every virtual to it, which the trampoline above dispatches to Python.
class PythonStrategyHandle : public Strategy {
 public:
  explicit PythonStrategyHandle(py::object instance)
      : instance_(std::move(instance)), strategy_(instance_.cast<Strategy*>()) {}
  PythonStrategyHandle(const PythonStrategyHandle&) = delete;
  PythonStrategyHandle& operator=(const PythonStrategyHandle&) = delete;
  ~PythonStrategyHandle() override {
    // Library code destroys strategies without the GIL; after the interpreter has ended (a
    // handle that outlives it) the reference is left, not dropped.
    if (Py_IsInitialized() == 0) {
      instance_.release();
      return;
    }
    py::gil_scoped_acquire gil;
    instance_ = py::object();
  }

  std::vector<StrategyOption> options() const override { return strategy_->options(); }
  void set_option(const std::string& name, double value) override {
    strategy_->set_option(name, value);
  }
  std::string description() const override { return strategy_->description(); }
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override {
    return strategy_->calibrate(material, ply_angle, thickness);
  }
  Calibration calibrate_coupon(const CouponSpec& coupon) const override {
    return strategy_->calibrate_coupon(coupon);
  }
  std::string calibration_key(const CouponSpec& coupon) const override {
    return strategy_->calibration_key(coupon);
  }
  Model assemble(const CouponSpec& coupon, const Calibration& calibration) const override {
    return strategy_->assemble(coupon, calibration);
  }
  BoundaryCompletion boundary_completion() const override {
    return strategy_->boundary_completion();
  }
  std::optional<UnitCell> unit_cell(const Calibration& calibration,
                                    double thickness) const override {
    return strategy_->unit_cell(calibration, thickness);
  }

 private:
  py::object instance_;
  Strategy* strategy_;
};

// A new instance of a strategy class registered from Python, checked to be a plydem.Strategy.
std::unique_ptr<Strategy> instantiate(const py::object& factory, const std::string& name) {
  py::gil_scoped_acquire gil;
  py::object instance = factory();
  if (!py::isinstance<Strategy>(instance)) {
    throw Error("the factory registered as strategy '" + name + "' returned a " +
                py::str(py::type::of(instance).attr("__name__")).cast<std::string>() +
                ", not a plydem.Strategy");
  }
  return std::make_unique<PythonStrategyHandle>(std::move(instance));
}

// The value of a Calibration that Python reads as a dict (the keys of calibration_dict).
py::object calibration_item(const Calibration& c, const std::string& key) {
  py::dict d = calibration_dict(c);
  if (!d.contains(key)) throw py::key_error(key);
  return d[py::str(key)];
}

py::array matrix6(const Matrix6d& m) {
  py::array_t<double> result({6, 6});
  auto r = result.mutable_unchecked<2>();
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < 6; ++k) r(i, k) = m(i, k);
  return result;
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
          "static solves: 'auto' (by size), 'direct' or 'cholmod'");
}

}  // namespace

void plydem::python::define_module(py::module_& m) {
  m.doc() =
      "plydem: particle (DEM and lattice) models of FRP composite laminae and laminates.\n\n"
      "SI units throughout (m, Pa, N, rad). Arrays of a Model are NumPy views of the C++ arrays.\n"
      "Every error the library raises arrives as plydem.Error with its message.";
  m.attr("__version__") = PLYDEM_VERSION;
  auto& error = py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  error.attr("__doc__") =
      "Bad input or an impossible request (plydem::Error): the message names the problem in the "
      "user's terms, as the command line prints it.";

  // --- materials ------------------------------------------------------------------------------
  py::class_<LaminaStrength>(m, "LaminaStrength",
                             "A ply's strengths [Pa] and fracture energies [J/m^2], 0 = not "
                             "given (core/material.hpp); keywords set them.")
      .def(py::init([](py::kwargs kwargs) { return from_kwargs<LaminaStrength>(kwargs); }),
           "LaminaStrength(XT=..., XC=..., YT=..., YC=..., S12=..., G_fibre=..., G_matrix=..., "
           "weibull_modulus=...)")
      .def_readwrite("XT", &LaminaStrength::XT, "longitudinal tensile strength [Pa]")
      .def_readwrite("XC", &LaminaStrength::XC, "longitudinal compressive strength [Pa]")
      .def_readwrite("YT", &LaminaStrength::YT, "transverse tensile strength [Pa]")
      .def_readwrite("YC", &LaminaStrength::YC, "transverse compressive strength [Pa]")
      .def_readwrite("S12", &LaminaStrength::S12, "in-plane shear strength [Pa]")
      .def_readwrite("G_fibre", &LaminaStrength::G_fibre,
                     "fracture energy of a crack across the fibres [J/m^2]")
      .def_readwrite("G_matrix", &LaminaStrength::G_matrix,
                     "fracture energy of a crack along the fibres [J/m^2]")
      .def_readwrite("weibull_modulus", &LaminaStrength::weibull_modulus,
                     "Weibull modulus of the bonds' strength scatter; 0 = none");
  py::class_<Material>(m, "Material",
                       "A transversely isotropic ply, fibre along local axis 1 (paper Table 1). "
                       "Keywords: name, E1, E2, G12 [Pa], nu12, nu23, density [kg/m^3]; validated "
                       "(positive constants, positive-definite compliance).")
      .def(py::init([](py::kwargs kwargs) {
             Material material = from_kwargs<Material>(kwargs);
             validate(material);
             return material;
           }),
           "Material(name=..., E1=..., E2=..., G12=..., nu12=..., nu23=..., density=2000): raises "
           "plydem.Error unless the constants make a stable ply.")
      .def_readwrite("name", &Material::name, "label for reports")
      .def_readwrite("E1", &Material::E1, "fibre-direction Young's modulus [Pa]")
      .def_readwrite("E2", &Material::E2, "transverse Young's modulus, E3 = E2 [Pa]")
      .def_readwrite("G12", &Material::G12, "in-plane shear modulus, G13 = G12 [Pa]")
      .def_readwrite("nu12", &Material::nu12, "major Poisson's ratio; nu13 = nu12")
      .def_readwrite("nu23", &Material::nu23, "transverse Poisson's ratio")
      .def_readwrite("density", &Material::density, "mass density [kg/m^3]")
      .def_readwrite("strength", &Material::strength,
                     "LaminaStrength: XT, XC, YT, YC, S12 [Pa], G_fibre, G_matrix [J/m^2], "
                     "weibull_modulus (0 = not given)")
      .def_property_readonly("nu21", &Material::nu21, "minor Poisson's ratio nu12 E2 / E1")
      .def_property_readonly("G23", &Material::G23, "transverse shear modulus E2 / (2 (1 + nu23))")
      .def(
          "validate", [](const Material& material) { validate(material); },
          "Raises plydem.Error naming the problem unless the ply is stable.")
      .def("__repr__", [](const Material& x) {
        return "Material(name='" + x.name + "', E1=" + std::to_string(x.E1) +
               ", E2=" + std::to_string(x.E2) + ", G12=" + std::to_string(x.G12) +
               ", nu12=" + std::to_string(x.nu12) + ", nu23=" + std::to_string(x.nu23) + ")";
      });
  m.def("load_material", &load_material, py::arg("name_or_file"),
        "A built-in material by name (see builtin_materials()) or a TOML file with name, E1, E2, "
        "G12, nu12, nu23 [Pa] and optionally density; validated.");
  m.def("builtin_materials", &builtin_material_names, "Names of the built-in materials.");

  // --- coupons --------------------------------------------------------------------------------
  py::class_<CouponSpec>(
      m, "CouponSpec",
      "The coupon a strategy builds: one ply, a rectangle in the x-y plane, long "
      "along x. Keywords: material, ply_angle [rad], length, width, thickness, "
      "particle_diameter [m], complete_boundary_cells.")
      .def(py::init([](py::kwargs kwargs) {
             CouponSpec coupon;
             coupon.material = load_material("eglass-my750");
             coupon = from_kwargs<CouponSpec>(kwargs, coupon);
             coupon.validate();
             return coupon;
           }),
           "CouponSpec(**keywords); the material defaults to eglass-my750, sizes to the paper's "
           "coupon (10 x 0.83 mm, ply 0.2 mm, particles 0.05 mm).")
      .def_readwrite("material", &CouponSpec::material, "the ply's Material")
      .def_readwrite("ply_angle", &CouponSpec::ply_angle, "fibre angle from +x [rad]")
      .def_readwrite("length", &CouponSpec::length, "along x [m]")
      .def_readwrite("width", &CouponSpec::width, "along y [m]")
      .def_readwrite("thickness", &CouponSpec::thickness, "ply thickness delta [m]")
      .def_readwrite("particle_diameter", &CouponSpec::particle_diameter, "[m]")
      .def_readwrite("complete_boundary_cells", &CouponSpec::complete_boundary_cells,
                     "let bonds at free edges carry the share of their missing partners")
      .def("validate", &CouponSpec::validate, "Raises plydem.Error naming a bad size.");

  // --- the model ------------------------------------------------------------------------------
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

  // --- strategies -----------------------------------------------------------------------------
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

  py::class_<Strategy, PyStrategy>(
      m, "Strategy",
      "A packing plus the rule that turns a ply's target stiffness into bond stiffnesses (paper "
      "Sec. 3). Make a registered one with create_strategy(name).\n\n"
      "To write one in Python, subclass it (calling plydem.Strategy.__init__(self) in __init__) "
      "and override description(), calibrate(material, ply_angle, thickness) -> Calibration and "
      "assemble(coupon, calibration) -> Model (assemble_specimen builds one from positions and "
      "bonded pairs); optionally options() -> [StrategyOption], set_option(name, value), "
      "calibrate_coupon(coupon), calibration_key(coupon), boundary_completion() and "
      "unit_cell(calibration, thickness) -> UnitCell (the strength test needs it). Then "
      "register_strategy(name, cls) makes it available by name to every test, and `plydem "
      "tension --plugin FILE.py --strategy NAME` to the command line.")
      .def(py::init<>(), "For subclasses written in Python.")
      .def("description", &Strategy::description, "one line, as `plydem strategies` shows")
      .def(
          "options",
          [](const Strategy& s) {
            py::dict d;
            for (const StrategyOption& o : s.options()) d[py::str(o.name)] = o.value;
            return d;
          },
          "The strategy's options as {name: value}. (A Python strategy overrides it returning a "
          "list of StrategyOption.)")
      .def("option_list", &Strategy::options, "The options with their descriptions.")
      .def("set_option", &Strategy::set_option, py::arg("name"), py::arg("value"),
           "Sets an option; plydem.Error for an unknown name or a value out of range.")
      .def(
          "calibrate",
          [](const Strategy& s, const Material& material, double ply_angle, double thickness) {
            py::gil_scoped_release release;
            return s.calibrate(material, ply_angle, thickness);
          },
          py::arg("material"), py::arg("ply_angle") = 0.0, py::arg("thickness") = 0.2e-3,
          "Bond stiffnesses for a ply at ply_angle [rad] of the given thickness [m]: a "
          "Calibration (method, lattice_angle, families, and target, affine and relaxed as 3x3 "
          "NumPy arrays [Pa], relaxed_error), also readable as a dict.")
      .def(
          "calibrate_coupon",
          [](const Strategy& s, const CouponSpec& coupon) {
            py::gil_scoped_release release;
            return s.calibrate_coupon(coupon);
          },
          py::arg("coupon"), "The calibration the coupon's bonds get (default: calibrate()).")
      .def(
          "calibration_key",
          [](const Strategy& s, const CouponSpec& coupon) { return s.calibration_key(coupon); },
          py::arg("coupon"),
          "Coupons with the same key share a calibration (default: material, ply angle, "
          "thickness, options).")
      .def(
          "assemble",
          [](const Strategy& s, const CouponSpec& coupon, const Calibration& calibration) {
            py::gil_scoped_release release;
            return std::make_shared<Model>(s.assemble(coupon, calibration));
          },
          py::arg("coupon"), py::arg("calibration"),
          "Builds the coupon's particles and bonds with a calibration of its ply: a Model.")
      .def("boundary_completion", &Strategy::boundary_completion,
           "How the coupon's boundary cells are completed (BoundaryCompletion).")
      .def(
          "unit_cell",
          [](const Strategy& s, const Calibration& calibration, double thickness) {
            py::gil_scoped_release release;
            return s.unit_cell(calibration, thickness);
          },
          py::arg("calibration"), py::arg("thickness") = 0.2e-3,
          "The periodic cell the calibration was solved on (UnitCell), or None.")
      .def(
          "build",
          [](const Strategy& s, const CouponSpec& coupon) {
            py::gil_scoped_release release;
            Specimen specimen = s.build(coupon);
            return std::make_shared<Model>(std::move(specimen.model));
          },
          py::arg("coupon"),
          "Calibrates and builds the coupon into a Model (plydem.Error if the calibration's "
          "target is not the coupon's ply Q-bar).");

  m.def(
      "strategies", [] { return default_registry().names(); },
      "Names of the registered strategies.");
  m.def(
      "strategy_description",
      [](const std::string& name) { return default_registry().description(name); }, py::arg("name"),
      "The registered strategy's one-line description.");
  m.def(
      "create_strategy",
      [](const std::string& name, py::kwargs options) {
        std::unique_ptr<Strategy> strategy = default_registry().create(name);
        for (const auto& [key, value] : options) {
          strategy->set_option(py::str(key).cast<std::string>(), value.cast<double>());
        }
        return strategy;
      },
      py::arg("name"),
      "A new instance of the registered strategy `name`, its options set from the keywords; "
      "plydem.Error naming the registered strategies if `name` is unknown.");
  m.def(
      "register_strategy",
      [](const std::string& name, const py::object& factory, py::object description) {
        require(PyCallable_Check(factory.ptr()) != 0,
                "register_strategy('" + name +
                    "', ...) needs a plydem.Strategy subclass (or a "
                    "callable that returns an instance)");
        // One instance now: a factory that cannot make a strategy fails here, not in a test.
        const std::unique_ptr<Strategy> probe = instantiate(factory, name);
        const std::string text =
            description.is_none() ? probe->description() : description.cast<std::string>();
        // The registry keeps the factory for the life of the process: the reference is
        // deliberately never dropped (the registry outlives the interpreter).
        auto* held = new py::object(factory);
        default_registry().add(name, text, [held, name] { return instantiate(*held, name); });
      },
      py::arg("name"), py::arg("strategy"), py::arg("description") = py::none(),
      "Registers a strategy written in Python under `name`: `strategy` is a subclass of "
      "plydem.Strategy (or a callable returning an instance), instantiated for every use. From "
      "then on create_strategy(name), tension_test(strategy=name), strength_test(...) and "
      "`plydem ... --plugin FILE.py --strategy name` use it. plydem.Error if the name is taken "
      "or empty; the description defaults to the instance's description().");

  // --- helpers for strategies written in Python -------------------------------------------------
  m.def("reduced_stiffness", &reduced_stiffness, py::arg("material"),
        "The ply's plane-stress stiffness Q in its own axes (1 along the fibre) [Pa], 3x3.");
  m.def("rotate_reduced_stiffness", &rotate_reduced_stiffness, py::arg("Q"), py::arg("ply_angle"),
        "Q-bar: Q turned by the ply angle [rad] into the specimen frame (x along the coupon).");
  m.def(
      "affine_stiffness",
      [](const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
        return matrix6(affine_stiffness(cell, families));
      },
      py::arg("cell"), py::arg("families"),
      "The eq. (5) lattice sum of the cell with the families' springs (particles move with the "
      "strain, no spin): 6x6 stiffness [Pa], Voigt order 11 22 33 23 13 12.");
  m.def(
      "relaxed_stiffness",
      [](const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
        return matrix6(relaxed_stiffness(cell, families));
      },
      py::arg("cell"), py::arg("families"),
      "The stiffness of the cell with spins and sublattice shifts at minimum energy, what the "
      "engine simulates: 6x6 [Pa].");
  m.def(
      "in_plane_block",
      [](const py::object& stiffness) { return in_plane_block(square_matrix<6>(stiffness, "")); },
      py::arg("stiffness"), "The (xx, yy, xy) block of a 6x6 stiffness: 3x3 [Pa].");
  m.def(
      "relative_difference",
      [](const py::object& a, const py::object& b) {
        return relative_difference(square_matrix<3>(a, "a"), square_matrix<3>(b, "b"));
      },
      py::arg("a"), py::arg("b"), "|a - b|_F / |b|_F of two 3x3 stiffnesses.");
  m.def(
      "assemble_specimen",
      [](const Eigen::Array<double, Eigen::Dynamic, 3>& position, double radius,
         double particle_volume, double density, const Eigen::ArrayXXi& pairs,
         const std::vector<int>& family, double thickness, const std::string& description,
         const std::vector<FamilyCalibration>& families) {
        require(pairs.cols() == 2 || pairs.size() == 0, "pairs must be an (m, 2) integer array");
        SpecimenLayout layout;
        layout.position = position;
        layout.radius = radius;
        layout.particle_volume = particle_volume;
        layout.density = density;
        for (Eigen::Index b = 0; b < pairs.rows(); ++b) {
          layout.pairs.emplace_back(pairs(b, 0), pairs(b, 1));
        }
        require(family.empty() || family.size() == layout.pairs.size(),
                "family has " + std::to_string(family.size()) + " entries for " +
                    std::to_string(layout.pairs.size()) + " pairs");
        for (int f : family) {
          require(f >= 0 && f < static_cast<int>(families.size()),
                  "bond family " + std::to_string(f) + " has no calibration (" +
                      std::to_string(families.size()) + " families given)");
        }
        layout.family = family;
        layout.thickness = thickness;
        layout.description = description;
        py::gil_scoped_release release;
        auto model = std::make_shared<Model>(assemble_specimen(layout, &families));
        model->check_consistency();
        return model;
      },
      py::arg("position"), py::arg("radius"), py::arg("particle_volume"), py::arg("density"),
      py::arg("pairs"), py::arg("family"), py::arg("thickness"), py::arg("description"),
      py::arg("families"),
      "The one specimen assembler (strategies/specimen.hpp) for a packing made in Python: "
      "particles at `position` ((n, 3) [m]) of one radius [m], each standing for "
      "particle_volume [m^3] of ply of `density` [kg/m^3] (mass, solid-sphere inertia), bonds "
      "between the rows of `pairs` ((m, 2) ints) with their geometry, bond b getting the springs "
      "of families[family[b]] (a list of FamilyCalibration, e.g. calibration.families) as a "
      "parallel bond of the particle radius. Grips are set by the tests. Returns a checked "
      "Model.");
  m.def(
      "complete_boundary_cells",
      [](Model& model, int family_count, int bulk_bonds) {
        return complete_boundary_cells(model.particles, model.bonds, family_count, bulk_bonds);
      },
      py::arg("model"), py::arg("family_count"), py::arg("bulk_bonds"),
      "Lets the bonds at free edges carry the share of their missing partners "
      "(strategies/boundary_cells.hpp), for a packing whose bulk particles have bulk_bonds bonds "
      "of each of family_count families; returns the number of bonds changed.");

  // --- laminates ------------------------------------------------------------------------------
  m.def("parse_layup", &parse_layup, py::arg("layup"),
        "A layup string, bottom ply first ('[0/90/0]', '[0/±45/90]s', ...) as angles [rad].");
  m.def(
      "build_laminate",
      [](const Strategy& strategy, const CouponSpec& coupon, const std::string& layup,
         double interface_normal, double interface_shear) {
        LaminateSpec spec;
        spec.coupon = coupon;
        spec.ply_angles = parse_layup(layup);
        spec.interface.normal = interface_normal;
        spec.interface.shear = interface_shear;
        py::gil_scoped_release release;
        Specimen specimen = build_laminate(strategy, spec);
        return std::make_shared<Model>(std::move(specimen.model));
      },
      py::arg("strategy"), py::arg("coupon"), py::arg("layup"), py::arg("interface_normal") = 0.0,
      py::arg("interface_shear") = 0.0,
      "Builds a laminate (paper Sec. 3.5): every ply of `layup` with the coupon's material and "
      "size (its ply_angle ignored), joined by interface bonds [N/m^3 per unit area; 0 = 10 E2/t "
      "and 10 G12/t].");

  // --- static solve ---------------------------------------------------------------------------
  py::class_<DofConstraints>(
      m, "DofConstraints",
      "Prescribed degrees of freedom: one row per particle, columns ux uy uz theta_x theta_y "
      "theta_z [m, rad]; `fixed` and `value` are writable NumPy views.")
      .def(py::init<int>(), py::arg("particles"), "All dofs of `particles` particles free.")
      .def_property_readonly(
          "fixed",
          [](py::object self) {
            DofConstraints& c = self.cast<DofConstraints&>();
            const py::ssize_t rows = c.fixed.rows();
            return py::array(py::dtype::of<bool>(), {rows, py::ssize_t(kDofsPerParticle)},
                             {py::ssize_t(sizeof(bool)), py::ssize_t(sizeof(bool)) * rows},
                             c.fixed.data(), self);
          },
          "which dofs are prescribed (n x 6 bool view)")
      .def_property_readonly(
          "value",
          [](py::object self) {
            DofConstraints& c = self.cast<DofConstraints&>();
            const py::ssize_t rows = c.value.rows();
            const py::ssize_t item = sizeof(double);
            return py::array(py::dtype::of<double>(), {rows, py::ssize_t(kDofsPerParticle)},
                             {item, item * rows}, c.value.data(), self);
          },
          "prescribed values (n x 6 view) [m, rad]")
      .def(
          "fix",
          [](DofConstraints& c, int particle, int dof, double value) {
            c.fix(particle, static_cast<Dof>(dof), value);
          },
          py::arg("particle"), py::arg("dof"), py::arg("value") = 0.0,
          "Prescribes dof (0..5: ux uy uz theta_x theta_y theta_z) of one particle.")
      .def(
          "fix_group",
          [](DofConstraints& c, const Model& model, int group, int dof, double value) {
            return c.fix_group(model.particles, static_cast<BoundaryGroup>(group),
                               static_cast<Dof>(dof), value);
          },
          py::arg("model"), py::arg("group"), py::arg("dof"), py::arg("value") = 0.0,
          "Prescribes dof of every particle whose group is `group` (1 left grip, 2 right grip); "
          "returns how many particles that was.")
      .def("prescribed_count", &DofConstraints::prescribed_count, "number of prescribed dofs");
  m.attr("LEFT_GRIP") = static_cast<int>(BoundaryGroup::kLeftGrip);
  m.attr("RIGHT_GRIP") = static_cast<int>(BoundaryGroup::kRightGrip);
  m.attr("UX") = 0;
  m.attr("UY") = 1;
  m.attr("UZ") = 2;
  m.attr("THETA_X") = 3;
  m.attr("THETA_Y") = 4;
  m.attr("THETA_Z") = 5;

  m.def(
      "solve_static",
      [](Model& model, const DofConstraints& constraints, bool pin_rigid_modes,
         const std::string& method) {
        StaticSettings settings;
        settings.pin_rigid_modes = pin_rigid_modes;
        settings.method = static_method(method);
        StaticResult r;
        {
          py::gil_scoped_release release;
          r = solve_static(model, constraints, settings);
        }
        py::dict d;
        d["method"] = r.method_name;
        d["dofs"] = r.dofs;
        d["free_dofs"] = r.free_dofs;
        d["prescribed_dofs"] = r.prescribed_dofs;
        d["iterations"] = r.iterations;
        d["relative_residual"] = r.relative_residual;
        d["strain_energy"] = r.strain_energy;
        py::array_t<double> reaction({py::ssize_t(r.reaction.rows()), py::ssize_t(6)});
        auto out = reaction.mutable_unchecked<2>();
        for (Eigen::Index i = 0; i < r.reaction.rows(); ++i)
          for (int k = 0; k < 6; ++k) out(i, k) = r.reaction(i, k);
        d["reaction"] = reaction;
        d["pinned"] = static_cast<int>(r.pinned.size());
        d["seconds"] = r.seconds.total();
        return d;
      },
      py::arg("model"), py::arg("constraints"), py::arg("pin_rigid_modes") = false,
      py::arg("method") = "auto",
      "Linear statics (solvers/static_solver.hpp): writes displacement, rotation, force and "
      "torque into the model's arrays (the views see them) and returns a dict with method, dofs, "
      "free_dofs, prescribed_dofs, iterations, relative_residual, strain_energy [J], reaction "
      "(n x 6 [N, N m]), pinned and seconds. method: auto, direct or iterative. pin_rigid_modes "
      "fixes the dofs that would leave a rigid-body mode free (at zero, carrying no force).");

  // --- explicit dynamics ----------------------------------------------------------------------
  py::class_<PrescribedMotion>(
      m, "PrescribedMotion",
      "Velocities imposed on every particle of a boundary group; components whose fix_* flag is "
      "False stay free. Keywords: group, velocity [m/s], angular_velocity [rad/s], fix_velocity, "
      "fix_angular_velocity (three booleans each).")
      .def(py::init([](py::kwargs kwargs) { return from_kwargs<PrescribedMotion>(kwargs); }),
           "PrescribedMotion(**keywords)")
      .def_property(
          "group", [](const PrescribedMotion& x) { return static_cast<int>(x.group); },
          [](PrescribedMotion& x, int g) { x.group = static_cast<BoundaryGroup>(g); },
          "the boundary group (LEFT_GRIP, RIGHT_GRIP)")
      .def_readwrite("velocity", &PrescribedMotion::velocity, "[m/s]")
      .def_readwrite("angular_velocity", &PrescribedMotion::angular_velocity, "[rad/s]")
      .def_readwrite("fix_velocity", &PrescribedMotion::fix_velocity, "which components are set")
      .def_readwrite("fix_angular_velocity", &PrescribedMotion::fix_angular_velocity,
                     "which components are set");

  py::class_<PyIntegrator>(
      m, "ExplicitIntegrator",
      "Damped central differences on a Model (solvers/explicit_integrator.hpp): the same bond "
      "law as the static solve, PFC local damping, prescribed motions of boundary groups.")
      .def(py::init(
               [](std::shared_ptr<Model> model, double damping, double safety, double time_step) {
                 ExplicitSettings settings;
                 settings.local_damping = damping;
                 settings.safety_factor = safety;
                 settings.time_step = time_step;
                 return std::make_unique<PyIntegrator>(std::move(model), settings);
               }),
           py::arg("model"), py::arg("damping") = 0.7, py::arg("safety") = 0.8,
           py::arg("time_step") = 0.0,
           "ExplicitIntegrator(model, damping=0.7, safety=0.8, time_step=0): time_step 0 = "
           "safety times the critical step. Raises plydem.Error for bad settings or model.")
      .def_property_readonly(
          "time_step", [](const PyIntegrator& x) { return x.integrator.time_step(); }, "[s]")
      .def_property_readonly(
          "time", [](const PyIntegrator& x) { return x.integrator.time(); }, "[s]")
      .def_property_readonly(
          "cycles", [](const PyIntegrator& x) { return x.integrator.cycles(); }, "cycles so far")
      .def(
          "set_prescribed_motions",
          [](PyIntegrator& x, const std::vector<PrescribedMotion>& motions) {
            x.integrator.set_prescribed_motions(motions);
          },
          py::arg("motions"),
          "Replaces the prescribed motions (a list of PrescribedMotion); allowed from a callback.")
      .def(
          "breaks",
          [](const PyIntegrator& x) {
            py::list list;
            for (const BondBreak& b : x.integrator.breaks()) {
              py::dict d;
              d["bond"] = b.bond;
              d["mode"] = mode_name(b.mode);
              d["time"] = b.at;
              d["load"] = b.load;
              d["position"] = py::make_tuple(b.position.x(), b.position.y(), b.position.z());
              list.append(d);
            }
            return list;
          },
          "The bonds broken so far, in order: a list of dicts with bond (row in model.bonds), "
          "mode ('tension' or 'shear'), time [s], load and position (the contact point [m]). "
          "The model's bonds.state and bonds.damage show them after run() or gather().")
      .def(
          "energy",
          [](const PyIntegrator& x) {
            const EnergyAccount e = x.integrator.energy();
            py::dict d;
            d["initial"] = e.initial;
            d["boundary_work"] = e.boundary_work;
            d["strain_energy"] = e.strain_energy;
            d["kinetic_energy"] = e.kinetic_energy;
            d["damping"] = e.damping;
            d["released"] = e.released;
            d["contact_energy"] = e.contact_energy;
            d["friction"] = e.friction;
            d["balance"] = e.balance();
            return d;
          },
          "The run's energy account [J] (kept when the model can break, or with the setting): "
          "initial, boundary_work, strain_energy, kinetic_energy, damping, released (by breaking "
          "and softening bonds), contact_energy, friction, and balance = initial + boundary_work "
          "- the rest.")
      .def(
          "gather",
          [](PyIntegrator& x) {
            std::vector<int> all(static_cast<std::size_t>(x.model->particles.size()));
            for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
            x.integrator.gather(all, x.model->particles);
          },
          "From a callback: copies the current state (displacement, rotation, velocities, force, "
          "torque) into the model's arrays, so that its NumPy views show it. After run() the "
          "model holds the state anyway.")
      .def(
          "run",
          [](PyIntegrator& x, long max_cycles, double tolerance, double time_limit,
             long check_interval, py::object callback) {
            RunControl control;
            control.max_cycles = max_cycles;
            control.tolerance = tolerance;
            control.time_limit_seconds = time_limit;
            control.check_interval = check_interval;
            // Every check takes the GIL: for the callback, and to honour Ctrl-C (the
            // KeyboardInterrupt ends the run with the model written back).
            control.on_check = [&callback](const RunCheck& check) {
              py::gil_scoped_acquire acquire;
              if (PyErr_CheckSignals() != 0) throw py::error_already_set();
              if (callback.is_none()) return true;
              py::object answer = callback(check_dict(check));
              return answer.is_none() || answer.cast<bool>();
            };
            RunReport r;
            {
              py::gil_scoped_release release;
              r = x.integrator.run(control);
            }
            py::dict d;
            d["cycles"] = r.cycles;
            d["checks"] = r.checks;
            d["stop"] = std::string(to_string(r.stop));
            d["strain_energy"] = r.last.strain_energy;
            d["kinetic_energy"] = r.last.kinetic_energy;
            d["unbalanced_force_ratio"] = r.last.unbalanced_force_ratio;
            d["wall_seconds"] = r.wall_seconds;
            return d;
          },
          py::arg("max_cycles") = 0, py::arg("tolerance") = 0.0, py::arg("time_limit") = 0.0,
          py::arg("check_interval") = 1000, py::arg("callback") = py::none(),
          "Cycles until a stop condition holds (at least one of max_cycles, tolerance on the "
          "unbalanced-force ratio, time_limit [s]); callback(check) is called every "
          "check_interval cycles with a dict (cycles, run_cycles, strain_energy, kinetic_energy, "
          "unbalanced_force_ratio, elapsed_seconds, seconds_left) and stops the run by returning "
          "False. The GIL is released between checks; Ctrl-C stops the run. Returns a dict with "
          "cycles, checks, stop ('quasi-static', 'cycle limit', 'time limit', 'hook'), the last "
          "cycle's energies and ratio, wall_seconds.");

  // --- the tension test -----------------------------------------------------------------------
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

  // --- the strength test ----------------------------------------------------------------------
  py::class_<StrengthSettings> strength_settings(
      m, "StrengthSettings",
      "The tension test to failure (`plydem strength`), with the command line's defaults (its "
      "strategy: square); "
      "keywords set the attributes below. Angles in radians, sizes in metres, strengths in Pa.");
  def_coupon_settings(strength_settings);
  strength_settings
      .def(py::init([](py::kwargs kwargs) {
             StrengthSettings settings;
             settings.coupon.material = load_material("eglass-my750");
             return from_kwargs<StrengthSettings>(kwargs, settings);
           }),
           "StrengthSettings(**keywords): the command line's defaults, changed by the keywords.")
      .def_property(
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
          "GIc + (GIIc - GIc) B^eta (softening bonds)")
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

  // --- output ---------------------------------------------------------------------------------
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
