// Ruiwo arm/head motor frames (FACTS.md §5.2, from Leju's SimpleSDK.py): the
// MIT-Cheetah PTM command, the special enable/disable/zero frames and the
// status reply. Classic 8-byte CAN 2.0A frames, arbitration ID = motor ID.
//
// The SDK truncates and never clamps, so a value out of range would wrap on
// the wire. Here every value is clamped *before* packing and every clamp is
// reported to the caller as a flag. All functions are real-time safe.
#pragma once

#include <cstdint>
#include <linux/can.h>

#include "drivers/driver_error.h"

namespace kuavo::drivers::ruiwo {

// Field ranges, output side (FACTS.md §5.2 scaling table).
inline constexpr double kPositionMin_rad = -12.5, kPositionMax_rad = 12.5;
inline constexpr double kVelocityMin_rad_s = -10.0, kVelocityMax_rad_s = 10.0;
inline constexpr double kTorqueMin_Nm = -50.0, kTorqueMax_Nm = 50.0;
inline constexpr double kKpMax_Nm_per_rad = 250.0;
inline constexpr double kKdMax_Nm_s_per_rad = 50.0;

inline constexpr int kPositionBits = 16;
inline constexpr int kVelocityBits = 12;
inline constexpr int kGainBits = 12;
inline constexpr int kTorqueBits = 12;

// Special commands: bytes 0-6 = 0xFF, byte 7 selects.
enum class SpecialCommand : std::uint8_t {
  kEnable = 0xFC,   // enter motor state
  kDisable = 0xFD,  // reset state (no torque)
  kSetZero = 0xFE,  // current position becomes zero
};

// Bits of the clamp report; 0 means the frame carries exactly what was asked.
enum ClampFlag : std::uint8_t {
  kClampPosition = 1u << 0,
  kClampVelocity = 1u << 1,
  kClampKp = 1u << 2,
  kClampKd = 1u << 3,
  kClampTorque = 1u << 4,
  kNonFinite = 1u << 7,  // a NaN/Inf was replaced (by 0; position NaN also zeroes kp)
};

struct PtmCommand {
  double position_rad = 0.0;
  double velocity_rad_s = 0.0;
  double kp_Nm_per_rad = 0.0;
  double kd_Nm_s_per_rad = 0.0;
  double torque_Nm = 0.0;
};

struct Status {
  std::uint8_t motor_id = 0;
  double position_rad = 0.0;
  double velocity_rad_s = 0.0;
  double torque_Nm = 0.0;
  std::uint8_t temperature_raw = 0;  // driver-board temperature byte, unit undocumented
  std::uint8_t fault_code = 0;       // 0 = no fault
};

// u = (x - min) / (max - min) * (2^bits - 1), truncated like the SDK.
// x must already be inside [min, max].
std::uint32_t to_uint(double x, double min, double max, int bits);
double from_uint(std::uint32_t u, double min, double max, int bits);

// Clamps `cmd` in place to the wire ranges; returns the ClampFlag bits.
std::uint8_t clamp_ptm_rt(PtmCommand& cmd);

// Packs a PTM command (clamping a copy first). Returns the ClampFlag bits.
std::uint8_t encode_ptm_rt(std::uint8_t motor_id, const PtmCommand& cmd, can_frame& out);
void encode_special_rt(std::uint8_t motor_id, SpecialCommand cmd, can_frame& out);
// Multi-turn encoder zeroing: ID 0x600 + motor ID, payload 67 06 FE 00 00 00 00 76.
void encode_multiturn_zero_rt(std::uint8_t motor_id, can_frame& out);

// The motor's side of the protocol, for the bus emulator and tests: unpack a
// PTM command; pack a status reply (values clamped to the wire ranges).
DriverError decode_ptm_rt(const can_frame& frame, PtmCommand& out);
void encode_status_rt(const Status& status, can_frame& out);

// Decodes a status reply (8 bytes, byte 0 = motor ID). kOk, kWrongLength,
// kRemoteFrame or kWrongCanId (error or extended frame).
DriverError decode_status_rt(const can_frame& frame, Status& out);

}  // namespace kuavo::drivers::ruiwo
