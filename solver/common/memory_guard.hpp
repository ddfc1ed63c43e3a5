#pragma once
/// \file memory_guard.hpp
/// Refusing work that cannot fit: an up-front estimate of the memory a job needs, checked against
/// this machine's physical memory before anything large is allocated, so that a too fine mesh
/// size or a too wide network fails at once with the option and the estimate named, instead of
/// minutes later with a bare std::bad_alloc (or a machine driven into swap).
#include <string>

namespace softkin {

/// This machine's physical memory in bytes (sysconf), or 0 if it cannot be read.
double PhysicalMemoryBytes();

/// The share of PhysicalMemoryBytes() one job may plan to use.
constexpr double kMemoryBudgetFraction = 0.8;

/// "3.2 GiB", "512 MiB", "12 KiB": a byte count for messages.
std::string FormatBytes(double bytes);

/// Throws std::invalid_argument "WHAT: needs an estimated X (HOW), more than 80 % of this
/// machine's Y; ADVICE" when `bytes` exceeds kMemoryBudgetFraction of the physical memory (or is
/// not finite). `what` names the option or key responsible; `how` says what the estimate counts.
/// Does nothing when the physical memory is unknown.
void CheckMemoryEstimate(const std::string& what, double bytes, const std::string& how,
                         const std::string& advice);

}  // namespace softkin
