// The experiment config reader's fuzz target reads configs without running them: it links
// experiments/runner/experiment.cpp alone, whose registry would otherwise pull in every kind.
#include "experiments/runner/experiment.hpp"

namespace plydem {

void register_builtin_experiments(ExperimentRegistry&) {}

}  // namespace plydem
