// A libFuzzer target: PLYDEM_FUZZ_TARGET names the reader (tests/fuzz/fuzz_inputs.hpp), one
// binary per reader (tests/fuzz/CMakeLists.txt). Run by scripts/fuzz.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/fuzz_inputs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  plydem::fuzz::PLYDEM_FUZZ_TARGET(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
