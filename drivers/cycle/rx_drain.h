// The bounded receive loop every bus binding runs each cycle: read at most
// max_frames frames, stop at an empty queue or a closed peer, count controller
// error frames and frames that are not classic CAN, hand the rest (with their
// monotonic sample time) to on_frame. Real-time safe: no heap, bounded.
#pragma once

#include "drivers/cycle/rx_stamp.h"

namespace kuavo::drivers {

struct DrainCounts {
  int error_frames = 0;  // controller error frames (see port.health)
  int not_classic = 0;   // receive errors and FD frames
  bool peer_closed = false;
};

// on_frame(const can_frame&, hal::TimeNs stamp_ns)
template <typename OnFrame>
DrainCounts drain_classic_frames_rt(CanPort& port, int max_frames, hal::TimeNs now_ns,
                                    hal::TimeNs realtime_to_monotonic_ns, OnFrame&& on_frame) {
  DrainCounts counts;
  RxFrame rx;
  can_frame f;
  for (int n = 0; n < max_frames; ++n) {
    const DriverError e = receive_rt(port, rx);
    if (e == DriverError::kRxEmpty) break;
    if (e == DriverError::kPeerClosed) {
      counts.peer_closed = true;
      break;
    }
    if (e == DriverError::kErrorFrame) {
      ++counts.error_frames;
      continue;
    }
    if (e != DriverError::kOk || !as_classic(rx, f)) {
      ++counts.not_classic;
      continue;
    }
    on_frame(static_cast<const can_frame&>(f), rx_stamp_ns(rx, now_ns, realtime_to_monotonic_ns));
  }
  return counts;
}

}  // namespace kuavo::drivers
