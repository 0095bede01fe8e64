// The joints' end stops (sim/joint_stop.h): a joint pushed against its stop by a constant
// drive torque comes to rest past the limit by τ/k, the static deflection of the stop's
// spring (closed form), on either side; inside its range no stop acts.
#include <gtest/gtest.h>

#include <cmath>

#include "controllers/dynamics/rigid_body.h"
#include "sim/joint_stop.h"
#include "sim/plant.h"
#include "tests/support/test_robot.h"

namespace kuavo::test {
namespace {

constexpr int kWristPitch = model::kLeftArmFirst + 6;  // zarm_l7_joint: a light distal joint

// Floating without gravity or contact, every other joint held by a stiff PD, the wrist
// driven by torque_Nm alone for 2 s from the middle of its range.
double rest_position(const model::Model& m, double torque_Nm) {
  sim::PlantConfig cfg;
  cfg.gravity = false;
  cfg.contact = false;
  cfg.relative_tolerance = 1e-8;
  cfg.absolute_tolerance = 1e-9;
  sim::Plant plant(m, cfg);
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  q[7 + kWristPitch] = 0.5 * (m.limits.position_min_rad[kWristPitch] + m.limits.position_max_rad[kWristPitch]);
  plant.reset(q, dynamics::VelocityVector::Zero());
  hal::CommandFrame c;
  for (int j = 0; j < model::kNumJoints; ++j) {
    c.joints[j].mode = hal::JointMode::kPdTorque;
    c.joints[j].position_ref_rad = q[7 + j];
    c.joints[j].kp_Nm_per_rad = 500.0;
    c.joints[j].kd_Nm_s_per_rad = 5.0;
  }
  c.joints[kWristPitch].kp_Nm_per_rad = 0.0;
  c.joints[kWristPitch].kd_Nm_s_per_rad = 0.0;
  c.joints[kWristPitch].torque_ff_Nm = torque_Nm;
  plant.set_command(c);
  while (plant.time_s() < 2.0 - 1e-9) {
    EXPECT_EQ(plant.advance(1e-3), sim::PlantError::kOk) << plant.last_error();
  }
  EXPECT_LT(std::abs(plant.truth().v[6 + kWristPitch]), 1e-3) << "at rest";
  return plant.truth().q[7 + kWristPitch];
}

TEST(JointStop, DriveAgainstTheStopDeflectsItByTorqueOverStiffness) {
  const model::Model& m = s45_robot();
  const double tau = 0.5 * m.limits.peak_torque_Nm[kWristPitch];  // within the drive's clip
  const double deflection = tau / sim::kJointStopStiffness_Nm_per_rad;
  const double upper = rest_position(m, tau) - m.limits.position_max_rad[kWristPitch];
  const double lower = m.limits.position_min_rad[kWristPitch] - rest_position(m, -tau);
  EXPECT_NEAR(upper, deflection, 0.01 * deflection);
  EXPECT_NEAR(lower, deflection, 0.01 * deflection);
  RecordProperty("deflection_rad", std::to_string(upper));
}

TEST(JointStop, NoTorqueInsideTheRangeAndNeverOutwards) {
  EXPECT_EQ(sim::joint_stop_torque(0.0, 5.0, -1.0, 1.0), 0.0);
  EXPECT_EQ(sim::joint_stop_torque(1.0, 5.0, -1.0, 1.0), 0.0);  // on the stop
  // Leaving the stop fast: the spring's push back, no damping pulling it in.
  EXPECT_NEAR(sim::joint_stop_torque(1.01, -50.0, -1.0, 1.0), -0.01 * sim::kJointStopStiffness_Nm_per_rad, 1e-9);
  EXPECT_NEAR(sim::joint_stop_torque(-1.01, 50.0, -1.0, 1.0), 0.01 * sim::kJointStopStiffness_Nm_per_rad, 1e-9);
  EXPECT_LT(sim::joint_stop_torque(1.01, 3.0, -1.0, 1.0), -0.01 * sim::kJointStopStiffness_Nm_per_rad);  // braked
}

}  // namespace
}  // namespace kuavo::test
