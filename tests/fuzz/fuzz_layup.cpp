#include "strategies/laminate.hpp"
#include "tests/fuzz/fuzz_inputs.hpp"

namespace plydem::fuzz {

void layup(std::string_view input) {
  refused_or_accepted([&] { (void)format_layup(parse_layup(std::string(input))); });
}

}  // namespace plydem::fuzz
