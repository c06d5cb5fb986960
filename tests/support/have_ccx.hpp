#pragma once
// Whether CalculiX can run; when not, the case says why and counts as skipped
// (tests/support/test_support.hpp skip()), so that ctest reports it skipped, never passed.
#include "experiments/fem/calculix.hpp"
#include "test_support.hpp"

namespace plydem::test {

inline bool have_ccx() {
  const CalculixAvailability ccx = calculix_availability();
  if (!ccx.available) skip(ccx.message);
  return ccx.available;
}

}  // namespace plydem::test
