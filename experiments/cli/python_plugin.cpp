#include "experiments/cli/python_plugin.hpp"

#include <filesystem>
#include <memory>

#include "core/error.hpp"

#ifdef PLYDEM_EMBED_PYTHON
#include <pybind11/embed.h>

#include "python/bindings.hpp"

namespace py = pybind11;

// `import plydem` inside the embedded interpreter: a built-in module, found before any plydem
// extension on sys.path, so that a plug-in registers into this program's registry.
PYBIND11_EMBEDDED_MODULE(plydem, m) {
  plydem::python::define_module(m);
}
#endif

namespace plydem::cli {

#ifdef PLYDEM_EMBED_PYTHON
namespace {

// The interpreter, started by the first plug-in and ended when the program exits.
std::unique_ptr<py::scoped_interpreter>& interpreter() {
  static std::unique_ptr<py::scoped_interpreter> instance;
  return instance;
}

}  // namespace

bool python_plugins_available() {
  return true;
}

void load_python_plugin(const std::string& file) {
  const std::filesystem::path path(file);
  require(std::filesystem::is_regular_file(path),
          "--plugin " + file + ": no such file (a Python file that registers strategies)");
  if (!interpreter()) interpreter() = std::make_unique<py::scoped_interpreter>();
  try {
    const std::string absolute = std::filesystem::absolute(path).string();
    py::module_::import("sys").attr("path").attr("insert")(
        0, std::filesystem::absolute(path).parent_path().string());
    py::dict globals;
    globals["__builtins__"] = py::module_::import("builtins");
    globals["__name__"] = "__plydem_plugin__";
    globals["__file__"] = absolute;
    py::eval_file(absolute, globals);
  } catch (py::error_already_set& e) {
    throw Error("--plugin " + file + " raised " + std::string(e.what()));
  }
}

int run_with_plugins(const std::function<int()>& command) {
  if (!interpreter()) return command();
  py::gil_scoped_release release;
  try {
    return command();
  } catch (py::error_already_set& e) {
    py::gil_scoped_acquire gil;
    throw Error("a Python plug-in's strategy raised " + std::string(e.what()));
  }
}

#else

bool python_plugins_available() {
  return false;
}

void load_python_plugin(const std::string& file) {
  throw Error("--plugin needs Python for " + file +
              ", and this plydem was built without it (the sanitizer build, or no pybind11 and "
              "Python headers when it was configured: scripts/setup installs pybind11-dev and "
              "python3-dev)");
}

int run_with_plugins(const std::function<int()>& command) {
  return command();
}

#endif

}  // namespace plydem::cli
