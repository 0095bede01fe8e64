// Emulated CiA 402 drives on one CANopen bus (far end of a socketpair): NMT,
// boot-up and heartbeat production, expedited SDO downloads into a small
// object dictionary, the 402 power state machine driven by RPDO1's
// controlword, CST target torque or CSP (target position, torque offset and
// the position-loop gains 0x2010 written by SDO), and TPDO1/TPDO2 answered on
// every SYNC once mapped. The simulator writes the motor state and reads the
// applied torque; in CSP it evaluates drive_torque_at_Nm at its own states
// (the drive's fast loop, continuous). Everything comes from decoded frames.
// Heap-free; `serve_rt` never blocks.
#pragma once

#include <array>
#include <cstdint>

#include "controllers/hal/types.h"
#include "drivers/can/can_port.h"
#include "drivers/canopen/canopen_frames.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/canopen/cia402_state.h"
#include "drivers/emulator/fault_injection.h"

namespace kuavo::drivers::emulator {

struct EmulatedDrive {
  canopen::DriveConfig config{};  // node ID, counts per turn, rated torque
  canopen::NmtState nmt = canopen::NmtState::kUnknown;  // kUnknown = powered off / not booted
  canopen::Cia402State power = canopen::Cia402State::kSwitchOnDisabled;
  bool last_reset_bit = false;
  bool silent = false;           // fault injection: sends nothing
  bool rpdo1_mapped = false, tpdo1_mapped = false, tpdo2_mapped = false;
  std::uint16_t heartbeat_period_ms = 0;  // 0x1017
  std::int8_t mode = 0;                   // 0x6060
  std::int16_t target_torque_permille = 0;  // the RPDO1 i16: target torque or torque offset
  std::int32_t target_position_counts = 0;  // 0x607A (CSP)
  std::uint16_t rpdo1_torque_object = 0;    // what RPDO1 maps there: 0x6071 or 0x60B2
  std::uint32_t kp_register = 0, kd_register = 0;  // 0x2010 sub 1, 2
  std::uint16_t error_code = 0;           // 0x603F
  hal::TimeNs next_heartbeat_ns = 0;
  double position_rad = 0.0;   // plant state, motor side
  double velocity_rad_s = 0.0;
  // What the last two TPDOs reported (as quantized on the wire), newest first: the samples
  // a CSP offset received now was written against (a wire inspector's reference).
  std::array<double, 2> reported_position_rad{}, reported_velocity_rad_s{};
  std::uint32_t sdo_writes = 0;
};

inline constexpr int kMaxEmulatedDrives = 8;

struct Cia402Emulator {
  std::array<EmulatedDrive, kMaxEmulatedDrives> drives{};
  int count = 0;
  FaultInjection faults{};
  std::uint32_t frames_in = 0, frames_out = 0, syncs = 0;
  std::uint32_t frames_dropped = 0;  // not sent: lost (fault injection) or from a silent drive
};

// Adds a drive (start-up). It boots (sends its boot-up message) on the first
// serve_rt after an NMT reset, like a drive powered on with the bus.
void add_drive(Cia402Emulator& emu, const canopen::DriveConfig& config);

// Handles every waiting frame and produces due heartbeats. Returns frames handled.
int serve_rt(Cia402Emulator& emu, CanPort& port, hal::TimeNs now_ns);

// Torque the drive produces (motor side) at motor state (position, velocity),
// 0 unless operation enabled and NMT operational:
//   CST (mode 10): the target torque (0x6071 mapped), whatever the state;
//   CSP (mode 8):  kp (target - position) - kd velocity + torque offset (0x60B2
//                  mapped, else 0), limited to +-config.torque_limit_Nm (the
//                  drive's max torque; `saturated` reports it).
// Any other mode: 0.
double drive_torque_at_Nm(const EmulatedDrive& d, double position_rad, double velocity_rad_s,
                          bool* saturated = nullptr);
// At the drive's own last written state (what TPDO1 reports).
double drive_torque_Nm(const EmulatedDrive& d);

// Fault injection (refused while disarmed): silence a drive or latch a fault.
bool set_drive_silent(Cia402Emulator& emu, std::uint8_t node, bool silent);
bool inject_drive_fault(Cia402Emulator& emu, std::uint8_t node, std::uint16_t error_code);

}  // namespace kuavo::drivers::emulator
