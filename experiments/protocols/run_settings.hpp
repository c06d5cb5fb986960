#pragma once
/// \file
/// What a run of any test takes besides the test's own settings: its OpenMP threads and PETSc's
/// options. `plydem` takes them on every command (--threads, --petsc-options), a config at its top
/// level (`threads`, `petsc_options`, every kind), Python as keywords of tension_test() and
/// strength_test(); their description is in experiments/runner/settings_descriptions.hpp.

#include <string>

namespace plydem {

struct RunSettings {
  /// OpenMP threads of the run (the explicit kernel, the model's build, the solvers' loops);
  /// 0 = OpenMP's default (OMP_NUM_THREADS, else every core). Results are the same on any number
  /// (tests/test_thread_determinism.cpp).
  int threads = 0;
  /// PETSc options for the static solves with --linear-solver petsc (set_petsc_options); "" = none.
  std::string petsc_options;
};

/// Applies `settings` for its lifetime: the OpenMP thread count (the previous one restored at the
/// end) and the PETSc options (added to PETSc's options database for the rest of the process, as
/// set_petsc_options does). Throws plydem::Error for a negative thread count or PETSc options
/// without PETSc.
class RunScope {
 public:
  explicit RunScope(const RunSettings& settings);
  ~RunScope();
  RunScope(const RunScope&) = delete;
  RunScope& operator=(const RunScope&) = delete;

 private:
  int previous_threads_ = 0;
};

}  // namespace plydem
