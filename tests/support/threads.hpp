#pragma once
/// \file
/// The number of OpenMP threads for one scope, for the tests that hold runs on 1, 2 and 4 threads
/// to the same bits.
#include <omp.h>

namespace plydem::test {

// Sets the number of OpenMP threads for one scope.
struct Threads {
  explicit Threads(int n) : previous(omp_get_max_threads()) { omp_set_num_threads(n); }
  ~Threads() { omp_set_num_threads(previous); }
  int previous;
};

}  // namespace plydem::test
