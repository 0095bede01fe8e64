#include "rtos_shim/stall_probe.h"

#include <gtest/gtest.h>

#include <vector>

#include "rtos_shim/clock.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::rtos {
namespace {

// A clock that advances by a script: each read 40 ns after the last, except where a stall
// of a planted length comes first. The oracle is the script itself.
struct ScriptedClock {
  std::vector<TimeNs>* stalls_at_read;  // stall (ns) added before read i; 0: none
  mutable std::size_t read = 0;
  mutable TimeNs t = 1'000'000;
  TimeNs now_ns() const noexcept {
    const TimeNs stall = read < stalls_at_read->size() ? (*stalls_at_read)[read] : 0;
    ++read;
    t += 40 + stall;
    return t;
  }
};

TEST(RtosStallProbe, CountsThePlantedStallsAndTheLongest) {
  std::vector<TimeNs> stalls(20'000, 0);
  stalls[100] = 12'000;    // over 10 us only
  stalls[5'000] = 60'000;  // over 10 and 50 us
  stalls[9'000] = 151'000; // over all four
  stalls[9'001] = 149'960; // a gap of 150 us exactly: not over 150 us
  stalls[200] = 9'950;     // 9.99 us with the read's 40 ns: under every threshold
  const ScriptedClock clock{&stalls};
  StallStats s;
  stall_probe_spin_rt(clock, 1'000'000, s);  // 1 ms of clock time
  EXPECT_EQ(s.max_gap_ns, 151'040);
  EXPECT_EQ(s.gaps_over[0], 4u);
  EXPECT_EQ(s.gaps_over[1], 3u);
  EXPECT_EQ(s.gaps_over[2], 2u);
  EXPECT_EQ(s.gaps_over[3], 1u);
  // It stops at the first read 1 ms or more after the first: n reads after the first, with
  // 40 n + the planted stalls >= 1 ms.
  const TimeNs planted = 12'000 + 60'000 + 151'000 + 149'960 + 9'950;
  const TimeNs n = (1'000'000 - planted + 39) / 40;
  EXPECT_EQ(s.reads, static_cast<std::uint64_t>(1 + n));
  EXPECT_GE(s.spun_ns, 1'000'000);
  EXPECT_LT(s.spun_ns, 1'000'000 + 40);
  // Bursts add up.
  StallStats again = s;
  stall_probe_spin_rt(clock, 1'000'000, again);
  EXPECT_EQ(again.gaps_over[0], s.gaps_over[0]);  // the script's stalls are used up
  EXPECT_EQ(again.max_gap_ns, s.max_gap_ns);
  EXPECT_GT(again.reads, 2 * s.reads - 100);
  EXPECT_GE(again.spun_ns, 2'000'000);
}

// On the real clock: the burst lasts what it was asked, reads the clock many times, never
// sees time go back, and allocates nothing.
TEST(RtosStallProbe, SpinsOnTheMonotonicClockWithoutAllocating) {
  StallStats s;
  kuavo::test::AllocTrap trap;
  const TimeNs t0 = now_ns();
  stall_probe_spin_rt(MonotonicClock{}, 2'000'000, s);
  const TimeNs t1 = now_ns();
  EXPECT_EQ(trap.count(), 0u);
  EXPECT_GE(s.spun_ns, 2'000'000);
  EXPECT_GE(t1 - t0, 2'000'000);
  EXPECT_GT(s.reads, 100u);
  EXPECT_GE(s.max_gap_ns, 0);
  EXPECT_LE(s.max_gap_ns, t1 - t0);
}

}  // namespace
}  // namespace kuavo::rtos
