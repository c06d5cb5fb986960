#include "tests/fuzz/fuzz_inputs.hpp"

namespace plydem::fuzz {

Entry entry(const std::string& target) {
  if (target == "material") return &material;
  if (target == "experiment_config") return &experiment_config;
  if (target == "layup") return &layup;
  if (target == "command_line") return &command_line;
  return nullptr;
}

}  // namespace plydem::fuzz
