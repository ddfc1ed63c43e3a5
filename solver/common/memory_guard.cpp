#include "softkin/solver/common/memory_guard.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace softkin {

double PhysicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return 0.0;
  return static_cast<double>(pages) * static_cast<double>(page);
}

std::string FormatBytes(double bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 6) {
    bytes /= 1024.0;
    ++u;
  }
  char buf[64];
  std::snprintf(buf, sizeof(buf), u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
  return buf;
}

void CheckMemoryEstimate(const std::string& what, double bytes, const std::string& how,
                         const std::string& advice) {
  const double have = PhysicalMemoryBytes();
  if (have <= 0.0) return;
  const double budget = kMemoryBudgetFraction * have;
  if (std::isfinite(bytes) && bytes <= budget) return;
  const std::string need = std::isfinite(bytes) ? FormatBytes(bytes) : std::string("unbounded");
  throw std::invalid_argument(what + ": needs an estimated " + need + " (" + how + "), more than " +
                              std::to_string(static_cast<int>(100 * kMemoryBudgetFraction)) +
                              " % of this machine's " + FormatBytes(have) + "; " + advice);
}

}  // namespace softkin
