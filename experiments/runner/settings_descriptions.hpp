#pragma once
/// \file
/// The settings descriptions (core/settings.hpp): every setting of the tests plydem runs, declared
/// once with its name at each edge, unit, default, range, help and conditions. The command line
/// (experiments/cli/settings_cli.hpp), the experiment configs (settings_config.hpp), Python
/// (python/settings_python.hpp) and docs/settings.md (settings_reference.hpp) are generated from
/// them. A setting added here appears at every edge it names.
///
/// The edges' names that existed before the descriptions are kept as they were (users' scripts
/// rely on them); where they differ between edges the description states both (--length-mm,
/// coupon.length_mm [mm]; Python coupon.length [m]).

#include <string>
#include <vector>

#include "core/settings.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/protocols/dcb.hpp"
#include "experiments/protocols/run_settings.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/protocols/tension.hpp"

namespace plydem {

/// `plydem tension` and the kind `tension`: the tension test, and CalculiX of the same coupon
/// beside it (fem_twin_tension_test).
struct TensionRun {
  TensionSettings test;
  bool fem = false;  ///< also run CalculiX of the same coupon
  FemTwinSettings twin;
};

/// threads, petsc_options: every command, every kind (top-level keys), Python's tension_test()
/// and strength_test() keywords.
const SettingsDescription<RunSettings>& run_settings_description();
/// The coupon's material, ply angle, size and edges (CouponSpec; Python's plydem.CouponSpec).
const SettingsDescription<CouponSpec>& coupon_settings_description();
/// TensionSettings (Python's plydem.TensionSettings): the coupon, the laminate, the loading, the
/// explicit solver, the linear solver, checkpoints. Defaults: the command line's (the paper's
/// 0 deg E-glass/MY750 coupon, hex2d).
const SettingsDescription<TensionSettings>& tension_settings_description();
/// TensionRun: `plydem tension` and the kind `tension` (the test's settings and --fem's).
const SettingsDescription<TensionRun>& tension_run_description();
/// StrengthSettings (`plydem strength`, the kinds strength, crossply and hole_failure, Python's
/// plydem.StrengthSettings). Defaults: the command line's (square).
const SettingsDescription<StrengthSettings>& strength_settings_description();
/// DcbSettings (the kind dcb).
const SettingsDescription<DcbSettings>& dcb_settings_description();

/// The settings of tension_settings_description() that `plydem calibrate` takes.
SettingsSelection calibrate_selection();

/// The explicit backends (backend_choices()) described: "cpu (SIMD kernel, OpenMP threads) or
/// cuda (...)"; `quoted`: each name in single quotes, as Python writes strings.
std::string backend_choices_help(bool quoted);

}  // namespace plydem
