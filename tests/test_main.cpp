// The doctest main of every test binary: as doctest's own, except that a run in which a case
// skipped for want of an external tool (plydem::test::skip) and nothing failed exits with 77,
// which ctest reports as skipped rather than passed.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include "support/test_support.hpp"

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int result = context.run();
  if (context.shouldExit() || result != 0) return result;
  return plydem::test::skipped_cases() > 0 ? plydem::test::kSkipReturnCode : 0;
}
