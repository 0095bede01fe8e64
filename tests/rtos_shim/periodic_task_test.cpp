#include "rtos_shim/periodic_task.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "tests/support/alloc_trap.h"

namespace kuavo::rtos {
namespace {

constexpr TimeNs kPeriodNs = 1'000'000;  // 1 kHz: short tests, still well above timer slack

// --- Deadline bookkeeping, with made-up times (exact) ---

TEST(RtosPeriodicPerf, NextReleaseRegularAndOverrun) {
  // On time: next release one period later.
  NextRelease r = next_release(1000, 1300, 1000);
  EXPECT_EQ(r.deadline_ns, 2000);
  EXPECT_FALSE(r.overrun);
  EXPECT_EQ(r.skipped_periods, 0u);
  // Ending exactly on the next deadline is still on time.
  r = next_release(1000, 2000, 1000);
  EXPECT_EQ(r.deadline_ns, 2000);
  EXPECT_FALSE(r.overrun);
  // Just late: the release at 2000 is dropped, resume on the grid at 3000.
  r = next_release(1000, 2001, 1000);
  EXPECT_EQ(r.deadline_ns, 3000);
  EXPECT_TRUE(r.overrun);
  EXPECT_EQ(r.skipped_periods, 1u);
  // Very late: 2000, 3000, 4000, 5000 dropped; never schedules in the past.
  r = next_release(1000, 5500, 1000);
  EXPECT_EQ(r.deadline_ns, 6000);
  EXPECT_TRUE(r.overrun);
  EXPECT_EQ(r.skipped_periods, 4u);
}

TEST(RtosPeriodicPerf, CountersAccumulate) {
  PeriodicPerf perf;
  perf.record_rt(10, 300, false, 0);
  perf.record_rt(50, 2500, true, 2);
  perf.record_rt(20, 100, false, 0);
  const PeriodicPerfSnapshot s = perf.snapshot();
  EXPECT_EQ(s.cycles, 3u);
  EXPECT_EQ(s.overruns, 1u);
  EXPECT_EQ(s.skipped_periods, 2u);
  EXPECT_EQ(s.last_cycle_ns, 100);
  EXPECT_EQ(s.max_cycle_ns, 2500);
  EXPECT_EQ(s.last_wake_latency_ns, 20);
  EXPECT_EQ(s.max_wake_latency_ns, 50);
  perf.reset();
  EXPECT_EQ(perf.snapshot().cycles, 0u);
  EXPECT_EQ(perf.snapshot().max_cycle_ns, 0);
}

// --- The loop on the calling thread ---

struct RecordingBody {
  static constexpr int kMax = 64;
  CycleInfo infos[kMax];
  int calls = 0;
  TimeNs busy_ns = 0;   // made slow by sleeping this long after waking
  int slow_every = 0;   // 0: every cycle slow (if busy_ns), n: only cycles with index % n == 0
  const PeriodicPerf* perf = nullptr;  // if set: skipped periods so far, read at each call
  std::uint64_t skipped_before[kMax] = {};
  void operator()(const CycleInfo& info) noexcept {
    if (calls < kMax) {
      infos[calls] = info;
      if (perf != nullptr) skipped_before[calls] = perf->snapshot().skipped_periods;
    }
    ++calls;
    if (busy_ns > 0 && (slow_every == 0 || info.cycle % slow_every == 0)) {
      sleep_until_ns_rt(info.wake_ns + busy_ns);
    }
  }
};

TEST(RtosPeriodicLoop, RunsNCyclesOnAnAbsoluteGrid) {
  std::atomic<bool> stop{false};
  PeriodicPerf perf;
  RecordingBody body;
  body.perf = &perf;
  const std::uint64_t ran = run_periodic_loop_rt(kPeriodNs, 20, stop, perf, body);
  EXPECT_EQ(ran, 20u);
  EXPECT_EQ(body.calls, 20);
  EXPECT_EQ(perf.snapshot().cycles, 20u);
  const TimeNs first_ns = body.infos[0].deadline_ns;
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(body.infos[i].cycle, static_cast<std::uint64_t>(i));
    EXPECT_GE(body.infos[i].wake_ns, body.infos[i].deadline_ns) << "woke before the deadline";
    EXPECT_EQ((body.infos[i].deadline_ns - first_ns) % kPeriodNs, 0) << "left the release grid";
    if (i > 0) {
      EXPECT_GT(body.infos[i].deadline_ns, body.infos[i - 1].deadline_ns);
    }
  }
  // Releases are on the grid; any skipped ones (a loaded machine) are counted. The
  // skips a cycle causes show in the next release, so the count is read when the
  // last cycle starts (the snapshot after the loop also holds the last cycle's own).
  EXPECT_EQ(body.infos[19].deadline_ns - first_ns,
            static_cast<TimeNs>(19 + body.skipped_before[19]) * kPeriodNs);
  EXPECT_GE(perf.snapshot().skipped_periods, body.skipped_before[19]);
}

TEST(RtosPeriodicLoop, SlowBodyOverrunsEveryCycle) {
  std::atomic<bool> stop{false};
  PeriodicPerf perf;
  RecordingBody body;
  body.busy_ns = kPeriodNs * 5 / 2;  // 2.5 periods: each cycle ends past >= 2 release times
  run_periodic_loop_rt(kPeriodNs, 10, stop, perf, body);
  const PeriodicPerfSnapshot s = perf.snapshot();
  EXPECT_EQ(s.cycles, 10u);
  EXPECT_EQ(s.overruns, 10u);
  EXPECT_GE(s.skipped_periods, 20u);
  EXPECT_GE(s.max_cycle_ns, body.busy_ns);
  for (int i = 1; i < 10; ++i) {
    EXPECT_GE(body.infos[i].deadline_ns - body.infos[i - 1].deadline_ns, 3 * kPeriodNs)
        << "a late cycle must not be followed by catch-up releases";
  }
}

TEST(RtosPeriodicLoop, OnlySlowCyclesAreGuaranteedOverruns) {
  std::atomic<bool> stop{false};
  PeriodicPerf perf;
  RecordingBody body;
  body.busy_ns = kPeriodNs * 3 / 2;
  body.slow_every = 4;  // cycles 0, 4, 8, 12 are slow
  run_periodic_loop_rt(kPeriodNs, 16, stop, perf, body);
  const PeriodicPerfSnapshot s = perf.snapshot();
  EXPECT_EQ(s.cycles, 16u);
  // A shared machine may add late cycles, never remove the slow ones.
  EXPECT_GE(s.overruns, 4u);
  EXPECT_LE(s.overruns, 16u);
  EXPECT_GE(s.skipped_periods, s.overruns);
}

TEST(RtosPeriodicLoop, StopFlagEndsTheLoop) {
  std::atomic<bool> stop{true};
  PeriodicPerf perf;
  RecordingBody body;
  EXPECT_EQ(run_periodic_loop_rt(kPeriodNs, 0, stop, perf, body), 0u);
  EXPECT_EQ(body.calls, 0);
}

TEST(RtosPeriodicLoop, LoopDoesNotAllocate) {
  std::atomic<bool> stop{false};
  PeriodicPerf perf;
  RecordingBody body;
  kuavo::test::AllocTrap trap;
  run_periodic_loop_rt(kPeriodNs, 10, stop, perf, body);
  EXPECT_EQ(trap.count(), 0u) << "first allocation: " << trap.first_size_bytes() << " bytes";
}

// --- The task on its own thread ---

PeriodicConfig unprivileged_config(std::uint64_t cycles) {
  PeriodicConfig c;
  c.period_ns = kPeriodNs;
  c.max_cycles = cycles;
  c.rt.on_failure = RtFailurePolicy::kBestEffort;
  return c;
}

TEST(RtosPeriodicTask, RunsMaxCyclesOnItsThread) {
  RecordingBody body;
  PeriodicTask task;
  const RtStatus s = task.start(unprivileged_config(20), body);
  EXPECT_TRUE(s.ok()) << s.describe();
  task.join();
  EXPECT_TRUE(task.finished());
  EXPECT_EQ(body.calls, 20);
  EXPECT_EQ(task.perf().cycles, 20u);
}

TEST(RtosPeriodicTask, RequestStopEndsAnOpenEndedTask) {
  std::atomic<int> calls{0};
  auto body = [&calls](const CycleInfo&) noexcept { calls.fetch_add(1, std::memory_order_relaxed); };
  PeriodicTask task;
  ASSERT_TRUE(task.start(unprivileged_config(0), body).ok());
  // Bounded wait (10 s) for a few cycles; normally a few ms.
  for (int i = 0; i < 10'000 && calls.load() < 3; ++i) sleep_until_ns_rt(now_ns() + kPeriodNs);
  EXPECT_GE(calls.load(), 3);
  EXPECT_FALSE(task.finished());
  task.request_stop();
  task.join();
  EXPECT_TRUE(task.finished());
  const int after_stop = calls.load();
  EXPECT_EQ(static_cast<std::uint64_t>(after_stop), task.perf().cycles);
}

TEST(RtosPeriodicTask, RejectsBadPeriodAndDoubleStart) {
  RecordingBody body;
  PeriodicTask task;
  PeriodicConfig bad = unprivileged_config(1);
  bad.period_ns = 0;
  RtStatus s = task.start(bad, body);
  EXPECT_TRUE(s.failed(RtStep::kConfig));
  EXPECT_EQ(s.errno_by_step[static_cast<int>(RtStep::kConfig)], EINVAL);

  ASSERT_TRUE(task.start(unprivileged_config(0), body).ok());
  s = task.start(unprivileged_config(1), body);
  EXPECT_TRUE(s.failed(RtStep::kConfig));
  EXPECT_EQ(s.errno_by_step[static_cast<int>(RtStep::kConfig)], EBUSY);
  task.request_stop();
  task.join();
}

// CPU 1000 exists on no test machine (but is inside cpu_set_t), so affinity is
// refused with EINVAL whatever the privileges: a reliable way to exercise failure.
constexpr int kMissingCpu = 1000;

TEST(RtosPeriodicTask, RequiredSetupFailureMeansTheLoopNeverRuns) {
  RecordingBody body;
  PeriodicTask task;
  PeriodicConfig c = unprivileged_config(5);
  c.rt.cpu = kMissingCpu;
  c.rt.on_failure = RtFailurePolicy::kRequire;
  const RtStatus s = task.start(c, body);
  EXPECT_FALSE(s.ok());
  EXPECT_TRUE(s.failed(RtStep::kCpuAffinity));
  EXPECT_EQ(s.errno_by_step[static_cast<int>(RtStep::kCpuAffinity)], EINVAL);
  EXPECT_NE(s.describe().find("pthread_setaffinity_np failed: Invalid argument"), std::string::npos)
      << s.describe();
  task.join();
  EXPECT_TRUE(task.finished());
  EXPECT_EQ(body.calls, 0);
}

TEST(RtosPeriodicTask, BestEffortSetupFailureStillRuns) {
  RecordingBody body;
  PeriodicTask task;
  PeriodicConfig c = unprivileged_config(5);
  c.rt.cpu = kMissingCpu;
  const RtStatus s = task.start(c, body);
  EXPECT_TRUE(s.failed(RtStep::kCpuAffinity));
  task.join();
  EXPECT_EQ(body.calls, 5);
}

TEST(RtosPeriodicTask, SchedFifoGrantedOrReported) {
  // Privileged runs get SCHED_FIFO; unprivileged ones report it. Either way the
  // status must match what the thread really got.
  std::atomic<int> policy{-1};
  auto body = [&policy](const CycleInfo&) noexcept {
    int p = 0;
    sched_param param{};
    pthread_getschedparam(pthread_self(), &p, &param);
    policy.store(p);
  };
  PeriodicTask task;
  PeriodicConfig c = unprivileged_config(2);
  c.rt.fifo_priority = 10;  // low: never starves the other builds on this machine
  const RtStatus s = task.start(c, body);
  task.join();
  EXPECT_FALSE(s.failed(RtStep::kConfig));
  if (s.failed(RtStep::kSchedFifo)) {
    EXPECT_NE(policy.load(), SCHED_FIFO);
    EXPECT_NE(s.describe().find("pthread_setschedparam(SCHED_FIFO) failed"), std::string::npos);
  } else {
    EXPECT_EQ(policy.load(), SCHED_FIFO);
  }
}

}  // namespace
}  // namespace kuavo::rtos
