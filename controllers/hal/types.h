// Hardware abstraction: the fixed-size sample and command types the controllers
// consume and produce. The simulator binding and the CAN drivers fill the same
// types; controllers/ never sees a bus or a simulator. Every sample carries the
// time it was acquired (rtos_shim monotonic or simulated time, nanoseconds).
#pragma once

#include <array>
#include <cstdint>

#include "controllers/model/model_tables.h"

namespace kuavo::hal {

using TimeNs = std::int64_t;

struct JointSample {
  double position_rad = 0.0;
  double velocity_rad_s = 0.0;
  double torque_Nm = 0.0;      // measured (current-based) joint torque
  TimeNs stamp_ns = 0;         // acquisition time
  bool valid = false;          // false until the first good reading, or after a reply timeout
};

struct ImuSample {
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};  // sensor -> world
  std::array<double, 3> angular_rate_rad_s{};                  // sensor axes
  std::array<double, 3> acceleration_m_s2{};                   // specific force, sensor axes
  TimeNs stamp_ns = 0;
  bool valid = false;
};

enum class JointMode : std::uint8_t {
  kDisabled = 0,  // no torque (motor off)
  kDamping = 1,   // safe mode: tau = -kd * velocity only
  kPdTorque = 2,  // tau = tau_ff + kp (q_ref - q) + kd (v_ref - v)
};

struct JointCommand {
  JointMode mode = JointMode::kDisabled;
  double torque_ff_Nm = 0.0;
  double position_ref_rad = 0.0;
  double velocity_ref_rad_s = 0.0;
  double kp_Nm_per_rad = 0.0;
  double kd_Nm_s_per_rad = 0.0;
};

struct SensorFrame {
  std::array<JointSample, model::kNumJoints> joints{};
  ImuSample imu{};
};

struct CommandFrame {
  std::array<JointCommand, model::kNumJoints> joints{};
  TimeNs stamp_ns = 0;  // control tick that produced it
};

// Every joint commanded to damping (the safe state a fault must reach).
inline bool all_damping(const CommandFrame& c) {
  for (const JointCommand& j : c.joints) {
    if (j.mode != JointMode::kDamping) return false;
  }
  return true;
}

}  // namespace kuavo::hal
