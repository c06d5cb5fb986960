#pragma once
/// \file
/// Python's edge of the settings descriptions (core/settings.hpp): def_settings binds every field
/// of a description that has a plain Python name as a property of the class (its docstring the
/// help, with the SI unit, the choices and the range), checked as the other edges check it; the
/// fields whose Python attribute is the struct's own member (python_native: a Material, a list of
/// radians) and the dotted ones (an attribute of an attribute, coupon.length) are bound by their
/// own classes. run_settings_from_kwargs takes the run's settings (threads, petsc_options) from a
/// function's keywords.

#include <deque>
#include <string>

#include "core/settings.hpp"
#include "experiments/protocols/run_settings.hpp"
#include "python/export.hpp"

namespace plydem::python {

/// A value as Python has it (None when unset).
py::object setting_to_python(const SettingValue& value);
/// A Python value as the struct takes it (SI; not converted), checked as the other edges check
/// it (the choices, the range, a finite number); `what` names it in errors. TypeError for a value
/// of the wrong type.
SettingValue setting_from_python(const SettingInfo& info, const py::handle& value,
                                 const std::string& what);
/// The docstring of a field whose help is `help` (its settings named as Python names them).
std::string python_setting_doc(const SettingInfo& info, const std::string& help);
/// The run's settings (threads, petsc_options) given as keywords, removed from `kwargs`.
RunSettings run_settings_from_kwargs(py::kwargs& kwargs);

/// Binds the fields of `d` with a plain Python name as properties of `cls`.
template <class S, class... Options>
void def_settings(py::class_<S, Options...>& cls, const SettingsDescription<S>& d) {
  static std::deque<std::string> docs;  // pybind11 keeps the pointers
  for (const SettingField<S>& f : d.fields()) {
    if (f.python.empty() || f.python_native || f.python.find('.') != std::string::npos) continue;
    const SettingField<S>* field = &f;
    docs.push_back(
        python_setting_doc(f, render_setting_reason(f.help, SettingEdge::kPython, d.finder())));
    cls.def_property(
        f.python.c_str(), [field](const S& s) { return setting_to_python(field->get(s)); },
        [field](S& s, const py::object& value) {
          field->set(s, setting_from_python(*field, value, field->python), field->python);
        },
        docs.back().c_str());
  }
}

}  // namespace plydem::python
