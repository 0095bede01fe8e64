#include "rtos_shim/lockstep_scheduler.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <tuple>
#include <vector>

#include "tests/support/alloc_trap.h"

namespace kuavo::rtos {
namespace {

using K = SimEventKind;
constexpr TimeNs kMs = 1'000'000;

bool same(const SimEvent& a, const SimEvent& b) {
  return std::tie(a.kind, a.time_ns, a.dt_ns, a.index, a.plan_state_ns) ==
         std::tie(b.kind, b.time_ns, b.dt_ns, b.index, b.plan_state_ns);
}

std::vector<SimEvent> run_all(const LockstepConfig& config) {
  LockstepScheduler sched;
  EXPECT_EQ(sched.reset(config), LockstepError::kOk);
  std::vector<SimEvent> events;
  SimEvent ev;
  while (sched.next(ev)) events.push_back(ev);
  return events;
}

TEST(RtosLockstep, RejectsBadConfigurations) {
  LockstepScheduler sched;
  SimEvent ev;
  EXPECT_FALSE(sched.next(ev)) << "no events before reset()";

  LockstepConfig c;
  c.control_period_ns = 0;
  EXPECT_EQ(sched.reset(c), LockstepError::kBadControlPeriod);
  c = {};
  c.plan_period_ns = 3 * kMs;  // not a multiple of 2 ms
  EXPECT_EQ(sched.reset(c), LockstepError::kBadPlanPeriod);
  c = {};
  c.plan_delay_ns = -1;
  EXPECT_EQ(sched.reset(c), LockstepError::kBadPlanDelay);
  c = {};
  c.plant_steps_per_tick = 3;  // 2 ms / 3 is not whole ns
  EXPECT_EQ(sched.reset(c), LockstepError::kBadPlantSteps);
  c = {};
  c.start_ns = 10;
  c.stop_ns = 5;
  EXPECT_EQ(sched.reset(c), LockstepError::kBadStopTime);
  EXPECT_FALSE(sched.next(ev)) << "a failed reset leaves the scheduler stopped";
  EXPECT_STREQ(describe(LockstepError::kBadPlanDelay), "plan_delay_ns must be >= 0");
}

TEST(RtosLockstep, ExactEventOrder) {
  // Small numbers so the expected sequence can be written out by hand.
  LockstepConfig c;
  c.control_period_ns = 2;
  c.plan_period_ns = 6;
  c.plan_delay_ns = 4;
  c.plant_steps_per_tick = 2;
  c.stop_ns = 10;
  const std::vector<SimEvent> expected = {
      {K::kControlTick, 0, 2, 0, 0}, {K::kPlanRequest, 0, 0, 0, 0}, {K::kPlantStep, 0, 1, 0, 0},
      {K::kPlantStep, 1, 1, 1, 0},
      {K::kControlTick, 2, 2, 1, 0}, {K::kPlantStep, 2, 1, 2, 0},
      {K::kPlantStep, 3, 1, 3, 0},
      {K::kPlanApply, 4, 0, 0, 0},   {K::kControlTick, 4, 2, 2, 0}, {K::kPlantStep, 4, 1, 4, 0},
      {K::kPlantStep, 5, 1, 5, 0},
      {K::kControlTick, 6, 2, 3, 0}, {K::kPlanRequest, 6, 0, 1, 6}, {K::kPlantStep, 6, 1, 6, 0},
      {K::kPlantStep, 7, 1, 7, 0},
      {K::kControlTick, 8, 2, 4, 0}, {K::kPlantStep, 8, 1, 8, 0},
      {K::kPlantStep, 9, 1, 9, 0},
      // plan 1 would apply at 10 == stop_ns: not emitted
  };
  const std::vector<SimEvent> got = run_all(c);
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(same(got[i], expected[i]))
        << "event " << i << ": kind " << int(got[i].kind) << " t " << got[i].time_ns << " dt "
        << got[i].dt_ns << " index " << got[i].index << " state " << got[i].plan_state_ns;
  }
}

TEST(RtosLockstep, PlanAppliedExactlyDelayAfterItsStateAndBeforeThatTick) {
  LockstepConfig c;  // 500 Hz control, 50 Hz planning
  c.plan_delay_ns = 6 * kMs;
  c.plant_steps_per_tick = 4;
  c.stop_ns = 1'000 * kMs;
  LockstepScheduler sched;
  ASSERT_EQ(sched.reset(c), LockstepError::kOk);

  SimEvent ev;
  TimeNs last_time_ns = 0;
  bool in_flight = false;
  std::uint64_t in_flight_index = 0;
  TimeNs in_flight_state_ns = -1;
  std::uint64_t applied_plan_seen_by_tick = UINT64_MAX;  // what the controller would be using
  std::uint64_t ticks_with_fresh_plan = 0;
  bool apply_pending_for_tick = false;
  while (sched.next(ev)) {
    ASSERT_EQ(sched.now_ns(), ev.time_ns);
    ASSERT_GE(ev.time_ns, last_time_ns) << "virtual time went back";
    last_time_ns = ev.time_ns;
    switch (ev.kind) {
      case K::kPlanRequest:
        ASSERT_FALSE(in_flight) << "two plans in flight";
        ASSERT_EQ(ev.plan_state_ns, ev.time_ns);
        ASSERT_EQ(ev.time_ns % (20 * kMs), 0) << "planning releases on its 50 Hz grid";
        in_flight = true;
        in_flight_index = ev.index;
        in_flight_state_ns = ev.time_ns;
        break;
      case K::kPlanApply:
        ASSERT_TRUE(in_flight);
        ASSERT_EQ(ev.index, in_flight_index);
        ASSERT_EQ(ev.plan_state_ns, in_flight_state_ns);
        ASSERT_EQ(ev.time_ns - ev.plan_state_ns, 6 * kMs) << "latency is exactly the delay";
        in_flight = false;
        applied_plan_seen_by_tick = ev.index;
        apply_pending_for_tick = true;
        break;
      case K::kControlTick:
        if (apply_pending_for_tick) {
          // The delay is a whole number of ticks, so the first tick to use the plan is the one at
          // exactly state time + delay.
          ASSERT_EQ(ev.time_ns, in_flight_state_ns + 6 * kMs);
          ++ticks_with_fresh_plan;
          apply_pending_for_tick = false;
        }
        break;
      case K::kPlantStep:
        ASSERT_EQ(ev.dt_ns, kMs / 2);
        break;
    }
  }
  EXPECT_EQ(sched.stats().control_ticks, 500u);
  EXPECT_EQ(sched.stats().plans_requested, 50u);
  EXPECT_EQ(sched.stats().plans_applied, 50u);
  EXPECT_EQ(sched.stats().plans_skipped, 0u);
  EXPECT_EQ(sched.stats().plant_steps, 2000u);
  EXPECT_EQ(ticks_with_fresh_plan, 50u);
  EXPECT_EQ(applied_plan_seen_by_tick, 49u);
}

TEST(RtosLockstep, ZeroDelayPlanIsSeenByTheNextTick) {
  LockstepConfig c;
  c.control_period_ns = 2;
  c.plan_period_ns = 4;
  c.plan_delay_ns = 0;
  c.stop_ns = 3;
  const std::vector<SimEvent> got = run_all(c);
  ASSERT_EQ(got.size(), 6u);
  EXPECT_EQ(got[0].kind, K::kControlTick);  // tick 0 ran before the planner
  EXPECT_EQ(got[1].kind, K::kPlanRequest);
  EXPECT_EQ(got[2].kind, K::kPlanApply);
  EXPECT_EQ(got[2].time_ns, 0);
  EXPECT_EQ(got[3].kind, K::kPlantStep);
  EXPECT_EQ(got[4].kind, K::kControlTick);
  EXPECT_EQ(got[4].time_ns, 2);
  EXPECT_EQ(got[5].kind, K::kPlantStep);
}

// Per-call latency: each plan's measured compute time, rounded up to control ticks.
TEST(RtosLockstep, PerPlanDelayAndSkippedReleasesWhilePlannerIsBusy) {
  LockstepConfig c;  // 2 ms ticks, 20 ms planning
  c.stop_ns = 200 * kMs;
  LockstepScheduler sched;
  ASSERT_EQ(sched.reset(c), LockstepError::kOk);
  EXPECT_FALSE(sched.set_plan_delay_ns(kMs)) << "no plan has just been requested";

  // Plan 1 takes 25 ms (longer than the 20 ms planning period): the release at 40 ms is lost.
  const TimeNs compute_ns[] = {3'100'000, 25'000'000, 4'000'000};
  std::vector<std::pair<TimeNs, TimeNs>> applies;  // (state time, apply time)
  std::vector<TimeNs> request_times;
  SimEvent ev;
  while (sched.next(ev)) {
    if (ev.kind == K::kPlanRequest) {
      const TimeNs measured_ns = compute_ns[ev.index % 3];
      EXPECT_FALSE(sched.set_plan_delay_ns(-1));
      EXPECT_TRUE(sched.set_plan_delay_ns(round_up_to_multiple_ns(measured_ns, c.control_period_ns)));
      request_times.push_back(ev.time_ns);
    } else if (ev.kind == K::kPlanApply) {
      applies.emplace_back(ev.plan_state_ns, ev.time_ns);
    } else {
      EXPECT_FALSE(sched.set_plan_delay_ns(kMs)) << "only right after a request";
    }
  }
  ASSERT_GE(applies.size(), 3u);
  EXPECT_EQ(applies[0], std::make_pair(TimeNs{0}, TimeNs{4 * kMs}));         // 3.1 ms -> 2 ticks
  EXPECT_EQ(applies[1], std::make_pair(TimeNs{20 * kMs}, TimeNs{46 * kMs}));  // 25 ms -> 13 ticks
  // Release at 40 ms falls while plan 1 is in flight; the next is at 60 ms.
  EXPECT_EQ(applies[2], std::make_pair(TimeNs{60 * kMs}, TimeNs{64 * kMs}));
  ASSERT_GE(request_times.size(), 3u);
  EXPECT_EQ(request_times[2], 60 * kMs);
  EXPECT_GE(sched.stats().plans_skipped, 1u);
  EXPECT_EQ(sched.stats().plans_requested + sched.stats().plans_skipped, 10u);
}

TEST(RtosLockstep, IdenticalEventSequenceAcrossRuns) {
  LockstepConfig c;
  c.plan_delay_ns = 8 * kMs;
  c.plant_steps_per_tick = 2;
  c.start_ns = 123 * kMs;
  c.stop_ns = c.start_ns + 300 * kMs;
  const std::vector<SimEvent> a = run_all(c);
  const std::vector<SimEvent> b = run_all(c);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 100u);
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(same(a[i], b[i])) << "event " << i;

  // The comparison can fail: a different latency gives a different sequence.
  c.plan_delay_ns = 10 * kMs;
  const std::vector<SimEvent> d = run_all(c);
  bool differs = d.size() != a.size();
  for (std::size_t i = 0; !differs && i < a.size(); ++i) differs = !same(a[i], d[i]);
  EXPECT_TRUE(differs);
}

TEST(RtosLockstep, SteadyStateNextDoesNotAllocate) {
  LockstepConfig c;
  c.plant_steps_per_tick = 4;
  LockstepScheduler sched;
  ASSERT_EQ(sched.reset(c), LockstepError::kOk);
  SimEvent ev;
  std::uint64_t plan_requests = 0;
  {
    kuavo::test::AllocTrap trap;
    for (int i = 0; i < 20'000; ++i) {
      ASSERT_TRUE(sched.next(ev));
      if (ev.kind == K::kPlanRequest) {
        ++plan_requests;
        sched.set_plan_delay_ns(4 * kMs);
      }
    }
    EXPECT_EQ(trap.count(), 0u) << "first allocation: " << trap.first_size_bytes() << " bytes";
  }
  EXPECT_GT(plan_requests, 0u);
}

}  // namespace
}  // namespace kuavo::rtos
