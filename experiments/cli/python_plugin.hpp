#pragma once
/// \file
/// Python plug-ins for the command line: `plydem --plugin FILE.py ...` runs FILE.py in an
/// interpreter embedded in this program, whose `import plydem` is this program's own library (the
/// module python/bindings.hpp defines), so that the strategies a plug-in registers with
/// plydem.register_strategy are in the registry every command uses:
///
///   plydem tension --plugin examples/python/custom_packing.py --strategy py-square --angle 30
///
/// Built when the Python module is (pybind11 found, not the sanitizer build); elsewhere
/// `--plugin FILE.py` is refused with the reason. experiments/cli/plugins.hpp chooses between
/// these and the C++ plug-ins (`--plugin libNAME.so`) by the file's extension.
#include <functional>
#include <string>

namespace plydem::cli {

/// Whether this program can run Python plug-ins.
bool python_plugins_available();

/// Runs `file` in the embedded interpreter (started on first use, alive until the program ends)
/// with `__file__` set and its folder first on sys.path. Throws plydem::Error naming a missing
/// file, the exception the file raised (with its traceback), or a build without Python.
void load_python_plugin(const std::string& file);

/// Runs `command` with Python's lock released, so that the library may call a plug-in's
/// strategies from any thread (each call takes the lock), and turns a Python exception raised
/// inside them into plydem::Error. Without plug-ins loaded it just runs `command`.
int run_with_plugins(const std::function<int()>& command);

}  // namespace plydem::cli
