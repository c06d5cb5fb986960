#include "experiments/protocols/run_settings.hpp"

#include <fmt/format.h>
#include <omp.h>

#include "core/error.hpp"
#include "solvers/linear_solver.hpp"

namespace plydem {

RunScope::RunScope(const RunSettings& settings) : previous_threads_(omp_get_max_threads()) {
  require(
      settings.threads >= 0,
      fmt::format("threads must be at least 0 (0 = OpenMP's default), got {}", settings.threads));
  if (!settings.petsc_options.empty()) set_petsc_options(settings.petsc_options);
  if (settings.threads > 0) omp_set_num_threads(settings.threads);
}

RunScope::~RunScope() {
  omp_set_num_threads(previous_threads_);
}

}  // namespace plydem
