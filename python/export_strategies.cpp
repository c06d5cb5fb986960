/// \file
/// plydem.Strategy, which Python code may subclass, and the strategy registry from Python:
/// strategies(), strategy_description(), create_strategy() and register_strategy(), whose
/// strategies the library then uses as it uses its own.
#include "python/export.hpp"

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"
#include "strategies/strategy.hpp"

namespace plydem::python {

namespace {

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

}  // namespace

void export_strategy(py::module_& m) {
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
}

void export_registry(py::module_& m) {
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
}

}  // namespace plydem::python
