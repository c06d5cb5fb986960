/// \file
/// `import plydem`: the library from Python (pybind11). Materials, the strategy registry and its
/// calibrations, ply coupons and laminates built into a Model whose particle and bond arrays are
/// NumPy views of the C++ arrays (no copy), the static solve, the tension test (the same dict as
/// `plydem tension --json`) and VTU output. Every plydem::Error arrives as plydem.Error with the
/// library's message. The GIL is released while C++ works.
///
///   PYTHONPATH=build/python /usr/bin/python3 -c "import plydem; print(plydem.strategies())"
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/model.hpp"
#include "experiments/output/report.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/tension_test.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"
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
// check_consistency): the state and the boundary groups, and the bonds' stiffnesses (zero breaks a
// bond). Topology, reference geometry, masses and kinds are read-only.
bool writable_particle_field(const std::string& name) {
  return name == "displacement" || name == "velocity" || name == "rotation" ||
         name == "angular_velocity" || name == "force" || name == "torque" || name == "group";
}
bool writable_bond_field(const std::string& name) {
  return name == "normal_stiffness" || name == "shear_stiffness" || name == "bending_stiffness" ||
         name == "twisting_stiffness";
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

}  // namespace

PYBIND11_MODULE(plydem, m) {
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
      .def_readonly("name", &StrategyOption::name, "the option's name, as set_option takes it")
      .def_readonly("value", &StrategyOption::value, "its current value")
      .def_readonly("description", &StrategyOption::description, "one line, with the unit");

  py::class_<Strategy>(m, "Strategy",
                       "A packing plus the rule that turns a ply's target stiffness into bond "
                       "stiffnesses (paper Sec. 3). Make one with create_strategy(name).")
      .def("description", &Strategy::description, "one line, as `plydem strategies` shows")
      .def(
          "options",
          [](const Strategy& s) {
            py::dict d;
            for (const StrategyOption& o : s.options()) d[py::str(o.name)] = o.value;
            return d;
          },
          "The strategy's options as {name: value}.")
      .def("option_list", &Strategy::options, "The options with their descriptions.")
      .def("set_option", &Strategy::set_option, py::arg("name"), py::arg("value"),
           "Sets an option; plydem.Error for an unknown name or a value out of range.")
      .def(
          "calibrate",
          [](const Strategy& s, const Material& material, double ply_angle, double thickness) {
            Calibration c;
            {
              py::gil_scoped_release release;
              c = s.calibrate(material, ply_angle, thickness);
            }
            return calibration_dict(c);
          },
          py::arg("material"), py::arg("ply_angle") = 0.0, py::arg("thickness") = 0.2e-3,
          "Bond stiffnesses for a ply at ply_angle [rad] of the given thickness [m]: a dict with "
          "method, lattice_angle, families (label, direction, normal, shear, bending, twisting) "
          "and the plane-stress stiffnesses target (Q-bar), affine (eq. 5) and relaxed as 3x3 "
          "NumPy arrays [Pa], and relaxed_error.")
      .def(
          "build",
          [](const Strategy& s, const CouponSpec& coupon) {
            py::gil_scoped_release release;
            Specimen specimen = s.build(coupon);
            return std::make_shared<Model>(std::move(specimen.model));
          },
          py::arg("coupon"), "Calibrates and builds the coupon into a Model.");

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
  py::class_<TensionSettings>(
      m, "TensionSettings",
      "The virtual uniaxial tension test (paper Secs. 3.4 and 4), as `plydem tension` sets it "
      "up; keywords set the attributes below. Angles in radians, sizes in metres.")
      .def(py::init([](py::kwargs kwargs) {
             TensionSettings settings;
             settings.coupon.material = load_material("eglass-my750");
             return from_kwargs<TensionSettings>(kwargs, settings);
           }),
           "TensionSettings(**keywords): the command line's defaults, changed by the keywords.")
      .def_readwrite("strategy", &TensionSettings::strategy, "registered strategy name")
      .def_readwrite("strategy_options", &TensionSettings::strategy_options,
                     "list of (name, value), applied in order before calibration")
      .def_readwrite("coupon", &TensionSettings::coupon, "material, ply angle and size")
      .def_readwrite("layup", &TensionSettings::layup,
                     "ply angles of a laminate, bottom to top [rad]; empty = one ply")
      .def_property(
          "interface_normal", [](const TensionSettings& s) { return s.interface.normal; },
          [](TensionSettings& s, double v) { s.interface.normal = v; },
          "interface normal stiffness per unit area [N/m^3]; 0 = 10 E2/t")
      .def_property(
          "interface_shear", [](const TensionSettings& s) { return s.interface.shear; },
          [](TensionSettings& s, double v) { s.interface.shear = v; },
          "interface shear stiffness per unit area [N/m^3]; 0 = 10 G12/t")
      .def_readwrite("grip_length", &TensionSettings::grip_length, "[m]; 0 = two diameters")
      .def_readwrite("gauge_fraction", &TensionSettings::gauge_fraction,
                     "central fraction of the length measured")
      .def_readwrite("edge_band_diameters", &TensionSettings::edge_band_diameters,
                     "gauge particles this many diameters from a free edge are left out")
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
        nlohmann::json json;
        {
          py::gil_scoped_release release;
          const TensionResult result = TensionTest(settings).run();
          json = tension_json(result, settings);
        }
        return to_python(json);
      },
      py::arg("settings") = py::none(),
      "Runs the tension test (TensionSettings, or its keywords) and returns the dict `plydem "
      "tension --json` prints: Ex, Ey, nu_xy, nu_yx, theory, particles, bonds, wall_seconds, ...");

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
