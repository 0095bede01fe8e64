// The periodic loop itself, run on the calling thread: sleep to an absolute
// deadline, run the body, account, repeat. Absolute deadlines (clock_nanosleep
// TIMER_ABSTIME) keep the rate exact however long each body takes; overruns are
// counted and recovered from as next_release() describes. PeriodicTask runs this
// on its own real-time thread; it is public so it can be used on a thread the
// caller set up itself.
#pragma once

#include <atomic>
#include <cstdint>

#include "rtos_shim/clock.h"
#include "rtos_shim/periodic_perf.h"

namespace kuavo::rtos {

// What the body learns about its cycle.
struct CycleInfo {
  std::uint64_t cycle = 0;  // 0, 1, 2, ... (cycles run, not release times)
  TimeNs deadline_ns = 0;   // scheduled release time (CLOCK_MONOTONIC)
  TimeNs wake_ns = 0;       // when the thread actually woke
};

// Runs body(const CycleInfo&) every period_ns until `stop` is set or max_cycles
// cycles have run (0 = no limit). The first release is one period after the call.
// Returns the number of cycles run. The body is called directly (no type erasure,
// no allocation) and must itself be real-time safe and must not throw.
template <class Body>
std::uint64_t run_periodic_loop_rt(TimeNs period_ns, std::uint64_t max_cycles,
                                   const std::atomic<bool>& stop, PeriodicPerf& perf,
                                   Body& body) noexcept {
  std::uint64_t cycle = 0;
  TimeNs deadline_ns = now_ns() + period_ns;
  while ((max_cycles == 0 || cycle < max_cycles) && !stop.load(std::memory_order_relaxed)) {
    sleep_until_ns_rt(deadline_ns);
    const TimeNs wake_ns = now_ns();
    body(CycleInfo{cycle, deadline_ns, wake_ns});
    const TimeNs end_ns = now_ns();
    const NextRelease next = next_release(deadline_ns, end_ns, period_ns);
    perf.record_rt(wake_ns - deadline_ns, end_ns - wake_ns, next.overrun, next.skipped_periods);
    deadline_ns = next.deadline_ns;
    ++cycle;
  }
  return cycle;
}

}  // namespace kuavo::rtos
