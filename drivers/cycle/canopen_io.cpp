#include "drivers/cycle/canopen_io.h"

#include "drivers/cycle/rx_stamp.h"

namespace kuavo::drivers {

CanopenReceiveReport canopen_receive_rt(CanPort& port, std::span<const canopen::DriveConfig> configs,
                                        std::span<canopen::DriveState> states, hal::TimeNs now_ns,
                                        hal::TimeNs realtime_to_monotonic_ns) {
  CanopenReceiveReport r;
  RxFrame rx;
  can_frame f;
  // Bounded: per drive 2 TPDOs, a heartbeat, an SDO answer, an EMCY, plus slack.
  const int limit = 8 * static_cast<int>(configs.size()) + 16;
  for (int n = 0; n < limit; ++n) {
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
      ++r.unclaimed;
      continue;
    }
    const hal::TimeNs stamp = rx_stamp_ns(rx, now_ns, realtime_to_monotonic_ns);
    bool claimed = false;
    for (std::size_t i = 0; i < configs.size() && i < states.size(); ++i) {
      claimed = canopen::handle_frame_rt(configs[i], states[i], f, stamp) == DriverError::kOk || claimed;
    }
    if (claimed) {
      ++r.frames;
    } else {
      ++r.unclaimed;
    }
  }
  return r;
}

CanopenSendReport canopen_send_rt(CanPort& port, std::span<const canopen::DriveConfig> configs,
                                  std::span<canopen::DriveState> states,
                                  std::span<const canopen::DriveCommand> commands, hal::TimeNs now_ns) {
  CanopenSendReport r;
  can_frame f;
  auto send = [&](const can_frame& frame) {
    const DriverError e = send_rt(port, frame);
    if (e == DriverError::kOk) {
      ++r.sent;
      return true;
    }
    if (e == DriverError::kTxQueueFull) {
      ++r.dropped;
    } else {
      ++r.failed;
    }
    return false;
  };
  const canopen::DriveCommand idle{};
  for (std::size_t i = 0; i < configs.size() && i < states.size(); ++i) {
    const canopen::DriveCommand& cmd = i < commands.size() ? commands[i] : idle;
    if (canopen::step_rt(configs[i], states[i], now_ns, cmd, f)) send(f);
  }
  canopen::encode_sync_rt(f);
  r.sync_sent = send(f);
  return r;
}

}  // namespace kuavo::drivers
