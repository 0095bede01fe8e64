// CiA 402 power state machine, seen from the master: decode the statusword,
// choose the controlword that moves the drive one step toward the wanted state.
// Transitions (CiA 402 figure): switch-on-disabled -(shutdown)-> ready to switch
// on -(switch on)-> switched on -(enable operation)-> operation enabled; a Fault
// leaves only through a fault-reset rising edge (bit 7) to switch-on-disabled.
#pragma once

#include <cstdint>

#include "drivers/driver_error.h"

namespace kuavo::drivers::canopen {

enum class Cia402State : std::uint8_t {
  kNotReadyToSwitchOn = 0,
  kSwitchOnDisabled = 1,
  kReadyToSwitchOn = 2,
  kSwitchedOn = 3,
  kOperationEnabled = 4,
  kQuickStopActive = 5,
  kFaultReactionActive = 6,
  kFault = 7,
};

const char* to_string(Cia402State s);

namespace controlword {
inline constexpr std::uint16_t kDisableVoltage = 0x0000;
inline constexpr std::uint16_t kQuickStop = 0x0002;
inline constexpr std::uint16_t kShutdown = 0x0006;
inline constexpr std::uint16_t kSwitchOn = 0x0007;  // also "disable operation"
inline constexpr std::uint16_t kEnableOperation = 0x000F;
inline constexpr std::uint16_t kFaultReset = 0x0080;
}  // namespace controlword

Cia402State decode_statusword(std::uint16_t statusword);

// Each enable request may try this many fault resets before giving up.
inline constexpr std::uint8_t kMaxFaultResets = 3;

struct Cia402Control {
  std::uint8_t fault_resets = 0;
  bool reset_bit_sent = false;  // last controlword had bit 7 set (edge bookkeeping)
};

// Controlword to send now, given the drive's state and whether the firmware
// wants torque. want_enabled == false walks the drive down to switch-on
// disabled (no torque) and re-arms the fault-reset budget. `error` becomes
// kFaultResetFailed when the budget is spent (the drive stays disabled), else kOk.
std::uint16_t next_controlword_rt(Cia402State state, bool want_enabled, Cia402Control& ctl,
                                  DriverError& error);

}  // namespace kuavo::drivers::canopen
