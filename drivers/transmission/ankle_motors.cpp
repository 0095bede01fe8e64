#include "drivers/transmission/ankle_motors.h"

#include <algorithm>

#include "controllers/model/model.h"
#include "drivers/config/drivers_config.h"

namespace kuavo::drivers {

AnkleMotors ankle_motors_from_config(const DriversConfig& drivers) {
  AnkleMotors a;
  a.legs = drivers.legs;
  a.active = true;
  for (int leg = 0; leg < 2; ++leg) {
    const int first = leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    for (int k = 0; k < 2; ++k) {
      for (const DriveEntry& e : drivers.drives) {
        if (e.slot != first + 4 + k) continue;
        a.limit_Nm[leg](k) = e.config.torque_limit_Nm;
        // CSP: the torque offset carries csp_kd·(motor velocity of v_ref) (firmware/robot_io.cpp).
        if (e.config.mode == canopen::kModeCyclicSyncPosition) {
          a.velocity_gain_Nm_s_per_rad[leg](k) = e.config.csp_kd_Nm_s_per_rad;
        }
      }
      if (!(a.limit_Nm[leg](k) > 0.0)) a.active = false;
    }
  }
  return a;
}

bool ankle_motor_torques_rt(const AnkleMotors& a, int leg, const Eigen::Vector2d& q, const Eigen::Vector2d& tau,
                            Eigen::Vector2d& motor) noexcept {
  const LegTransmission& t = a.legs[leg];
  Vec2 crank;
  if (!ankle_motor_from_joint_rt(t.ankle, q, crank)) return false;
  const Vec2 crank_tau = ankle_motor_torque_rt(ankle_jacobian_rt(t.ankle, q, crank), tau);
  for (int k = 0; k < 2; ++k) motor[k] = motor_torque_Nm(t.ankle_motor[k], crank_tau[k]);
  return true;
}

bool map_ankle_motors_rt(const AnkleMotors& a, const std::array<Eigen::Vector2d, 2>& ankle_rad,
                         hal::AnkleMotorLimits& out) noexcept {
  out.active = true;
  for (int leg = 0; leg < 2; ++leg) {
    for (int c = 0; c < 2; ++c) {
      Vec2 motor = Vec2::Zero();
      if (!ankle_motor_torques_rt(a, leg, ankle_rad[leg], Vec2::Unit(c), motor)) out.active = false;
      out.joint_to_motor[leg].col(c) = motor;
    }
    out.limit_Nm[leg] = a.limit_Nm[leg];
    out.velocity_gain_Nm_s_per_rad[leg] = a.velocity_gain_Nm_s_per_rad[leg];
  }
  return out.active;
}

void map_ankle_motors_rt(AnkleMotors& a, const hal::SensorFrame& sensors, hal::AnkleMotorLimits& out) noexcept {
  std::array<Vec2, 2> ankle_rad;
  bool valid = true;
  for (int leg = 0; leg < 2; ++leg) {
    const int pitch = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + 4;
    const hal::JointSample& p = sensors.joints[pitch];
    const hal::JointSample& r = sensors.joints[pitch + 1];
    valid = valid && p.valid && r.valid;
    ankle_rad[leg] = Vec2(p.position_rad, r.position_rad);
  }
  if (!map_ankle_motors_rt(a, ankle_rad, out) || !valid) {
    out.active = false;
    ++a.unmapped_ticks;
  }
}

int clip_ankle_torques_rt(const AnkleMotors& a, int leg, const Eigen::Vector2d& q, Eigen::Vector2d& tau) noexcept {
  const LegTransmission& t = a.legs[leg];
  Vec2 crank;
  if (!ankle_motor_from_joint_rt(t.ankle, q, crank)) return -1;
  const Mat2 J = ankle_jacobian_rt(t.ankle, q, crank);
  const Vec2 crank_tau = ankle_motor_torque_rt(J, tau);
  Vec2 delivered;
  int clipped = 0;
  for (int k = 0; k < 2; ++k) {
    const double m = motor_torque_Nm(t.ankle_motor[k], crank_tau[k]);
    const double m_clipped = std::clamp(m, -a.limit_Nm[leg](k), a.limit_Nm[leg](k));
    clipped += m_clipped != m;
    delivered[k] = joint_torque_Nm(t.ankle_motor[k], m_clipped);
  }
  if (clipped > 0) tau = ankle_joint_torque_rt(J, delivered);  // unclipped: exactly as asked
  return clipped;
}

}  // namespace kuavo::drivers
