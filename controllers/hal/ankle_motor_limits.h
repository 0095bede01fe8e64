// The ankle pairs in motor space, as the hardware binding sees them. On the 4Pro the two
// ankle joints (pitch, roll) are driven by two motors (A, B) through a parallel linkage
// (FACTS.md §2.4): motor torques (A, B) = joint_to_motor · (τ_pitch, τ_roll), about
// 0.5·τ_pitch ± 1.1·τ_roll near the zero pose (1.45 at full dorsiflexion). Each motor's
// 27 N·m bounds pitch and roll jointly, which no joint-space box can express. The binding
// (the firmware and the simulator alike: drivers/transmission/ankle_motors.h, at the sampled
// ankle angles) fills this each tick; the WBC bounds the motor torques with it, and the MPC
// the stance ankles' share of them. Inactive: joint-space limits only.
#pragma once

#include <Eigen/Core>
#include <array>

namespace kuavo::hal {

struct AnkleMotorLimits {
  bool active = false;
  // Per leg (left, right): rows motor A, B; columns ankle pitch, roll.
  std::array<Eigen::Matrix2d, 2> joint_to_motor{Eigen::Matrix2d::Identity(), Eigen::Matrix2d::Identity()};
  std::array<Eigen::Vector2d, 2> limit_Nm{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};  // |motor k| ≤
  // What each motor's drive adds to the commanded torque per unit of motor velocity error,
  // J·(v_ref − v) with J = joint_to_motorᵀ⁻¹ (virtual work): the CSP drives' kd. Their torque
  // offset carries kd·J·v_ref and the drive's loop takes kd·J·v off at the sample it closes
  // on, so the motor's torque there is the mapped τ plus kd·J·(v_ref − v), and that is what
  // the drive clips at its limit (drivers/canopen/cia402_drive.cpp). 0: a binding that sends
  // τ alone.
  std::array<Eigen::Vector2d, 2> velocity_gain_Nm_s_per_rad{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
};

}  // namespace kuavo::hal
