// The plants' ankle pairs in motor space (sim/motor_model.h): with the ankle motors, a pitch
// torque beyond the joint box but within the two motors' clamps is delivered whole, a roll
// torque beyond one motor's clamp is cut to what the motors give (the drivers' map), and the
// robot moves with the delivered torque, not the asked one. Simbody (both derivative
// engines) and MuJoCo.
#include <gtest/gtest.h>

#include "controllers/dynamics/rigid_body.h"
#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"
#include "sim/mujoco_plant.h"
#include "sim/plant.h"

namespace kuavo::test {
namespace {

const model::Model& robot() {
  static const model::Model m = [] {
    model::Model r;
    EXPECT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, r), model::ModelError::kOk);
    return r;
  }();
  return m;
}

const drivers::AnkleMotors& ankle_motors() {
  static const drivers::AnkleMotors a = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot()));
  return a;
}

constexpr int kLeftPitch = model::kLeftLegFirst + 4, kRightPitch = model::kRightLegFirst + 4;
constexpr double kPitch_Nm = 70.0;

hal::CommandFrame ankle_torques(double left_pitch_Nm, double right_roll_Nm) {
  hal::CommandFrame c{};
  c.joints[kLeftPitch].mode = hal::JointMode::kPdTorque;
  c.joints[kLeftPitch].torque_ff_Nm = left_pitch_Nm;
  c.joints[kRightPitch + 1].mode = hal::JointMode::kPdTorque;
  c.joints[kRightPitch + 1].torque_ff_Nm = right_roll_Nm;
  return c;
}

// Floating in space, at rest: the truth after 1 ms of the command.
template <class PlantT>
sim::PlantTruth after_one_ms(PlantT& plant, const hal::CommandFrame& command) {
  dynamics::ConfigVector q = dynamics::neutral_configuration(robot());
  q[2] = 2.0;
  plant.reset(q, dynamics::VelocityVector::Zero());
  plant.set_command(command);
  EXPECT_EQ(plant.advance(1e-3), sim::PlantError::kOk);
  return plant.truth();
}

void expect_motor_clamps(const sim::PlantTruth& with, const sim::PlantTruth& without, const char* engine) {
  SCOPED_TRACE(engine);
  const model::Model& m = robot();
  // Pitch 70 N·m: beyond both motors (≈ 54 of pitch alone), and beyond the joint box (Leju's
  // WBC limit, 60), which alone clips it without the motors.
  Eigen::Vector2d pitch(kPitch_Nm, 0.0);
  const Eigen::Vector2d q_left(with.q[7 + kLeftPitch], with.q[8 + kLeftPitch]);
  ASSERT_EQ(drivers::clip_ankle_torques_rt(ankle_motors(), 0, q_left, pitch), 2);
  EXPECT_NEAR(with.joint_torque_Nm[kLeftPitch], pitch[0], 1e-9);
  EXPECT_NEAR(with.joint_torque_Nm[kLeftPitch + 1], pitch[1], 1e-9);
  EXPECT_GT(pitch[0], 50.0);  // more than the URDF's 36 N·m effort: two motors, not one
  EXPECT_LT(pitch[0], m.limits.peak_torque_Nm[kLeftPitch]);
  EXPECT_EQ(without.joint_torque_Nm[kLeftPitch], m.limits.peak_torque_Nm[kLeftPitch]);
  // Roll 30 N·m: beyond one motor (≈ 24.5 of roll alone); what the drivers' clip gives at the
  // ankle angles the truth reports, pitch coupled in.
  Eigen::Vector2d roll(0.0, 30.0);
  const Eigen::Vector2d q(with.q[7 + kRightPitch], with.q[8 + kRightPitch]);
  ASSERT_GT(drivers::clip_ankle_torques_rt(ankle_motors(), 1, q, roll), 0);
  EXPECT_NEAR(with.joint_torque_Nm[kRightPitch], roll[0], 1e-9);
  EXPECT_NEAR(with.joint_torque_Nm[kRightPitch + 1], roll[1], 1e-9);
  EXPECT_LT(roll[1], 27.0);
  EXPECT_EQ(without.joint_torque_Nm[kRightPitch + 1], 30.0);  // within the joint box
  // The robot moves with what is delivered: from rest, the left ankle's speed scales with it.
  EXPECT_NEAR(with.v[6 + kLeftPitch] / without.v[6 + kLeftPitch], pitch[0] / m.limits.peak_torque_Nm[kLeftPitch], 0.01);
}

TEST(PlantAnkleMotors, SimbodyPlantClipsEachMotorNotTheJoints) {
  for (const auto engine : {sim::DerivativeEngine::kRigidBody, sim::DerivativeEngine::kSimbody}) {
    sim::PlantConfig cfg;
    cfg.gravity = false;
    cfg.contact = false;
    cfg.derivatives = engine;
    cfg.integrator = engine == sim::DerivativeEngine::kSimbody ? sim::Integrator::kSimbodyRungeKuttaMerson : cfg.integrator;
    sim::Plant without(robot(), cfg);
    cfg.ankle_motors = &ankle_motors();
    sim::Plant with(robot(), cfg);
    const hal::CommandFrame command = ankle_torques(kPitch_Nm, 30.0);
    const sim::PlantTruth t_with = after_one_ms(with, command), t_without = after_one_ms(without, command);
    expect_motor_clamps(t_with, t_without, engine == sim::DerivativeEngine::kSimbody ? "simbody forces" : "rigid body");
  }
}

TEST(PlantAnkleMotors, MujocoPlantClipsEachMotorNotTheJoints) {
  sim::MujocoPlantConfig cfg;
  cfg.gravity = false;
  cfg.contact = false;
  sim::MujocoPlant without(robot(), cfg);
  cfg.ankle_motors = &ankle_motors();
  sim::MujocoPlant with(robot(), cfg);
  ASSERT_TRUE(with.ok()) << with.last_error();
  const hal::CommandFrame command = ankle_torques(kPitch_Nm, 30.0);
  const sim::PlantTruth t_with = after_one_ms(with, command), t_without = after_one_ms(without, command);
  expect_motor_clamps(t_with, t_without, "mujoco");
}

}  // namespace
}  // namespace kuavo::test
