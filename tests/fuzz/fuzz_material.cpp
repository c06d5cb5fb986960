#include "core/material.hpp"
#include "tests/fuzz/fuzz_inputs.hpp"

namespace plydem::fuzz {

void material(std::string_view input) {
  refused_or_accepted([&] { (void)parse_material(std::string(input), "fuzz.toml"); });
}

}  // namespace plydem::fuzz
