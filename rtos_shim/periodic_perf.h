// Perf counters of a periodic loop (cycle time, wake-up latency, deadline misses)
// and the pure deadline bookkeeping behind them, kept free of clocks so it can
// be tested with made-up times.
#pragma once

#include <atomic>
#include <cstdint>

#include "controllers/hal/types.h"

namespace kuavo::rtos {

using hal::TimeNs;

// A consistent-enough copy for reporting: each field is exact, fields may be
// from neighbouring cycles when read while the loop runs.
struct PeriodicPerfSnapshot {
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;         // cycles that ended after the next deadline
  std::uint64_t skipped_periods = 0;  // release times dropped to recover from overruns
  TimeNs last_cycle_ns = 0;           // body run time (wake to end) of the last cycle
  TimeNs max_cycle_ns = 0;
  TimeNs last_wake_latency_ns = 0;    // actual wake time minus deadline
  TimeNs max_wake_latency_ns = 0;
};

// Written by the loop thread only (relaxed atomics: no ordering needed, just
// untorn values for a monitor thread).
class PeriodicPerf {
 public:
  void record_rt(TimeNs wake_latency_ns, TimeNs cycle_ns, bool overrun,
                 std::uint64_t skipped_periods) noexcept;
  [[nodiscard]] PeriodicPerfSnapshot snapshot() const noexcept;
  void reset() noexcept;

 private:
  std::atomic<std::uint64_t> cycles_{0};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> skipped_periods_{0};
  std::atomic<TimeNs> last_cycle_ns_{0};
  std::atomic<TimeNs> max_cycle_ns_{0};
  std::atomic<TimeNs> last_wake_latency_ns_{0};
  std::atomic<TimeNs> max_wake_latency_ns_{0};

  static_assert(std::atomic<TimeNs>::is_always_lock_free);
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free);
};

// Where the loop goes after a cycle that was released at deadline_ns and ended at end_ns.
struct NextRelease {
  TimeNs deadline_ns;             // next absolute wake time, always > end_ns or == the regular one
  bool overrun;                   // the cycle ended after the regular next deadline
  std::uint64_t skipped_periods;  // regular release times dropped (0 without overrun)
};

// Regular case: deadline + period. Overrun (end past that): skip to the first
// release time on the original grid that is still ahead, instead of running
// back-to-back catch-up cycles -- a late control tick is worth less than a
// fresh one, and bursts would starve the other threads. The grid is kept so
// the phase relative to the other tasks does not drift. Real-time safe.
[[nodiscard]] constexpr NextRelease next_release(TimeNs deadline_ns, TimeNs end_ns,
                                                 TimeNs period_ns) noexcept {
  const TimeNs regular_ns = deadline_ns + period_ns;
  if (end_ns <= regular_ns) return {regular_ns, false, 0};
  // Whole periods elapsed since the deadline; >= 1 here.
  const auto elapsed_periods = static_cast<std::uint64_t>((end_ns - deadline_ns) / period_ns);
  return {deadline_ns + static_cast<TimeNs>(elapsed_periods + 1) * period_ns, true,
          elapsed_periods};
}

}  // namespace kuavo::rtos
