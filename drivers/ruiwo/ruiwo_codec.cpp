#include "drivers/ruiwo/ruiwo_codec.h"

#include <cmath>

namespace kuavo::drivers::ruiwo {

std::uint32_t to_uint(double x, double min, double max, int bits) {
  const double span = static_cast<double>((1u << bits) - 1u);
  return static_cast<std::uint32_t>((x - min) / (max - min) * span);
}

double from_uint(std::uint32_t u, double min, double max, int bits) {
  const double span = static_cast<double>((1u << bits) - 1u);
  return static_cast<double>(u) / span * (max - min) + min;
}

namespace {

// Clamps one field; NaN/Inf become `fallback` and set kNonFinite too.
std::uint8_t clamp_field(double& x, double lo, double hi, std::uint8_t flag, double fallback) {
  if (!std::isfinite(x)) {
    x = fallback;
    return static_cast<std::uint8_t>(flag | kNonFinite);
  }
  if (x < lo) {
    x = lo;
    return flag;
  }
  if (x > hi) {
    x = hi;
    return flag;
  }
  return 0;
}

}  // namespace

std::uint8_t clamp_ptm_rt(PtmCommand& c) {
  std::uint8_t flags = 0;
  const std::uint8_t pos_flags =
      clamp_field(c.position_rad, kPositionMin_rad, kPositionMax_rad, kClampPosition, 0.0);
  flags |= pos_flags;
  flags |= clamp_field(c.velocity_rad_s, kVelocityMin_rad_s, kVelocityMax_rad_s, kClampVelocity, 0.0);
  flags |= clamp_field(c.kp_Nm_per_rad, 0.0, kKpMax_Nm_per_rad, kClampKp, 0.0);
  flags |= clamp_field(c.kd_Nm_s_per_rad, 0.0, kKdMax_Nm_s_per_rad, kClampKd, 0.0);
  flags |= clamp_field(c.torque_Nm, kTorqueMin_Nm, kTorqueMax_Nm, kClampTorque, 0.0);
  // A made-up position target must not be servoed to: drop the stiffness.
  if (pos_flags & kNonFinite) c.kp_Nm_per_rad = 0.0;
  return flags;
}

std::uint8_t encode_ptm_rt(std::uint8_t motor_id, const PtmCommand& cmd, can_frame& out) {
  PtmCommand c = cmd;
  const std::uint8_t flags = clamp_ptm_rt(c);
  const std::uint32_t p = to_uint(c.position_rad, kPositionMin_rad, kPositionMax_rad, kPositionBits);
  const std::uint32_t v = to_uint(c.velocity_rad_s, kVelocityMin_rad_s, kVelocityMax_rad_s, kVelocityBits);
  const std::uint32_t kp = to_uint(c.kp_Nm_per_rad, 0.0, kKpMax_Nm_per_rad, kGainBits);
  const std::uint32_t kd = to_uint(c.kd_Nm_s_per_rad, 0.0, kKdMax_Nm_s_per_rad, kGainBits);
  const std::uint32_t t = to_uint(c.torque_Nm, kTorqueMin_Nm, kTorqueMax_Nm, kTorqueBits);
  out = can_frame{};
  out.can_id = motor_id;
  out.len = 8;
  out.data[0] = static_cast<std::uint8_t>(p >> 8);
  out.data[1] = static_cast<std::uint8_t>(p);
  out.data[2] = static_cast<std::uint8_t>(v >> 4);
  out.data[3] = static_cast<std::uint8_t>(((v & 0xFu) << 4) | (kp >> 8));
  out.data[4] = static_cast<std::uint8_t>(kp);
  out.data[5] = static_cast<std::uint8_t>(kd >> 4);
  out.data[6] = static_cast<std::uint8_t>(((kd & 0xFu) << 4) | (t >> 8));
  out.data[7] = static_cast<std::uint8_t>(t);
  return flags;
}

void encode_special_rt(std::uint8_t motor_id, SpecialCommand cmd, can_frame& out) {
  out = can_frame{};
  out.can_id = motor_id;
  out.len = 8;
  for (int i = 0; i < 7; ++i) out.data[i] = 0xFF;
  out.data[7] = static_cast<std::uint8_t>(cmd);
}

void encode_multiturn_zero_rt(std::uint8_t motor_id, can_frame& out) {
  static constexpr std::uint8_t kPayload[8] = {0x67, 0x06, 0xFE, 0x00, 0x00, 0x00, 0x00, 0x76};
  out = can_frame{};
  out.can_id = 0x600u + motor_id;
  out.len = 8;
  for (int i = 0; i < 8; ++i) out.data[i] = kPayload[i];
}

DriverError decode_ptm_rt(const can_frame& f, PtmCommand& out) {
  if (f.can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG)) return DriverError::kWrongCanId;
  if (f.can_id & CAN_RTR_FLAG) return DriverError::kRemoteFrame;
  if (f.len != 8) return DriverError::kWrongLength;
  const std::uint32_t p = (std::uint32_t{f.data[0]} << 8) | f.data[1];
  const std::uint32_t v = (std::uint32_t{f.data[2]} << 4) | (f.data[3] >> 4);
  const std::uint32_t kp = (std::uint32_t{f.data[3] & 0xFu} << 8) | f.data[4];
  const std::uint32_t kd = (std::uint32_t{f.data[5]} << 4) | (f.data[6] >> 4);
  const std::uint32_t t = (std::uint32_t{f.data[6] & 0xFu} << 8) | f.data[7];
  out.position_rad = from_uint(p, kPositionMin_rad, kPositionMax_rad, kPositionBits);
  out.velocity_rad_s = from_uint(v, kVelocityMin_rad_s, kVelocityMax_rad_s, kVelocityBits);
  out.kp_Nm_per_rad = from_uint(kp, 0.0, kKpMax_Nm_per_rad, kGainBits);
  out.kd_Nm_s_per_rad = from_uint(kd, 0.0, kKdMax_Nm_s_per_rad, kGainBits);
  out.torque_Nm = from_uint(t, kTorqueMin_Nm, kTorqueMax_Nm, kTorqueBits);
  return DriverError::kOk;
}

void encode_status_rt(const Status& status, can_frame& out) {
  PtmCommand c;  // reuse the command clamps for the three shared fields
  c.position_rad = status.position_rad;
  c.velocity_rad_s = status.velocity_rad_s;
  c.torque_Nm = status.torque_Nm;
  clamp_ptm_rt(c);
  const std::uint32_t p = to_uint(c.position_rad, kPositionMin_rad, kPositionMax_rad, kPositionBits);
  const std::uint32_t v = to_uint(c.velocity_rad_s, kVelocityMin_rad_s, kVelocityMax_rad_s, kVelocityBits);
  const std::uint32_t t = to_uint(c.torque_Nm, kTorqueMin_Nm, kTorqueMax_Nm, kTorqueBits);
  out = can_frame{};
  out.can_id = status.motor_id;
  out.len = 8;
  out.data[0] = status.motor_id;
  out.data[1] = static_cast<std::uint8_t>(p >> 8);
  out.data[2] = static_cast<std::uint8_t>(p);
  out.data[3] = static_cast<std::uint8_t>(v >> 4);
  out.data[4] = static_cast<std::uint8_t>(((v & 0xFu) << 4) | (t >> 8));
  out.data[5] = static_cast<std::uint8_t>(t);
  out.data[6] = status.temperature_raw;
  out.data[7] = status.fault_code;
}

DriverError decode_status_rt(const can_frame& f, Status& out) {
  if (f.can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG)) return DriverError::kWrongCanId;
  if (f.can_id & CAN_RTR_FLAG) return DriverError::kRemoteFrame;
  if (f.len != 8) return DriverError::kWrongLength;
  const std::uint32_t p = (std::uint32_t{f.data[1]} << 8) | f.data[2];
  const std::uint32_t v = (std::uint32_t{f.data[3]} << 4) | (f.data[4] >> 4);
  const std::uint32_t t = (std::uint32_t{f.data[4] & 0xFu} << 8) | f.data[5];
  out.motor_id = f.data[0];
  out.position_rad = from_uint(p, kPositionMin_rad, kPositionMax_rad, kPositionBits);
  out.velocity_rad_s = from_uint(v, kVelocityMin_rad_s, kVelocityMax_rad_s, kVelocityBits);
  out.torque_Nm = from_uint(t, kTorqueMin_Nm, kTorqueMax_Nm, kTorqueBits);
  out.temperature_raw = f.data[6];
  out.fault_code = f.data[7];
  return DriverError::kOk;
}

}  // namespace kuavo::drivers::ruiwo
