#include "rtos_shim/clock.h"

#include <gtest/gtest.h>

#include "rtos_shim/sim_clock.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::rtos {
namespace {

TEST(RtosClock, MonotonicNeverGoesBack) {
  TimeNs previous_ns = now_ns();
  EXPECT_GT(previous_ns, 0);
  for (int i = 0; i < 10'000; ++i) {
    const TimeNs t_ns = now_ns();
    ASSERT_GE(t_ns, previous_ns);
    previous_ns = t_ns;
  }
  EXPECT_GE(MonotonicClock{}.now_ns(), previous_ns);
}

TEST(RtosClock, SleepUntilReturnsNotBeforeTheDeadline) {
  for (int i = 0; i < 5; ++i) {
    const TimeNs deadline_ns = now_ns() + 500'000;
    sleep_until_ns_rt(deadline_ns);
    EXPECT_GE(now_ns(), deadline_ns);
  }
  // A deadline in the past returns at once instead of sleeping a whole epoch.
  sleep_until_ns_rt(now_ns() - kNsPerSecond);
}

TEST(RtosClock, ReadingAndSleepingDoNotAllocate) {
  kuavo::test::AllocTrap trap;
  TimeNs sum_ns = 0;
  for (int i = 0; i < 100; ++i) sum_ns += now_ns();
  sleep_until_ns_rt(now_ns() + 100'000);
  EXPECT_GT(sum_ns, 0);
  EXPECT_EQ(trap.count(), 0u) << "first allocation: " << trap.first_size_bytes() << " bytes";
}

TEST(RtosSimClock, AdvancesOnlyForward) {
  SimClock clock(1'000);
  EXPECT_EQ(clock.now_ns(), 1'000);
  EXPECT_TRUE(clock.advance_to_ns(1'000));
  EXPECT_TRUE(clock.advance_to_ns(2'500));
  EXPECT_EQ(clock.now_ns(), 2'500);
  EXPECT_FALSE(clock.advance_to_ns(2'499));
  EXPECT_EQ(clock.now_ns(), 2'500);
}

}  // namespace
}  // namespace kuavo::rtos
