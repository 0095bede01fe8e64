#include "rtos_shim/periodic_perf.h"

namespace kuavo::rtos {

void PeriodicPerf::record_rt(TimeNs wake_latency_ns, TimeNs cycle_ns, bool overrun,
                             std::uint64_t skipped_periods) noexcept {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  // Single writer: plain load + store is enough, no read-modify-write needed.
  cycles_.store(cycles_.load(kRelaxed) + 1, kRelaxed);
  if (overrun) overruns_.store(overruns_.load(kRelaxed) + 1, kRelaxed);
  if (skipped_periods != 0) {
    skipped_periods_.store(skipped_periods_.load(kRelaxed) + skipped_periods, kRelaxed);
  }
  last_cycle_ns_.store(cycle_ns, kRelaxed);
  if (cycle_ns > max_cycle_ns_.load(kRelaxed)) max_cycle_ns_.store(cycle_ns, kRelaxed);
  last_wake_latency_ns_.store(wake_latency_ns, kRelaxed);
  if (wake_latency_ns > max_wake_latency_ns_.load(kRelaxed)) {
    max_wake_latency_ns_.store(wake_latency_ns, kRelaxed);
  }
}

PeriodicPerfSnapshot PeriodicPerf::snapshot() const noexcept {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  PeriodicPerfSnapshot s;
  s.cycles = cycles_.load(kRelaxed);
  s.overruns = overruns_.load(kRelaxed);
  s.skipped_periods = skipped_periods_.load(kRelaxed);
  s.last_cycle_ns = last_cycle_ns_.load(kRelaxed);
  s.max_cycle_ns = max_cycle_ns_.load(kRelaxed);
  s.last_wake_latency_ns = last_wake_latency_ns_.load(kRelaxed);
  s.max_wake_latency_ns = max_wake_latency_ns_.load(kRelaxed);
  return s;
}

void PeriodicPerf::reset() noexcept {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  cycles_.store(0, kRelaxed);
  overruns_.store(0, kRelaxed);
  skipped_periods_.store(0, kRelaxed);
  last_cycle_ns_.store(0, kRelaxed);
  max_cycle_ns_.store(0, kRelaxed);
  last_wake_latency_ns_.store(0, kRelaxed);
  max_wake_latency_ns_.store(0, kRelaxed);
}

}  // namespace kuavo::rtos
