#include "drivers/cycle/canopen_io.h"

#include "drivers/cycle/rx_drain.h"

namespace kuavo::drivers {

CanopenReceiveReport canopen_receive_rt(CanPort& port, std::span<const canopen::DriveConfig> configs,
                                        std::span<canopen::DriveState> states, hal::TimeNs now_ns,
                                        hal::TimeNs realtime_to_monotonic_ns) {
  CanopenReceiveReport r;
  // Bounded: per drive 2 TPDOs, a heartbeat, an SDO answer, an EMCY, plus slack.
  const int limit = 8 * static_cast<int>(configs.size()) + 16;
  const DrainCounts counts =
      drain_classic_frames_rt(port, limit, now_ns, realtime_to_monotonic_ns, [&](const can_frame& f, hal::TimeNs stamp_ns) {
        bool claimed = false;
        for (std::size_t i = 0; i < configs.size() && i < states.size(); ++i) {
          claimed = canopen::handle_frame_rt(configs[i], states[i], f, stamp_ns) == DriverError::kOk || claimed;
        }
        if (claimed) {
          ++r.frames;
        } else {
          ++r.unclaimed;
        }
      });
  r.error_frames = counts.error_frames;
  r.unclaimed += counts.not_classic;
  r.peer_closed = counts.peer_closed;
  return r;
}

CanopenSendReport canopen_send_rt(CanPort& port, std::span<const canopen::DriveConfig> configs,
                                  std::span<canopen::DriveState> states,
                                  std::span<const canopen::DriveCommand> commands, hal::TimeNs now_ns) {
  CanopenSendReport r;
  can_frame frames[kMaxBatchFrames];
  DriverError results[kMaxBatchFrames];
  int count = 0;
  SendCounts counts;
  auto flush = [&] {
    send_batch_rt(port, std::span<const can_frame>(frames, count), std::span<DriverError>(results, count));
    count_sends(std::span<const DriverError>(results, count), counts);
  };
  const canopen::DriveCommand idle{};
  for (std::size_t i = 0; i < configs.size() && i < states.size(); ++i) {
    const canopen::DriveCommand& cmd = i < commands.size() ? commands[i] : idle;
    if (canopen::step_rt(configs[i], states[i], now_ns, cmd, frames[count]) && ++count == kMaxBatchFrames) {
      flush();
      count = 0;
    }
  }
  canopen::encode_sync_rt(frames[count++]);
  flush();
  r.sync_sent = results[count - 1] == DriverError::kOk;  // SYNC is the batch's last frame
  r.sent = counts.sent, r.dropped = counts.dropped, r.failed = counts.failed;
  return r;
}

}  // namespace kuavo::drivers
