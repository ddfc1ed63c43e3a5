#pragma once
/// \file stopwatch.hpp
/// Wall-clock seconds on the steady clock, for the times that solvers, trainers and experiments
/// report (FkResult::time_s, progress lines, summaries).

#include <chrono>

namespace softkin {

using SteadyClock = std::chrono::steady_clock;

/// Seconds from `from` to `to`.
inline double Seconds(SteadyClock::time_point from, SteadyClock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

/// Seconds from `from` to now.
inline double SecondsSince(SteadyClock::time_point from) {
  return Seconds(from, SteadyClock::now());
}

}  // namespace softkin
