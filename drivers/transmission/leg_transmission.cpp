#include "drivers/transmission/leg_transmission.h"

#include <algorithm>
#include <cmath>

namespace kuavo::drivers {

LegTransmission default_leg_transmission(bool left_leg) {
  LegTransmission t;
  t.serial[3].ratio_motor_per_joint = -1.0;
  t.ankle = left_leg ? make_left_ankle() : make_right_ankle();
  return t;
}

DriverError leg_joints_from_motors_rt(const LegTransmission& t,
                                      const std::array<canopen::MotorSample, kLegActuators>& motors,
                                      std::array<hal::JointSample, kLegActuators>& joints) {
  for (int i = 0; i < 4; ++i) {
    const canopen::MotorSample& m = motors[i];
    hal::JointSample& j = joints[i];
    j.position_rad = joint_position_rad(t.serial[i], m.position_rad);
    j.velocity_rad_s = joint_velocity_rad_s(t.serial[i], m.velocity_rad_s);
    j.torque_Nm = joint_torque_Nm(t.serial[i], m.torque_Nm);
    j.stamp_ns = m.stamp_ns;
    j.valid = m.valid;
  }
  const canopen::MotorSample& a = motors[4];
  const canopen::MotorSample& b = motors[5];
  const Vec2 crank(joint_position_rad(t.ankle_motor[0], a.position_rad),
                   joint_position_rad(t.ankle_motor[1], b.position_rad));
  const Vec2 crank_rate(joint_velocity_rad_s(t.ankle_motor[0], a.velocity_rad_s),
                        joint_velocity_rad_s(t.ankle_motor[1], b.velocity_rad_s));
  const Vec2 crank_torque(joint_torque_Nm(t.ankle_motor[0], a.torque_Nm),
                          joint_torque_Nm(t.ankle_motor[1], b.torque_Nm));
  Vec2 q(joints[4].position_rad, joints[5].position_rad);
  const DriverError e = ankle_joint_from_motor_rt(t.ankle, crank, q);
  const bool ok = e == DriverError::kOk;
  if (ok) {
    const Mat2 J = ankle_jacobian_rt(t.ankle, q, crank);
    const Vec2 qd = ankle_joint_velocity_rt(J, crank_rate);
    const Vec2 tau = ankle_joint_torque_rt(J, crank_torque);
    for (int k = 0; k < 2; ++k) {
      joints[4 + k].position_rad = q[k];
      joints[4 + k].velocity_rad_s = qd[k];
      joints[4 + k].torque_Nm = tau[k];
    }
  }
  for (int k = 0; k < 2; ++k) {
    joints[4 + k].stamp_ns = std::min(a.stamp_ns, b.stamp_ns);
    joints[4 + k].valid = ok && a.valid && b.valid;
  }
  return e;
}

double joint_torque_command_Nm(const hal::JointCommand& c, const hal::JointSample& j) {
  double tau = 0.0;
  switch (c.mode) {
    case hal::JointMode::kDisabled: tau = 0.0; break;
    case hal::JointMode::kDamping: tau = -c.kd_Nm_s_per_rad * j.velocity_rad_s; break;
    case hal::JointMode::kPdTorque:
      tau = c.torque_ff_Nm + c.kp_Nm_per_rad * (c.position_ref_rad - j.position_rad) +
            c.kd_Nm_s_per_rad * (c.velocity_ref_rad_s - j.velocity_rad_s);
      break;
  }
  return std::isfinite(tau) ? tau : 0.0;
}

DriverError leg_motor_torques_rt(const LegTransmission& t,
                                 const std::array<hal::JointSample, kLegActuators>& joints,
                                 const std::array<double, kLegActuators>& joint_torque_Nm,
                                 std::array<double, kLegActuators>& motor_torque_Nm) {
  for (int i = 0; i < 4; ++i) motor_torque_Nm[i] = drivers::motor_torque_Nm(t.serial[i], joint_torque_Nm[i]);
  const Vec2 q(joints[4].position_rad, joints[5].position_rad);
  Vec2 crank;
  if (!ankle_motor_from_joint_rt(t.ankle, q, crank)) {
    motor_torque_Nm[4] = motor_torque_Nm[5] = 0.0;
    return DriverError::kTransmissionUnsolved;
  }
  const Mat2 J = ankle_jacobian_rt(t.ankle, q, crank);
  const Vec2 crank_tau = ankle_motor_torque_rt(J, Vec2(joint_torque_Nm[4], joint_torque_Nm[5]));
  motor_torque_Nm[4] = drivers::motor_torque_Nm(t.ankle_motor[0], crank_tau[0]);
  motor_torque_Nm[5] = drivers::motor_torque_Nm(t.ankle_motor[1], crank_tau[1]);
  return DriverError::kOk;
}

}  // namespace kuavo::drivers
