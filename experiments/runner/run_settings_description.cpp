#include <string>

#include "experiments/runner/settings_descriptions.hpp"

// The run's own settings (threads, petsc_options) apart from the tests' descriptions: the
// experiment config reader checks every config's top-level keys against them, and its fuzz target
// (tests/fuzz/CMakeLists.txt) links this file without the solver layers the other descriptions use.

namespace plydem {

namespace {

SettingsDescription<RunSettings> make_run_settings() {
  SettingsDescription<RunSettings> d;
  d.integer(
       "threads", [](auto& s) -> auto& { return s.threads; })
      .with_flag("--threads")
      .with_key("threads")
      .with_python("threads")
      .at_least(0)
      .with_help(
          "OpenMP threads of the run (the explicit kernel, the model's build, the solvers' loops); "
          "0 = OpenMP's default (OMP_NUM_THREADS, else every core). Results are the same on any "
          "number");
  d.text(
       "petsc_options", [](auto& s) -> auto& { return s.petsc_options; })
      .with_flag("--petsc-options")
      .with_key("petsc_options")
      .with_python("petsc_options")
      .hide_default()
      .with_help(
          "PETSc options for --linear-solver petsc, e.g. \"-ksp_rtol 1e-10 -pc_type hypre\" (they "
          "override plydem's defaults: CG, GAMG threshold -1, Chebyshev-Jacobi smoothing, rtol "
          "1e-12)");
  return d;
}

}  // namespace

const SettingsDescription<RunSettings>& run_settings_description() {
  static const SettingsDescription<RunSettings> d = make_run_settings();
  return d;
}

}  // namespace plydem
