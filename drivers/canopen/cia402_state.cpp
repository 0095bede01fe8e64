#include "drivers/canopen/cia402_state.h"

namespace kuavo::drivers::canopen {

const char* to_string(Cia402State s) {
  switch (s) {
    case Cia402State::kNotReadyToSwitchOn: return "not ready to switch on";
    case Cia402State::kSwitchOnDisabled: return "switch on disabled";
    case Cia402State::kReadyToSwitchOn: return "ready to switch on";
    case Cia402State::kSwitchedOn: return "switched on";
    case Cia402State::kOperationEnabled: return "operation enabled";
    case Cia402State::kQuickStopActive: return "quick stop active";
    case Cia402State::kFaultReactionActive: return "fault reaction active";
    case Cia402State::kFault: return "fault";
  }
  return "unknown";
}

Cia402State decode_statusword(std::uint16_t sw) {
  // Masks from CiA 402 table "state coding": bits 0-3, 5 and 6.
  if ((sw & 0x004F) == 0x0000) return Cia402State::kNotReadyToSwitchOn;
  if ((sw & 0x004F) == 0x0040) return Cia402State::kSwitchOnDisabled;
  if ((sw & 0x006F) == 0x0021) return Cia402State::kReadyToSwitchOn;
  if ((sw & 0x006F) == 0x0023) return Cia402State::kSwitchedOn;
  if ((sw & 0x006F) == 0x0027) return Cia402State::kOperationEnabled;
  if ((sw & 0x006F) == 0x0007) return Cia402State::kQuickStopActive;
  if ((sw & 0x004F) == 0x000F) return Cia402State::kFaultReactionActive;
  if ((sw & 0x004F) == 0x0008) return Cia402State::kFault;
  // Undefined codings: treat as not ready, which commands nothing.
  return Cia402State::kNotReadyToSwitchOn;
}

std::uint16_t next_controlword_rt(Cia402State state, bool want_enabled, Cia402Control& ctl,
                                  DriverError& error) {
  error = DriverError::kOk;
  if (!want_enabled) {
    ctl.fault_resets = 0;
    ctl.reset_bit_sent = false;
    // Disable voltage works from every state and never needs a fault reset.
    return controlword::kDisableVoltage;
  }
  switch (state) {
    case Cia402State::kFault: {
      if (ctl.reset_bit_sent) {
        // Bit 7 must drop before the next rising edge.
        ctl.reset_bit_sent = false;
        return controlword::kDisableVoltage;
      }
      if (ctl.fault_resets >= kMaxFaultResets) {
        error = DriverError::kFaultResetFailed;
        return controlword::kDisableVoltage;
      }
      ++ctl.fault_resets;
      ctl.reset_bit_sent = true;
      return controlword::kFaultReset;
    }
    case Cia402State::kFaultReactionActive:
    case Cia402State::kNotReadyToSwitchOn:
      ctl.reset_bit_sent = false;
      return controlword::kDisableVoltage;  // wait; the drive moves on by itself
    case Cia402State::kSwitchOnDisabled:
    case Cia402State::kQuickStopActive:  // leave quick stop through disabled
      ctl.reset_bit_sent = false;
      return state == Cia402State::kQuickStopActive ? controlword::kDisableVoltage
                                                     : controlword::kShutdown;
    case Cia402State::kReadyToSwitchOn:
      return controlword::kSwitchOn;
    case Cia402State::kSwitchedOn:
    case Cia402State::kOperationEnabled:
      return controlword::kEnableOperation;
  }
  return controlword::kDisableVoltage;
}

}  // namespace kuavo::drivers::canopen
