// Whole-leg transmission: motor samples -> joint samples (knee reversed, ankle
// linkage), joint-space PD, and joint -> motor torques conserving power.
#include <gtest/gtest.h>

#include <limits>

#include "drivers/transmission/leg_transmission.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers {
namespace {

std::array<canopen::MotorSample, kLegActuators> motors_for(const LegTransmission& t, const double (&q)[6],
                                                            const double (&qd)[6]) {
  std::array<canopen::MotorSample, kLegActuators> m{};
  for (int i = 0; i < 4; ++i) {
    m[i].position_rad = motor_position_rad(t.serial[i], q[i]);
    m[i].velocity_rad_s = motor_velocity_rad_s(t.serial[i], qd[i]);
  }
  Vec2 crank;
  EXPECT_TRUE(ankle_motor_from_joint_rt(t.ankle, Vec2(q[4], q[5]), crank));
  const Vec2 rate = ankle_jacobian_rt(t.ankle, Vec2(q[4], q[5]), crank) * Vec2(qd[4], qd[5]);
  for (int k = 0; k < 2; ++k) {
    m[4 + k].position_rad = crank[k];
    m[4 + k].velocity_rad_s = rate[k];
  }
  for (auto& s : m) {
    s.valid = true;
    s.stamp_ns = 100;
  }
  return m;
}

TEST(LegTransmission, MotorSamplesMapToJointsIncludingReversedKnee) {
  const LegTransmission t = default_leg_transmission(true);
  const double q[6] = {0.1, -0.2, -0.6, 1.2, -0.4, 0.1};
  const double qd[6] = {0.5, -0.5, 1.0, -2.0, 0.3, -0.2};
  const auto motors = motors_for(t, q, qd);
  EXPECT_DOUBLE_EQ(motors[3].position_rad, -1.2);  // the knee motor turns the other way
  std::array<hal::JointSample, kLegActuators> joints{};
  ASSERT_EQ(leg_joints_from_motors_rt(t, motors, joints), DriverError::kOk);
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(joints[i].position_rad, q[i], 1e-9) << i;
    EXPECT_NEAR(joints[i].velocity_rad_s, qd[i], 1e-9) << i;
    EXPECT_TRUE(joints[i].valid);
  }
}

TEST(LegTransmission, InvalidMotorInvalidatesItsJoints) {
  const LegTransmission t = default_leg_transmission(false);
  const double q[6] = {0, 0, 0, 0.5, 0.1, -0.1}, qd[6] = {};
  auto motors = motors_for(t, q, qd);
  motors[5].valid = false;
  motors[1].valid = false;
  std::array<hal::JointSample, kLegActuators> joints{};
  ASSERT_EQ(leg_joints_from_motors_rt(t, motors, joints), DriverError::kOk);
  EXPECT_FALSE(joints[1].valid);
  EXPECT_FALSE(joints[4].valid);
  EXPECT_FALSE(joints[5].valid);
  EXPECT_TRUE(joints[3].valid);
}

TEST(LegTransmission, JointPdLaw) {
  hal::JointSample j;
  j.position_rad = 0.5;
  j.velocity_rad_s = -1.0;
  hal::JointCommand c;
  c.kp_Nm_per_rad = 100;
  c.kd_Nm_s_per_rad = 2;
  c.torque_ff_Nm = 3;
  c.position_ref_rad = 0.6;
  c.velocity_ref_rad_s = 0.5;
  c.mode = hal::JointMode::kPdTorque;
  EXPECT_DOUBLE_EQ(joint_torque_command_Nm(c, j), 3 + 100 * 0.1 + 2 * 1.5);
  c.mode = hal::JointMode::kDamping;
  EXPECT_DOUBLE_EQ(joint_torque_command_Nm(c, j), 2.0);
  c.mode = hal::JointMode::kDisabled;
  EXPECT_DOUBLE_EQ(joint_torque_command_Nm(c, j), 0.0);
  c.mode = hal::JointMode::kPdTorque;
  c.position_ref_rad = std::numeric_limits<double>::quiet_NaN();
  EXPECT_DOUBLE_EQ(joint_torque_command_Nm(c, j), 0.0);
}

TEST(LegTransmission, MotorTorquesConservePower) {
  const LegTransmission t = default_leg_transmission(true);
  const double q[6] = {0.05, 0.1, -0.8, 1.4, -0.5, 0.15};
  const double qd[6] = {0.3, -0.1, 0.7, -1.1, 0.9, -0.4};
  const auto motors = motors_for(t, q, qd);
  std::array<hal::JointSample, kLegActuators> joints{};
  ASSERT_EQ(leg_joints_from_motors_rt(t, motors, joints), DriverError::kOk);
  const std::array<double, kLegActuators> tau_joint{10, -5, 30, -60, 12, -4};
  std::array<double, kLegActuators> tau_motor{};
  ASSERT_EQ(leg_motor_torques_rt(t, joints, tau_joint, tau_motor), DriverError::kOk);
  double p_joint = 0, p_motor = 0;
  for (int i = 0; i < 6; ++i) {
    p_joint += tau_joint[i] * qd[i];
    p_motor += tau_motor[i] * motors[i].velocity_rad_s;
  }
  EXPECT_NEAR(p_joint, p_motor, 1e-9);
  EXPECT_DOUBLE_EQ(tau_motor[3], 60.0);  // reversed knee
}

TEST(LegTransmission, CycleDoesNotAllocate) {
  const LegTransmission t = default_leg_transmission(true);
  const double q[6] = {0, 0, -0.3, 0.6, -0.3, 0}, qd[6] = {};
  const auto motors = motors_for(t, q, qd);
  std::array<hal::JointSample, kLegActuators> joints{};
  std::array<double, kLegActuators> tau{}, out{};
  test::AllocTrap trap;
  (void)leg_joints_from_motors_rt(t, motors, joints);
  (void)leg_motor_torques_rt(t, joints, tau, out);
  EXPECT_EQ(trap.count(), 0u);
}

}  // namespace
}  // namespace kuavo::drivers
