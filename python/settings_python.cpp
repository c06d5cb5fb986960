#include "python/settings_python.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "experiments/runner/settings_descriptions.hpp"
#include "experiments/runner/settings_reference.hpp"

namespace plydem::python {

py::object setting_to_python(const SettingValue& value) {
  struct ToPython {
    py::object operator()(std::monostate) const { return py::none(); }
    py::object operator()(bool b) const { return py::bool_(b); }
    py::object operator()(long i) const { return py::int_(i); }
    py::object operator()(double x) const { return py::float_(x); }
    py::object operator()(const std::string& s) const { return py::str(s); }
    py::object operator()(const std::vector<std::string>& list) const { return py::cast(list); }
  };
  return std::visit(ToPython{}, value);
}

namespace {

// The Python value as the setting's type, or a TypeError.
SettingValue python_value(const SettingInfo& info, const py::handle& value,
                          const std::string& what) {
  const auto wrong = [&](const char* expected) {
    return py::type_error(fmt::format("{} must be {}, got {}", what, expected,
                                      py::str(py::type::of(value)).cast<std::string>()));
  };
  if (value.is_none()) {
    if (info.optional) return std::monostate{};
    throw wrong("set (None means nothing here)");
  }
  switch (info.type) {
    case SettingType::kSwitch:
      if (!py::isinstance<py::bool_>(value)) throw wrong("True or False");
      return value.cast<bool>();
    case SettingType::kInteger:
      if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value))
        throw wrong("an int");
      return value.cast<long>();
    case SettingType::kNumber:
      if (!py::isinstance<py::float_>(value) && !py::isinstance<py::int_>(value))
        throw wrong("a number");
      return value.cast<double>();
    case SettingType::kText:
      if (!py::isinstance<py::str>(value)) throw wrong("a str");
      return value.cast<std::string>();
    case SettingType::kTexts:
      return value.cast<std::vector<std::string>>();
  }
  return std::monostate{};
}

}  // namespace

SettingValue setting_from_python(const SettingInfo& info, const py::handle& value,
                                 const std::string& what) {
  const SettingValue v = python_value(info, value, what);
  if (const double* x = std::get_if<double>(&v)) {
    // Checked in the edge's unit, set in SI as given (a round trip would change its last bits).
    (void)setting_struct_value(info, info.unit.si_to_edge(*x), what);
    return v;
  }
  if (std::holds_alternative<bool>(v)) return v;  // Python has the struct's sense
  return setting_struct_value(info, v, what);
}

std::string python_setting_doc(const SettingInfo& info, const std::string& help) {
  std::string doc = help_with_unit(help, info.unit.si.empty() ? "" : "[" + info.unit.si + "]");
  if (info.choices) {
    std::vector<std::string> quoted;
    for (const std::string& c : info.choices()) quoted.push_back("'" + c + "'");
    doc += fmt::format("; one of {}", fmt::join(quoted, ", "));
  }
  if (info.optional) doc += "; None = " + info.unset;
  if (info.edge_inverts) doc += fmt::format(" (this attribute: the negation of {})", info.flag);
  return doc;
}

RunSettings run_settings_from_kwargs(py::kwargs& kwargs) {
  const SettingsDescription<RunSettings>& d = run_settings_description();
  RunSettings run = d.defaults();
  for (const SettingField<RunSettings>& f : d.fields()) {
    if (f.python.empty() || !kwargs.contains(f.python)) continue;
    f.set(run, setting_from_python(f, kwargs[py::str(f.python)], f.python), f.python);
    PyDict_DelItemString(kwargs.ptr(), f.python.c_str());
  }
  return run;
}

}  // namespace plydem::python
