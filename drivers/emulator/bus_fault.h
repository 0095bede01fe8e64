// Controller-level faults the emulated bus can report to the host, the way a
// SocketCAN interface does: as error frames (linux/can/error.h). Armed-only,
// like the frame faults.
#pragma once

#include "drivers/can/can_port.h"
#include "drivers/emulator/fault_injection.h"

namespace kuavo::drivers::emulator {

enum class BusFault : std::uint8_t {
  kErrorPassive = 0,  // CAN_ERR_CRTL, TX passive
  kBusOff = 1,        // CAN_ERR_BUSOFF
  kRestarted = 2,     // CAN_ERR_RESTARTED (after bus-off recovery)
};

// Sends the error frame on the emulator's end. false if disarmed or not sent.
bool inject_bus_fault(const FaultInjection& faults, CanPort& device_port, BusFault fault);

}  // namespace kuavo::drivers::emulator
