// One leg's six actuators <-> its six joints: hip roll, hip yaw, hip pitch and
// knee through linear transmissions (knee reversed), ankle pitch/roll through
// the parallel linkage (motor A in the ankle-pitch slot, B in the roll slot).
// Joint-space PD is evaluated here, in the joint frame where the controller
// defined it, and the resulting joint torques are mapped to motor torques for
// the CST drives. Real-time safe.
#pragma once

#include <array>

#include "controllers/hal/types.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/driver_error.h"
#include "drivers/transmission/ankle_linkage.h"
#include "drivers/transmission/linear_transmission.h"

namespace kuavo::drivers {

inline constexpr int kLegActuators = 6;

struct LegTransmission {
  std::array<LinearTransmission, 4> serial{};  // slots 0..3
  AnkleGeometry ankle{};
  // Crank angle = sign * (motor reading - offset). Leju applies
  // ankle_motor_offset_degree = -15 deg (FACTS.md §2.4); its sign convention is
  // unverified, so the default is 0 and the value belongs in the robot config.
  std::array<LinearTransmission, 2> ankle_motor{};
};

// Knee ratio -1 (reversed joint, FACTS.md §2.4), all other ratios 1.
LegTransmission default_leg_transmission(bool left_leg);

// Motor samples (slot order) -> joint samples. `joints` holds last cycle's
// values: the ankle solve warm-starts from them. A joint is valid only if its
// motors are; an unsolvable ankle marks both ankle joints invalid and returns
// kTransmissionUnsolved. Stamps are the motor stamps (oldest of the two for
// the ankle).
DriverError leg_joints_from_motors_rt(const LegTransmission& t,
                                      const std::array<canopen::MotorSample, kLegActuators>& motors,
                                      std::array<hal::JointSample, kLegActuators>& joints);

// Joint-space command law: kDisabled 0, kDamping -kd v, kPdTorque
// tau_ff + kp (q_ref - q) + kd (v_ref - v). Non-finite results become 0 (the
// firmware watchdog sees the NaN in the command itself).
double joint_torque_command_Nm(const hal::JointCommand& cmd, const hal::JointSample& joint);

// Joint torques -> motor torques at the current configuration (ankle: J^-T).
// Returns kTransmissionUnsolved (motor torques 0) if the ankle cannot be mapped.
DriverError leg_motor_torques_rt(const LegTransmission& t,
                                 const std::array<hal::JointSample, kLegActuators>& joints,
                                 const std::array<double, kLegActuators>& joint_torque_Nm,
                                 std::array<double, kLegActuators>& motor_torque_Nm);

}  // namespace kuavo::drivers
