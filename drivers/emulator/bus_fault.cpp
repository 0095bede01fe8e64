#include "drivers/emulator/bus_fault.h"

#include <linux/can/error.h>

namespace kuavo::drivers::emulator {

bool inject_bus_fault(const FaultInjection& faults, CanPort& device_port, BusFault fault) {
  if (!faults.armed) return false;
  can_frame f{};
  f.len = CAN_ERR_DLC;
  switch (fault) {
    case BusFault::kErrorPassive:
      f.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
      f.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
      break;
    case BusFault::kBusOff: f.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF; break;
    case BusFault::kRestarted: f.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED; break;
  }
  // The emulator's end must not refuse to send because of its own health.
  CanPort raw = device_port;
  raw.health = BusHealth{};
  return send_rt(raw, f) == DriverError::kOk;
}

}  // namespace kuavo::drivers::emulator
