// Our PDO layout for the CiA 402 drives (FACTS.md §5.1 lists the objects the
// EtherCAT drives exchange; on classic CAN they must fit 8-byte PDOs, so the
// layout is ours). All PDOs are synchronous: RPDOs take effect at the next
// SYNC, TPDOs are sampled at every SYNC (transmission type 1).
//
//   RPDO1 0x200+n: controlword 0x6040 (u16) | target torque 0x6071 (i16, per mille
//                  of rated torque 0x6076) | target position 0x607A (i32, counts)
//                  In CSP (mode 8) the i16 maps torque offset 0x60B2 instead: the
//                  drive closes tau = kp (target - actual position) - kd actual
//                  velocity + torque offset in its own fast loop, kp/kd being its
//                  position-loop gain registers (our object 0x2010, written at
//                  start-up). There is no room for velocity offset 0x60B1 in the
//                  8 bytes: the master folds kd * v_ref into the torque offset (exact,
//                  the drive's kd being fixed and known), which keeps one RPDO per
//                  drive per cycle (bus load unchanged).
//   TPDO1 0x180+n: statusword 0x6041 (u16) | actual torque 0x6077 (i16, per mille)
//                  | actual position 0x6064 (i32, counts)
//   TPDO2 0x280+n: actual velocity 0x606C (i32, counts/s) | error code 0x603F
//                  (u16) | mode display 0x6061 (i8)
#pragma once

#include <array>
#include <cstdint>
#include <linux/can.h>

#include "drivers/canopen/canopen_frames.h"
#include "drivers/driver_error.h"

namespace kuavo::drivers::canopen {

inline constexpr std::int8_t kModeCyclicSyncTorque = 10;    // CST, CiA 402 0x6060
inline constexpr std::int8_t kModeCyclicSyncPosition = 8;   // CSP

// Drive-internal position-loop gains (motor side), manufacturer-specific object:
// sub 1 kp in 0.001 N m/rad, sub 2 kd in 0.001 N m s/rad (u32). The real Youda
// drives keep such gains in vendor registers whose units FACTS.md §4.3 does not
// give; this object is ours, the emulated drive implements it.
inline constexpr std::uint16_t kObjPositionLoopGains = 0x2010;
inline constexpr std::uint16_t kObjTargetTorque = 0x6071;
inline constexpr std::uint16_t kObjTorqueOffset = 0x60B2;
inline constexpr double kGainRegisterPerUnit = 1000.0;
// Gain -> register: false (register untouched) for NaN, negative or above
// 4'000'000 (u32 range with margin). Rounds to the nearest 0.001.
bool gain_to_register(double gain, std::uint32_t& reg);
inline double register_to_gain(std::uint32_t reg) { return static_cast<double>(reg) / kGainRegisterPerUnit; }

// What the drive's cyclic mode needs configured.
struct DriveLoop {
  std::int8_t mode = kModeCyclicSyncTorque;  // kModeCyclicSyncTorque or kModeCyclicSyncPosition
  std::uint32_t kp_register = 0;              // CSP only (0x2010 sub 1)
  std::uint32_t kd_register = 0;              // CSP only (0x2010 sub 2)
};

struct RxPdo1 {
  std::uint16_t controlword = 0;
  std::int16_t target_torque_permille = 0;  // CST: target torque; CSP: torque offset
  std::int32_t target_position_counts = 0;
};

struct TxPdo1 {
  std::uint16_t statusword = 0;
  std::int16_t actual_torque_permille = 0;
  std::int32_t actual_position_counts = 0;
};

struct TxPdo2 {
  std::int32_t actual_velocity_counts_s = 0;
  std::uint16_t error_code = 0;
  std::int8_t mode_display = 0;
};

void encode_rpdo1_rt(std::uint8_t node, const RxPdo1& pdo, can_frame& out);
// The drive's side (emulator): kWrongCanId if not this node's RPDO1, kWrongLength
// unless 8 bytes, kRemoteFrame for RTR.
DriverError decode_rpdo1_rt(const can_frame& f, std::uint8_t node, RxPdo1& out);
// kWrongCanId if the frame is not this node's TPDO, kWrongLength if short.
DriverError decode_tpdo1_rt(const can_frame& f, std::uint8_t node, TxPdo1& out);
DriverError decode_tpdo2_rt(const can_frame& f, std::uint8_t node, TxPdo2& out);

inline constexpr int kMaxConfigWrites = 40;

struct ConfigSequence {
  std::array<SdoWrite, kMaxConfigWrites> writes{};
  int count = 0;
};

// SDO writes that configure a drive in pre-operational: PDOs disabled while
// remapped (CiA 301 procedure: COB-ID bit 31, count 0, entries, count, enable),
// unused PDOs switched off, the mode (CST; or CSP with the position-loop gains
// written first), heartbeat producer time, and the communication cycle period
// 0x1006 so the drive itself notices a dead master.
ConfigSequence pdo_config_sequence(std::uint8_t node, std::uint16_t heartbeat_period_ms,
                                   std::uint32_t cycle_period_us, const DriveLoop& loop = DriveLoop{});

}  // namespace kuavo::drivers::canopen
