// Emulated Ruiwo motor boards on the far end of a socketpair: every command
// frame gets the status reply a real board would send, computed from the
// motor state the simulator writes in (position, velocity at the motor). The
// torque the plant should apply follows the MIT law with the last command:
// tau = kp (p_des - p) + kd (v_des - v) + tau_ff, 0 while disabled.
// Heap-free; `serve_rt` never blocks.
#pragma once

#include <array>
#include <cstdint>

#include "drivers/can/can_port.h"
#include "drivers/emulator/fault_injection.h"
#include "drivers/ruiwo/ruiwo_codec.h"

namespace kuavo::drivers::emulator {

struct EmulatedRuiwoMotor {
  std::uint8_t id = 0;
  bool enabled = false;         // after the 0xFC frame
  bool silent = false;          // fault injection: never answers
  std::uint8_t fault_code = 0;  // sent in byte 7
  std::uint8_t temperature_raw = 35;
  double position_rad = 0.0;    // plant state, motor side
  double velocity_rad_s = 0.0;
  double zero_rad = 0.0;        // set by the 0xFE frame
  ruiwo::PtmCommand command{};  // last command as decoded from the wire
};

inline constexpr int kMaxEmulatedRuiwo = 16;

struct RuiwoEmulator {
  std::array<EmulatedRuiwoMotor, kMaxEmulatedRuiwo> motors{};
  int count = 0;
  std::array<std::int8_t, 256> index_of_id{};
  FaultInjection faults{};
  std::uint32_t frames_in = 0, replies_out = 0, replies_dropped = 0, unknown_frames = 0;
};

// Adds motors with these IDs (start-up).
void init_ruiwo_emulator(RuiwoEmulator& emu, const std::uint8_t* ids, int count);

// Answers every frame waiting on `port`. Returns the number of frames handled.
int serve_rt(RuiwoEmulator& emu, CanPort& port);

// Torque the plant applies for motor `index`, from its current state.
double motor_torque_Nm(const EmulatedRuiwoMotor& m);

// Fault injection: refused (false) while emu.faults is disarmed.
bool set_silent(RuiwoEmulator& emu, std::uint8_t id, bool silent);

}  // namespace kuavo::drivers::emulator
