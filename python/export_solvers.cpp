/// \file
/// The solvers from Python: plydem.DofConstraints and solve_static (linear statics), and
/// plydem.PrescribedMotion and plydem.ExplicitIntegrator (damped explicit dynamics with a
/// callback at every check).
#include "python/export.hpp"

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "solvers/device_backend.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/static_solver.hpp"

namespace plydem::python {

namespace {

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

// ExplicitIntegrator.breaks(): the bonds broken so far as a list of dicts.
py::list breaks_list(const PyIntegrator& x) {
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
}

// ExplicitIntegrator.energy(): the run's energy account as a dict.
py::dict energy_dict(const PyIntegrator& x) {
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
}

// ExplicitIntegrator.run(): cycles with the callback at every check, the GIL released between.
py::dict run_integrator(PyIntegrator& x, long max_cycles, double tolerance, double time_limit,
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
}

}  // namespace

void export_dof_constraints(py::module_& m) {
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
}

void export_static_solve(py::module_& m) {
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
}

void export_prescribed_motion(py::module_& m) {
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
}

void export_explicit_integrator(py::module_& m) {
  py::class_<PyIntegrator>(
      m, "ExplicitIntegrator",
      "Damped central differences on a Model (solvers/explicit_integrator.hpp): the same bond "
      "law as the static solve, PFC local damping, prescribed motions of boundary groups.")
      .def(py::init([](std::shared_ptr<Model> model, double damping, double safety,
                       double time_step, const std::string& backend) {
             ExplicitSettings settings;
             settings.local_damping = damping;
             settings.safety_factor = safety;
             settings.time_step = time_step;
             settings.backend = parse_backend_choice(backend);
             return std::make_unique<PyIntegrator>(std::move(model), settings);
           }),
           py::arg("model"), py::arg("damping") = 0.7, py::arg("safety") = 0.8,
           py::arg("time_step") = 0.0, py::arg("backend") = "cpu",
           (std::string("ExplicitIntegrator(model, damping=0.7, safety=0.8, time_step=0, "
                        "backend='cpu'): time_step 0 = safety times the critical step; backend: "
                        "where the cycles run, ") +
            backend_choices_help(true) + ". Raises plydem.Error for bad settings or model.")
               .c_str())
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
      .def("breaks", &breaks_list,
           "The bonds broken so far, in order: a list of dicts with bond (row in model.bonds), "
           "mode ('tension' or 'shear'), time [s], load and position (the contact point [m]). "
           "The model's bonds.state and bonds.damage show them after run() or gather().")
      .def("energy", &energy_dict,
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
      .def("run", &run_integrator, py::arg("max_cycles") = 0, py::arg("tolerance") = 0.0,
           py::arg("time_limit") = 0.0, py::arg("check_interval") = 1000,
           py::arg("callback") = py::none(),
           "Cycles until a stop condition holds (at least one of max_cycles, tolerance on the "
           "unbalanced-force ratio, time_limit [s]); callback(check) is called every "
           "check_interval cycles with a dict (cycles, run_cycles, strain_energy, kinetic_energy, "
           "unbalanced_force_ratio, elapsed_seconds, seconds_left) and stops the run by returning "
           "False. The GIL is released between checks; Ctrl-C stops the run. Returns a dict with "
           "cycles, checks, stop ('quasi-static', 'cycle limit', 'time limit', 'hook'), the last "
           "cycle's energies and ratio, wall_seconds.");
}

}  // namespace plydem::python
