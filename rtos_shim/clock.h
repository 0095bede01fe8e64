// Monotonic time for the firmware. CLOCK_MONOTONIC never jumps with NTP or
// settimeofday, so deadlines and sample stamps stay ordered. Everything outside
// rtos_shim gets time from here (robot) or from SimClock (simulation).
#pragma once

#include "controllers/hal/types.h"

namespace kuavo::rtos {

using hal::TimeNs;

inline constexpr TimeNs kNsPerSecond = 1'000'000'000;

// Current CLOCK_MONOTONIC time in ns. Safe in the real-time context (vDSO, no syscall).
[[nodiscard]] TimeNs now_ns() noexcept;

// Blocks until CLOCK_MONOTONIC reaches deadline_ns (absolute, so sleeps do not
// accumulate drift). Resumes after signals. The one blocking call allowed in the
// real-time context: the periodic task's own sleep.
void sleep_until_ns_rt(TimeNs deadline_ns) noexcept;

// The clock type the firmware binding passes where the simulator passes SimClock.
struct MonotonicClock {
  [[nodiscard]] TimeNs now_ns() const noexcept { return rtos::now_ns(); }
};

}  // namespace kuavo::rtos
