// Sample time of a received frame on the firmware's monotonic clock: the
// kernel receive stamp (CLOCK_REALTIME) shifted by the offset rtos_shim
// measured this cycle, or the cycle time if the socket gave no stamp.
#pragma once

#include "drivers/can/can_port.h"

namespace kuavo::drivers {

inline hal::TimeNs rx_stamp_ns(const RxFrame& rx, hal::TimeNs now_ns, hal::TimeNs realtime_to_monotonic_ns) {
  return rx.rx_realtime_ns != 0 ? rx.rx_realtime_ns + realtime_to_monotonic_ns : now_ns;
}

}  // namespace kuavo::drivers
