#include "core/machine_memory.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "core/error.hpp"

namespace plydem {

namespace {

// The "Key: value kB" line of /proc/meminfo, in bytes; negative if missing.
double meminfo_bytes(const std::string& key) {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) != 0) continue;
    std::istringstream fields(line.substr(key.size() + 1));
    double kib = -1;
    fields >> kib;
    return kib >= 0 ? kib * 1024.0 : -1.0;
  }
  return -1;
}

// A number in a cgroup file ("max" and unreadable files: negative).
double cgroup_number(const char* path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return -1;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return end != text.c_str() && std::isfinite(value) && value >= 0 ? value : -1.0;
}

}  // namespace

MachineMemory machine_memory() {
  MachineMemory m;
  if (const char* given = std::getenv("PLYDEM_AVAILABLE_MEMORY")) {
    char* end = nullptr;
    const double bytes = std::strtod(given, &end);
    require(
        end != given && *end == '\0' && std::isfinite(bytes) && bytes > 0,
        fmt::format("PLYDEM_AVAILABLE_MEMORY must be a positive number of bytes, got '{}'", given));
    m.available = m.total = bytes;
    m.source = "PLYDEM_AVAILABLE_MEMORY";
    return m;
  }
  m.available = std::numeric_limits<double>::infinity();
  m.total = m.available;
  m.source = "unknown";
  if (const double available = meminfo_bytes("MemAvailable"); available >= 0) {
    m.available = available;
    m.total = meminfo_bytes("MemTotal");
    m.source = "MemAvailable of /proc/meminfo";
  }
  struct Limit {
    const char* limit;
    const char* usage;
  };
  for (const Limit& c : {Limit{"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"},
                         Limit{"/sys/fs/cgroup/memory/memory.limit_in_bytes",
                               "/sys/fs/cgroup/memory/memory.usage_in_bytes"}}) {
    const double limit = cgroup_number(c.limit);
    const double usage = cgroup_number(c.usage);
    // cgroup v1 writes "no limit" as a huge number (about 2^63).
    if (limit < 0 || usage < 0 || limit > 1e18) continue;
    if (limit - usage < m.available) {
      m.available = std::max(0.0, limit - usage);
      m.total = limit;
      m.source = fmt::format("the cgroup's {}", c.limit);
    }
    break;
  }
  return m;
}

double peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return 1024.0 * std::stod(line.substr(6));  // kB
  return 0;
}

}  // namespace plydem
