// How long the machine takes a running CPU away from a real-time thread: the floor under
// any worst-case cycle measured on it. A thread spins reading the clock; a gap between two
// consecutive reads much longer than one read (~20-50 ns) is time the CPU spent elsewhere --
// an interrupt, an SMI, or on a VM the host running something else on that vCPU. Like the
// kernel's hwlat tracer, but on the real-time thread's own CPU and priority, in bursts of a
// control period's share so the kernel's real-time throttling (sched_rt_runtime_us: 950 ms
// of each second for SCHED_FIFO) never cuts in. `kuavo_fw --timing` runs it after the dance
// (firmware/timing.h): a cycle maximum near this floor is the machine's, not the controller's.
#pragma once

#include <array>
#include <cstdint>

#include "controllers/hal/types.h"

namespace kuavo::rtos {

// The gap lengths counted apart [ns].
inline constexpr std::array<hal::TimeNs, 4> kStallThresholds_ns = {10'000, 50'000, 100'000, 150'000};

struct StallStats {
  std::uint64_t reads = 0;       // clock reads
  hal::TimeNs spun_ns = 0;       // time covered by the spins (first read to last, per burst)
  hal::TimeNs max_gap_ns = 0;    // longest time between two consecutive reads
  std::array<std::uint64_t, kStallThresholds_ns.size()> gaps_over{};  // gaps longer than each threshold
};

// One burst: reads `clock` (any type with now_ns()) until spin_ns have passed since the
// first read, adding each gap between consecutive reads to `stats`. No allocation, no
// system call with the monotonic clock (vDSO).
template <class Clock>
void stall_probe_spin_rt(const Clock& clock, hal::TimeNs spin_ns, StallStats& stats) noexcept {
  const hal::TimeNs start = clock.now_ns();
  hal::TimeNs last = start;
  ++stats.reads;
  while (last - start < spin_ns) {
    const hal::TimeNs t = clock.now_ns();
    ++stats.reads;
    const hal::TimeNs gap = t - last;
    if (gap > stats.max_gap_ns) stats.max_gap_ns = gap;
    for (std::size_t i = 0; i < kStallThresholds_ns.size(); ++i) stats.gaps_over[i] += gap > kStallThresholds_ns[i];
    last = t;
  }
  stats.spun_ns += last - start;
}

}  // namespace kuavo::rtos
