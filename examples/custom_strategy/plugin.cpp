// The plug-in of this example: a shared library that registers hex2d-affine
// (affine_hex2d_strategy.hpp) into the registries of the `plydem` program that loads it:
//
//   plydem --plugin build/examples/libcustom_strategy_plugin.so strategies
//   plydem --plugin build/examples/libcustom_strategy_plugin.so tension --strategy hex2d-affine
//   PLYDEM_PLUGIN_PATH=build/examples plydem tension --strategy hex2d-affine --angle 30
//
// It links only plydem::plugin (headers): the plydem code it calls is the program's own.
// PLYDEM_PLUGIN records the plydem version it was built against, which the loader checks.
#include <memory>

#include "experiments/runner/plugin.hpp"

#include "affine_hex2d_strategy.hpp"

namespace {

void register_hex2d_affine(plydem::PluginRegistries& registries) {
  registries.strategies.add("hex2d-affine", custom::AffineHex2dStrategy().description(),
                            [] { return std::make_unique<custom::AffineHex2dStrategy>(); });
}

}  // namespace

PLYDEM_PLUGIN(register_hex2d_affine)
