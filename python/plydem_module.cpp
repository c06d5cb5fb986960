/// \file
/// `import plydem`: the extension module (python/bindings.hpp defines its contents).
///
///   PYTHONPATH=build/python /usr/bin/python3 -c "import plydem; print(plydem.strategies())"
#include "python/bindings.hpp"

PYBIND11_MODULE(plydem, m) {
  plydem::python::define_module(m);
}
