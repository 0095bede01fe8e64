// The bounded receive loop every bus binding runs each cycle: read at most
// max_frames frames (up to kMaxBatchFrames per system call), stop at an empty
// queue, a closed peer or a failing socket, count controller error frames and
// frames that are not classic CAN (receive errors among them), hand the rest
// (with their monotonic sample time) to on_frame. Real-time safe: no heap,
// bounded.
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
  RxFrame rx[kMaxBatchFrames];
  DriverError results[kMaxBatchFrames];
  can_frame f;
  for (int n = 0; n < max_frames;) {
    const int want = max_frames - n < kMaxBatchFrames ? max_frames - n : kMaxBatchFrames;
    const int got = receive_batch_rt(port, std::span<RxFrame>(rx, want), std::span<DriverError>(results, want));
    for (int k = 0; k < got; ++k) {
      const DriverError e = results[k];
      if (e == DriverError::kPeerClosed) {
        counts.peer_closed = true;
        return counts;
      }
      if (e == DriverError::kErrorFrame) {
        ++counts.error_frames;
        continue;
      }
      if (e != DriverError::kOk || !as_classic(rx[k], f)) {
        ++counts.not_classic;
        continue;
      }
      on_frame(static_cast<const can_frame&>(f), rx_stamp_ns(rx[k], now_ns, realtime_to_monotonic_ns));
    }
    n += got;
    if (got < want || (got > 0 && results[got - 1] == DriverError::kIoError)) break;  // queue empty, or the socket failed
  }
  return counts;
}

}  // namespace kuavo::drivers
