#pragma once
/// \file
/// The definition of the `plydem` Python module, in one function, so that two hosts can define it:
/// the extension module `plydem` that `import plydem` loads into a Python interpreter
/// (python/plydem_module.cpp), and the interpreter the command line embeds for `--plugin FILE.py`
/// (experiments/cli/python_plugin.cpp), whose plug-ins register strategies into the command line's
/// own registry.
#include <pybind11/pybind11.h>

namespace plydem::python {

/// Adds every class and function of `import plydem` to `m`.
void define_module(pybind11::module_& m);

}  // namespace plydem::python
