// One Ruiwo bus per control cycle, split where the controller runs:
//   ruiwo_receive_rt  - replies to last cycle's commands -> sensors, then timeouts
//   (controller)
//   ruiwo_send_rt     - this cycle's commands, clamped and reported
// Real-time safe.
#pragma once

#include <cstdint>

#include "controllers/hal/types.h"
#include "drivers/can/can_port.h"
#include "drivers/ruiwo/ruiwo_bus.h"

namespace kuavo::drivers {

struct RuiwoReceiveReport {
  int replies = 0;          // status frames matched to a motor
  int rejected = 0;         // undecodable, unknown ID, or FD frames
  int faulted = 0;          // replies with a non-zero fault byte
  int error_frames = 0;     // controller error frames (see port.health)
  int silent = 0;           // motors past kMaxConsecutiveMisses
  bool peer_closed = false;
};

struct RuiwoSendReport {
  int sent = 0;
  int dropped = 0;          // kTxQueueFull: resent with fresh values next cycle
  int failed = 0;           // bus-off or I/O error
  int clamped = 0;          // motors whose command needed any clamp
  std::uint8_t clamp_flags = 0;  // union of ruiwo::ClampFlag over the bus
};

RuiwoReceiveReport ruiwo_receive_rt(CanPort& port, ruiwo::Bus& bus, hal::TimeNs now_ns,
                                    hal::TimeNs realtime_to_monotonic_ns, hal::SensorFrame& sensors);

RuiwoSendReport ruiwo_send_rt(CanPort& port, ruiwo::Bus& bus, const hal::CommandFrame& commands,
                              hal::TimeNs now_ns);

}  // namespace kuavo::drivers
