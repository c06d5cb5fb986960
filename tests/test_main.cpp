// The doctest main of every test binary: as doctest's own, except that
//  - a run in which a case skipped for want of an external tool (plydem::test::skip) and nothing
//    failed exits with 77, which ctest reports as skipped rather than passed;
//  - a run whose filters match no test case fails: a ctest entry that names its cases
//    (tests/CMakeLists.txt, plydem_test_part) cannot pass by running nothing;
//  - under mpiexec it starts MPI (and PETSc) first, as the plydem program does (ParallelSession),
//    so that the cases run on 2 ranks (plydem_mpi2_cases) see every rank.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <iostream>

#include "solvers/linear_solver.hpp"
#include "support/test_support.hpp"

namespace {

int& cases_started() {
  static int count = 0;
  return count;
}

// Counts the test cases that run; reports nothing.
struct CaseCounter : doctest::IReporter {
  explicit CaseCounter(const doctest::ContextOptions&) {}
  void report_query(const doctest::QueryData&) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats&) override {}
  void test_case_start(const doctest::TestCaseData&) override { ++cases_started(); }
  void test_case_reenter(const doctest::TestCaseData&) override {}
  void test_case_end(const doctest::CurrentTestCaseStats&) override {}
  void test_case_exception(const doctest::TestCaseException&) override {}
  void subcase_start(const doctest::SubcaseSignature&) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData&) override {}
  void log_message(const doctest::MessageData&) override {}
  void test_case_skipped(const doctest::TestCaseData&) override {}
};

}  // namespace

DOCTEST_REGISTER_LISTENER("plydem_case_counter", 1, CaseCounter);

int main(int argc, char** argv) {
  const plydem::ParallelSession session(&argc, &argv);
  doctest::Context context(argc, argv);
  const int result = context.run();
  if (context.shouldExit() || result != 0) return result;
  if (cases_started() == 0) {
    std::cerr << "no test case matches the filters given\n";
    return 1;
  }
  return plydem::test::skipped_cases() > 0 ? plydem::test::kSkipReturnCode : 0;
}
