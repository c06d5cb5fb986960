#pragma once
/// \file
/// The tension kind (`plydem run experiments/NAME.toml` with `experiment = "tension"`): one
/// tension test as `plydem tension` runs it, from a config whose keys are the command's settings
/// (tension_run_description(), docs/settings.md), and CalculiX of the same coupon beside it with
/// `fem.same_coupon = true`. Its section: the table `plydem tension` prints (and the same-coupon
/// table); results.csv: Ex, Ey, nu_xy, nu_yx, Gxy of the DEM (source `dem STRATEGY`), of CLT
/// (`clt`) and of CalculiX (`calculix`), moduli in GPa.
///
///   experiment = "tension"
///   strategy = "hex2d"     angle_deg = 30     layup = "[0/90]s"     solver = "static"
///   [coupon] length_mm, width_mm, thickness_mm, diameter_mm, grips, grip_mm, gauge_fraction
///   [explicit] load_stages, ramp_cycles, cycles, max_cycles, tolerance, damping, safety, backend
///   [fem] same_coupon, element_mm, elements_per_ply, threads

#include "experiments/output/report.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/settings_descriptions.hpp"

namespace plydem {

/// Registers `tension` (CMake list PLYDEM_EXPERIMENTS entry `tension`).
void register_tension_experiment(ExperimentRegistry& registry);

/// CalculiX of the coupons `result` pulled (fem_twin_tension_test with run.twin), as the table
/// beside the DEM shows it. Throws plydem::Error when run.twin.executable is not found (naming the
/// Debian package) or the FEM fails.
SameCouponReference same_coupon_fem(const TensionRun& run, const TensionResult& result);

}  // namespace plydem
