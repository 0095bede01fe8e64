#include "drivers/cycle/ruiwo_io.h"

#include "drivers/cycle/rx_stamp.h"

namespace kuavo::drivers {

RuiwoReceiveReport ruiwo_receive_rt(CanPort& port, ruiwo::Bus& bus, hal::TimeNs now_ns,
                                    hal::TimeNs realtime_to_monotonic_ns, hal::SensorFrame& sensors) {
  RuiwoReceiveReport r;
  RxFrame rx;
  can_frame f;
  // Bounded: a babbling bus cannot hold the loop longer than this many frames.
  for (int n = 0; n < 4 * ruiwo::kMaxMotorsPerBus; ++n) {
    const DriverError e = receive_rt(port, rx);
    if (e == DriverError::kRxEmpty) break;
    if (e == DriverError::kPeerClosed) {
      r.peer_closed = true;
      break;
    }
    if (e == DriverError::kErrorFrame) {
      ++r.error_frames;
      continue;
    }
    if (e != DriverError::kOk || !as_classic(rx, f)) {
      ++r.rejected;
      continue;
    }
    const DriverError h = ruiwo::handle_reply_rt(bus, f, rx_stamp_ns(rx, now_ns, realtime_to_monotonic_ns), sensors);
    if (h == DriverError::kOk) {
      ++r.replies;
    } else if (h == DriverError::kMotorFault) {
      ++r.replies;
      ++r.faulted;
    } else {
      ++r.rejected;
    }
  }
  r.silent = ruiwo::check_timeouts_rt(bus, now_ns, sensors);
  return r;
}

RuiwoSendReport ruiwo_send_rt(CanPort& port, ruiwo::Bus& bus, const hal::CommandFrame& commands,
                              hal::TimeNs now_ns) {
  RuiwoSendReport r;
  can_frame f;
  for (int i = 0; i < bus.count; ++i) {
    const std::uint8_t flags = ruiwo::encode_command_rt(bus, i, commands.joints[bus.motors[i].joint], f);
    r.clamp_flags |= flags;
    if (flags != 0) ++r.clamped;
    const DriverError e = send_rt(port, f);
    if (e == DriverError::kOk) {
      ++r.sent;
    } else if (e == DriverError::kTxQueueFull) {
      ++r.dropped;
    } else {
      ++r.failed;
    }
    // Noted even when it did not leave the host: a request that cannot be sent
    // goes unanswered, so a full queue or a dead bus makes the motors silent
    // on the usual schedule instead of never.
    ruiwo::note_sent_rt(bus, i, now_ns);
  }
  return r;
}

}  // namespace kuavo::drivers
