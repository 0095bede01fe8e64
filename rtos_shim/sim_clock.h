// Virtual time for the simulator: advanced only by the lockstep scheduler, so a
// run's timing depends on nothing but its inputs. Same now_ns() shape as
// MonotonicClock, so code templated on the clock runs unchanged in both.
#pragma once

#include "controllers/hal/types.h"

namespace kuavo::rtos {

class SimClock {
 public:
  explicit SimClock(hal::TimeNs start_ns = 0) noexcept : now_ns_(start_ns) {}

  [[nodiscard]] hal::TimeNs now_ns() const noexcept { return now_ns_; }

  // Moves time forward to t_ns. Returns false (and leaves time unchanged) for a
  // step backwards: virtual time is monotonic like the real one.
  bool advance_to_ns(hal::TimeNs t_ns) noexcept {
    if (t_ns < now_ns_) return false;
    now_ns_ = t_ns;
    return true;
  }

 private:
  hal::TimeNs now_ns_;
};

}  // namespace kuavo::rtos
