// The fuzzers' findings as regression tests: every file in tests/fuzz/regressions/TARGET (inputs a
// fuzzer crashed, hung or leaked on, each fixed) and in the seed corpus tests/fuzz/corpus/TARGET
// goes through the same reader as the fuzz target TARGET (tests/fuzz/fuzz_inputs.hpp), in every
// build: each must be accepted or refused with plydem::Error (the entry swallows it), nothing else.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/fuzz/fuzz_inputs.hpp"

namespace fs = std::filesystem;

namespace {

const char* const kTargets[] = {"material", "experiment_config", "layup", "command_line"};

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Feeds every file under `folder`/TARGET to TARGET's reader; returns how many.
int feed_all(const fs::path& folder) {
  int fed = 0;
  for (const char* target : kTargets) {
    const plydem::fuzz::Entry entry = plydem::fuzz::entry(target);
    REQUIRE(static_cast<bool>(entry));
    const fs::path inputs = folder / target;
    if (!fs::is_directory(inputs)) continue;
    for (const fs::directory_entry& file : fs::directory_iterator(inputs)) {
      if (!file.is_regular_file() || file.path().filename() == "README.md") continue;
      CAPTURE(file.path().string());
      CHECK_NOTHROW(entry(read_bytes(file.path())));
      ++fed;
    }
  }
  return fed;
}

}  // namespace

TEST_CASE("every fuzz regression input is accepted or refused with plydem::Error") {
  CHECK(feed_all(fs::path(PLYDEM_FUZZ_DIR) / "regressions") > 0);
}

TEST_CASE("every seed of the fuzz corpus is accepted or refused with plydem::Error") {
  CHECK(feed_all(fs::path(PLYDEM_FUZZ_DIR) / "corpus") >= 4);
}

TEST_CASE("the fuzz entries know their targets") {
  for (const char* target : kTargets) CHECK(static_cast<bool>(plydem::fuzz::entry(target)));
  CHECK_FALSE(static_cast<bool>(plydem::fuzz::entry("nosuch")));
}
