// Seconds / SecondsSince: the durations every solver, trainer and experiment reports.
#include "softkin/solver/common/stopwatch.hpp"

#include <gtest/gtest.h>

#include <chrono>

namespace softkin {
namespace {

TEST(Stopwatch, SecondsIsTheSignedDurationBetweenTwoTimePoints) {
  const SteadyClock::time_point a = SteadyClock::now();
  const SteadyClock::time_point b = a + std::chrono::milliseconds(1500);
  EXPECT_DOUBLE_EQ(Seconds(a, b), 1.5);
  EXPECT_DOUBLE_EQ(Seconds(b, a), -1.5);
  EXPECT_DOUBLE_EQ(Seconds(a, a), 0.0);
  EXPECT_DOUBLE_EQ(Seconds(a, a + std::chrono::microseconds(250)), 250e-6);
}

TEST(Stopwatch, SecondsSinceCountsUpFromItsStart) {
  const SteadyClock::time_point hour_ago = SteadyClock::now() - std::chrono::hours(1);
  const double since = SecondsSince(hour_ago);
  EXPECT_GE(since, 3600.0);
  EXPECT_LT(since, 3600.0 + 60.0);  // the call itself takes far less than a minute
  const SteadyClock::time_point now = SteadyClock::now();
  EXPECT_GE(SecondsSince(now), 0.0);
}

}  // namespace
}  // namespace softkin
