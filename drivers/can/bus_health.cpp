#include "drivers/can/bus_health.h"

#include <linux/can/error.h>

namespace kuavo::drivers {

void apply_error_frame_rt(const can_frame& frame, BusHealth& health) {
  if ((frame.can_id & CAN_ERR_FLAG) == 0) return;
  const canid_t cls = frame.can_id & CAN_ERR_MASK;
  ++health.error_frames;
  if (cls & CAN_ERR_TX_TIMEOUT) ++health.tx_timeouts;
  if (cls & CAN_ERR_PROT) ++health.protocol_violations;
  if (cls & CAN_ERR_BUSOFF) health.bus_off = true;
  if (cls & CAN_ERR_RESTARTED) {
    ++health.restarts;
    health.error_passive = false;
    health.error_warning = false;
  }
  if (cls & CAN_ERR_CRTL) {
    ++health.controller_problems;
    // data[1] carries the controller status only when the frame has it.
    const std::uint8_t status = frame.len >= 2 ? frame.data[1] : 0;
    if (status & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) health.error_passive = true;
    if (status & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) health.error_warning = true;
    if (status & CAN_ERR_CRTL_ACTIVE) {
      health.error_passive = false;
      health.error_warning = false;
    }
  }
}

}  // namespace kuavo::drivers
