#include "drivers/cycle/ruiwo_io.h"

#include "drivers/cycle/rx_drain.h"

namespace kuavo::drivers {

RuiwoReceiveReport ruiwo_receive_rt(CanPort& port, ruiwo::Bus& bus, hal::TimeNs now_ns,
                                    hal::TimeNs realtime_to_monotonic_ns, hal::SensorFrame& sensors) {
  RuiwoReceiveReport r;
  // Bounded: a babbling bus cannot hold the loop longer than this many frames.
  const DrainCounts counts = drain_classic_frames_rt(
      port, 4 * ruiwo::kMaxMotorsPerBus, now_ns, realtime_to_monotonic_ns,
      [&](const can_frame& f, hal::TimeNs stamp_ns) {
        const DriverError h = ruiwo::handle_reply_rt(bus, f, stamp_ns, sensors);
        if (h == DriverError::kOk) {
          ++r.replies;
        } else if (h == DriverError::kMotorFault) {
          ++r.replies;
          ++r.faulted;
        } else {
          ++r.rejected;
        }
      });
  r.error_frames = counts.error_frames;
  r.rejected += counts.not_classic;
  r.peer_closed = counts.peer_closed;
  r.silent = ruiwo::check_timeouts_rt(bus, now_ns, sensors);
  return r;
}

RuiwoSendReport ruiwo_send_rt(CanPort& port, ruiwo::Bus& bus, const hal::CommandFrame& commands,
                              hal::TimeNs now_ns) {
  RuiwoSendReport r;
  SendCounts counts;
  can_frame frames[kMaxBatchFrames];
  DriverError results[kMaxBatchFrames];
  for (int first = 0; first < bus.count; first += kMaxBatchFrames) {
    const int count = bus.count - first < kMaxBatchFrames ? bus.count - first : kMaxBatchFrames;
    for (int k = 0; k < count; ++k) {
      const int i = first + k;
      const std::uint8_t flags = ruiwo::encode_command_rt(bus, i, commands.joints[bus.motors[i].joint], frames[k]);
      r.clamp_flags |= flags;
      if (flags != 0) ++r.clamped;
    }
    send_batch_rt(port, std::span<const can_frame>(frames, count), std::span<DriverError>(results, count));
    count_sends(std::span<const DriverError>(results, count), counts);
    for (int k = 0; k < count; ++k) {
      // Noted even when it did not leave the host: a request that cannot be sent
      // goes unanswered, so a full queue or a dead bus makes the motors silent
      // on the usual schedule instead of never.
      ruiwo::note_sent_rt(bus, first + k, now_ns);
    }
  }
  r.sent = counts.sent, r.dropped = counts.dropped, r.failed = counts.failed;
  return r;
}

}  // namespace kuavo::drivers
