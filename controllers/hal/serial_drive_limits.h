// The legs' serial joints (hip roll, hip yaw, hip pitch, knee) on drives that close their own
// loop: in CSP (firmware/README.md, leg binding) the torque offset on the wire is, in joint
// terms, τ_ff + kd·v_ref (the drive's gains equal the command's), and the drive's own −kd·q̇
// takes kd·v off at the sample, so the drive's torque there is τ_ff + kd·(v_ref − v) (with
// the target on the sample): the drivers clamp that at the drive's limit, not the offset
// (drivers/canopen/cia402_drive.cpp). The binding fills this at start-up; the WBC then keeps
// each joint's torque at the sample within the limit (controllers/wbc/wbc.h). Inactive (the
// simulator's joint drives, CST): no rows. The ankle pair is hal::AnkleMotorLimits.
#pragma once

#include <array>

namespace kuavo::hal {

inline constexpr int kSerialLegJoints = 4;  // hip roll, hip yaw, hip pitch, knee

struct SerialLegDriveLimits {
  bool active = false;
  // Per leg (left, right), per serial joint, joint side: the drive's clamp through its ratio,
  // and the torque its command adds per rad/s of v_ref.
  std::array<std::array<double, kSerialLegJoints>, 2> limit_Nm{};
  std::array<std::array<double, kSerialLegJoints>, 2> velocity_gain_Nm_s_per_rad{};
};

}  // namespace kuavo::hal
