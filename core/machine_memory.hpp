#pragma once
/// \file
/// How much memory this process may still allocate, for the size checks that run before a coupon
/// is built (experiments/protocols/resource_estimate.hpp).

#include <string>

namespace plydem {

struct MachineMemory {
  double available = 0;  ///< bytes this process may still allocate
  double total = 0;      ///< the machine's (or the cgroup's) memory [bytes]
  /// Where `available` comes from: "MemAvailable of /proc/meminfo", "cgroup memory.max", or
  /// "PLYDEM_AVAILABLE_MEMORY".
  std::string source;
};

/// The smaller of /proc/meminfo's MemAvailable and the cgroup's limit less its usage (cgroup v2
/// memory.max / memory.current, or v1 memory.limit_in_bytes / memory.usage_in_bytes). The
/// environment variable PLYDEM_AVAILABLE_MEMORY (bytes, e.g. 2e9) replaces both: for tests and
/// for sharing a machine. available = +infinity (source "unknown") where none can be read.
/// Throws plydem::Error for a PLYDEM_AVAILABLE_MEMORY that is not a positive number.
MachineMemory machine_memory();

/// This process' peak resident set size [bytes] (VmHWM of /proc/self/status), 0 where it cannot be
/// read: the benchmarks' memory figure.
double peak_resident_bytes();

}  // namespace plydem
