#include "drivers/config/drive_defaults.h"

#include <cmath>

#include "controllers/model/model_tables.h"

namespace kuavo::drivers {

namespace {

struct MotorType {
  double counts_per_rev;
  double continuous_Nm;  // kuavo.json joint_torque_limits
  double peak_Nm;        // kuavo.json joint_peak_torque_limits
};

constexpr double kEncoderCounts = 131072.0;  // 2^17
// Leg slot order: hip roll, hip yaw, hip pitch, knee, ankle motor A, ankle motor B.
constexpr MotorType kLeg[6] = {
    {kEncoderCounts * 18, 88.9, 127.0},  // PA100_18
    {kEncoderCounts * 10, 15.54, 22.2},  // PA100
    {kEncoderCounts * 10, 50.4, 72.0},   // PA100
    {kEncoderCounts * 18, 94.5, 135.0},  // PA100_18
    {kEncoderCounts * 36, 18.9, 27.0},   // CK
    {kEncoderCounts * 36, 18.9, 27.0},   // CK
};
constexpr MotorType kShoulderPitch = {kEncoderCounts * 10, 46.67, 66.67};  // PA100

}  // namespace

canopen::DriveConfig default_drive_config(int slot, std::uint8_t node_id, double cycle_rate_hz,
                                          double heartbeat_rate_hz) {
  canopen::DriveConfig c;
  c.node_id = node_id;
  MotorType t{kEncoderCounts, 1.0, 0.0};
  if (slot >= 0 && slot < 2 * model::kLegJoints) {
    t = kLeg[slot % model::kLegJoints];
  } else if (slot == model::kLeftArmFirst || slot == model::kRightArmFirst) {
    t = kShoulderPitch;
  }
  c.counts_per_rev = t.counts_per_rev;
  c.rated_torque_Nm = t.continuous_Nm;
  c.torque_limit_Nm = t.peak_Nm;
  if (cycle_rate_hz > 0) {
    c.cycle_period_us = static_cast<std::uint32_t>(std::lround(1e6 / cycle_rate_hz));
    // 4 missing TPDO cycles make the drive silent (cia402_drive.h).
    c.tpdo_timeout_ns = static_cast<hal::TimeNs>(std::llround(4e9 / cycle_rate_hz));
  }
  if (heartbeat_rate_hz > 0) {
    c.heartbeat_period_ms = static_cast<std::uint16_t>(std::lround(1000.0 / heartbeat_rate_hz));
    // 3 periods: one lost heartbeat is tolerated.
    c.heartbeat_timeout_ns = static_cast<hal::TimeNs>(c.heartbeat_period_ms) * 3'000'000;
  }
  return c;
}

}  // namespace kuavo::drivers
