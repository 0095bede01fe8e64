// Bus state as reported by the CAN controller through SocketCAN error frames
// (linux/can/error.h). Bus-off latches: the controller stops transmitting and
// the firmware must treat every device on that bus as silent until restart.
#pragma once

#include <cstdint>
#include <linux/can.h>

namespace kuavo::drivers {

struct BusHealth {
  bool bus_off = false;          // latched; cleared only by clear_bus_off()
  bool error_passive = false;    // TX or RX error counter >= 128
  bool error_warning = false;    // TX or RX error counter >= 96
  std::uint32_t error_frames = 0;
  std::uint32_t controller_problems = 0;  // overflows, warnings, passive transitions
  std::uint32_t tx_timeouts = 0;
  std::uint32_t protocol_violations = 0;
  std::uint32_t restarts = 0;             // controller came back after bus-off
};

// Folds one error frame (CAN_ERR_FLAG set) into the health record. Ignores
// frames without CAN_ERR_FLAG. Real-time safe.
void apply_error_frame_rt(const can_frame& frame, BusHealth& health);

// After the interface has been restarted (ip link / restart-ms) and a
// CAN_ERR_RESTARTED frame seen, the firmware may clear the latch.
inline void clear_bus_off(BusHealth& health) { health.bus_off = false; }

}  // namespace kuavo::drivers
