// A joint driven by one motor through a fixed ratio (gear, lever or a reversed
// linkage). ratio_motor_per_joint < 0 reverses the direction: the 4Pro knee is a
// "reversed joint" (FACTS.md §2.4), so its default ratio is -1 until the sign
// and ratio are verified on hardware. Real-time safe, header-only.
#pragma once

namespace kuavo::drivers {

struct LinearTransmission {
  double ratio_motor_per_joint = 1.0;  // motor rad per joint rad; never 0
  double motor_offset_rad = 0.0;       // motor position at joint zero
};

inline double motor_position_rad(const LinearTransmission& t, double joint_rad) {
  return t.ratio_motor_per_joint * joint_rad + t.motor_offset_rad;
}
inline double joint_position_rad(const LinearTransmission& t, double motor_rad) {
  return (motor_rad - t.motor_offset_rad) / t.ratio_motor_per_joint;
}
inline double motor_velocity_rad_s(const LinearTransmission& t, double joint_rad_s) {
  return t.ratio_motor_per_joint * joint_rad_s;
}
inline double joint_velocity_rad_s(const LinearTransmission& t, double motor_rad_s) {
  return motor_rad_s / t.ratio_motor_per_joint;
}
// Power is conserved: tau_joint * qd_joint = tau_motor * qd_motor.
inline double motor_torque_Nm(const LinearTransmission& t, double joint_Nm) {
  return joint_Nm / t.ratio_motor_per_joint;
}
inline double joint_torque_Nm(const LinearTransmission& t, double motor_Nm) {
  return motor_Nm * t.ratio_motor_per_joint;
}

}  // namespace kuavo::drivers
