// A strategy of your own, registered from outside the library.
//
// plydem's strategies are objects found by name in a registry (strategies/registry.hpp). This
// folder defines one, `hex2d-affine` (affine_hex2d_strategy.hpp), and uses it twice, with nothing
// in plydem edited or recompiled:
//   - custom_strategy.cpp (this file): a program of its own that adds the strategy to the
//     registry in its main() and runs the library's tension test with it;
//   - plugin.cpp: a plug-in, a shared library that the installed `plydem` command loads with
//     `--plugin` (or PLYDEM_PLUGIN_PATH), after which every command knows the strategy.
// CMakeLists.txt builds both against an installed plydem (find_package(plydem); docs/install.md),
// or inside plydem's own build tree.
//
// Sample runs:
//   build/examples/custom_strategy                    # 0 deg ply, the paper's coupon
//   build/examples/custom_strategy --angle 30 --length-mm 4 --width-mm 1
//   plydem --plugin build/examples/libcustom_strategy_plugin.so tension --strategy hex2d-affine
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <numbers>

#include "core/error.hpp"
#include "experiments/output/report.hpp"
#include "experiments/protocols/tension.hpp"
#include "strategies/registry.hpp"

#include "affine_hex2d_strategy.hpp"

int main(int argc, char** argv) {
  double angle_deg = 0, length_mm = 10, width_mm = 0.83;
  CLI::App app{"tension test with a user-registered strategy, hex2d-affine"};
  app.add_option("--angle", angle_deg, "ply angle [deg]")->capture_default_str();
  app.add_option("--length-mm", length_mm, "coupon length [mm]")->capture_default_str();
  app.add_option("--width-mm", width_mm, "coupon width [mm]")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    // The one line that makes a strategy available to every experiment and to `--strategy`.
    plydem::default_registry().add("hex2d-affine", custom::AffineHex2dStrategy().description(),
                                   [] { return std::make_unique<custom::AffineHex2dStrategy>(); });

    plydem::TensionSettings settings;
    settings.strategy = "hex2d-affine";
    settings.coupon.material = plydem::load_material("eglass-my750");
    settings.coupon.ply_angle = angle_deg * std::numbers::pi / 180;
    settings.coupon.length = length_mm * 1e-3;
    settings.coupon.width = width_mm * 1e-3;
    const plydem::TensionResult result = plydem::TensionTest(settings).run();
    std::cout << plydem::format_tension_table(result, settings);
    return 0;
  } catch (const plydem::Error& e) {
    std::cerr << "custom_strategy: error: " << e.what() << "\n";
    return 2;
  }
}
