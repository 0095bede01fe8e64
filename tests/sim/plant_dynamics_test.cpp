// The CVODE derivative (sim/plant_dynamics.h, our own rigid-body algorithms)
// against Simbody's realize(Acceleration) for the same state and forces, and the
// two as CVODE's right-hand side over a trajectory through touchdown.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "controllers/dynamics/rigid_body.h"
#include "sim/plant.h"

namespace kuavo::test {
namespace {

model::Model robot() {
  model::Model m;
  model::build_model(model::Variant::kS45, 55.0, m);
  return m;
}

// A PD hold towards a pose off the current one, stiff enough that some drives saturate.
hal::CommandFrame pd_towards(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  hal::CommandFrame c;
  for (auto& j : c.joints) j = {hal::JointMode::kPdTorque, 0.3 * u(rng), 0.5 * u(rng), 5.0 * u(rng), 300.0, 8.0};
  c.joints[5].mode = hal::JointMode::kDamping;
  c.joints[6].mode = hal::JointMode::kDisabled;
  return c;
}

// Tilted, sunk into the ground at one edge, everything moving: contact, stick
// and slip, Coriolis terms, saturation and the push all in play.
void random_state(const model::Model& m, std::mt19937_64& rng, dynamics::ConfigVector& q, dynamics::VelocityVector& v) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  q = dynamics::neutral_configuration(m);
  Eigen::Quaterniond quat(1.0, 0.02 * u(rng), 0.02 * u(rng), 0.3 * u(rng));
  quat.normalize();
  q.segment<4>(3) << quat.x(), quat.y(), quat.z(), quat.w();
  q[0] = 0.3 * u(rng);
  q[2] -= 0.004;
  for (int j = 0; j < model::kNumJoints; ++j) q[7 + j] += 0.05 * u(rng);
  for (int k = 0; k < model::kNv; ++k) v[k] = 0.3 * u(rng);
}

// Rounding, not modelling: the stiff floor's kN corner forces go through M⁻¹
// (condition number ~1e6: 20 g wrist links beside a 55 kg robot) by two different
// orders of operations; differences of 1e-10 of (1 + |ẏ|) appear. A modelling
// slip (a frame, a sign, a missed force) shows at 1e-3 and above.
constexpr double kDerivativeTolerance = 1e-8;

void expect_derivatives_agree(const sim::GroundParams& ground) {
  const model::Model m = robot();
  std::mt19937_64 rng(11);
  sim::PlantConfig cfg;
  cfg.ground = ground;
  sim::Plant plant(m, cfg);
  sim::Push push;
  push.start_s = 0.0;
  push.duration_s = 1.0;
  push.force_N = sim::Vec3(40.0, -70.0, 10.0);
  plant.set_push(push);
  int touching = 0;
  for (int trial = 0; trial < 8; ++trial) {
    dynamics::ConfigVector q;
    dynamics::VelocityVector v;
    random_state(m, rng, q, v);
    plant.reset(q, v);
    plant.set_command(pd_towards(rng));
    EXPECT_LE(plant.derivative_mismatch(), kDerivativeTolerance) << "trial " << trial << " at touchdown";
    // A few steps on: the tangential springs are stretched away from their anchors.
    for (int k = 0; k < 3; ++k) ASSERT_EQ(plant.advance(1e-3), sim::PlantError::kOk) << plant.last_error();
    EXPECT_LE(plant.derivative_mismatch(), kDerivativeTolerance) << "trial " << trial << " after 3 ms";
    for (const auto& f : plant.truth().contact_force_N) touching += f.z() > 0.0;
  }
  EXPECT_GT(touching, 8) << "the states must exercise the contact";
}

TEST(PlantDynamics, DerivativeMatchesSimbodyOnTheFloor) { expect_derivatives_agree(sim::kFloor); }
TEST(PlantDynamics, DerivativeMatchesSimbodyOnCarpet) { expect_derivatives_agree(sim::kCarpet); }

// Neutral pose 1 cm up and rolled a little, to be dropped; and every drive holding zero with
// kp 200, kd 5.
dynamics::ConfigVector dropped_pose(const model::Model& m) {
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  q[2] += 0.01;
  q[3] = 0.03;
  q.segment<4>(3).normalize();
  return q;
}
hal::CommandFrame holding_drives() {
  hal::CommandFrame hold;
  for (auto& j : hold.joints) j = {hal::JointMode::kPdTorque, 0.0, 0.0, 0.0, 200.0, 5.0};
  return hold;
}

// The same CVODE run with either derivative: dropped with the drives holding,
// through touchdown, at a tight tolerance.
TEST(PlantDynamics, CvodeTrajectoryMatchesSimbodyDerivative) {
  const model::Model m = robot();
  sim::PlantConfig a_cfg, b_cfg;
  a_cfg.relative_tolerance = b_cfg.relative_tolerance = 1e-8;
  a_cfg.absolute_tolerance = b_cfg.absolute_tolerance = 1e-9;
  b_cfg.derivatives = sim::DerivativeEngine::kSimbody;
  sim::Plant a(m, a_cfg), b(m, b_cfg);
  const dynamics::ConfigVector q = dropped_pose(m);
  const hal::CommandFrame hold = holding_drives();
  for (sim::Plant* p : {&a, &b}) {
    p->reset(q, dynamics::VelocityVector::Zero());
    p->set_command(hold);
  }
  double peak_force = 0.0;
  for (int k = 0; k < 50; ++k) {  // 0.1 s
    ASSERT_EQ(a.advance(2e-3), sim::PlantError::kOk) << a.last_error();
    ASSERT_EQ(b.advance(2e-3), sim::PlantError::kOk) << b.last_error();
    for (const auto& f : a.truth().contact_force_N) peak_force = std::max(peak_force, f.z());
  }
  EXPECT_GT(peak_force, 50.0) << "the run must go through touchdown";
  EXPECT_LE((a.truth().q - b.truth().q).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LE((a.truth().v - b.truth().v).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LE((a.contact_impulse() - b.contact_impulse()).cwiseAbs().maxCoeff(), 1e-5);
}

// The plant's own live check: every 50 intervals it compares the two derivatives.
TEST(PlantDynamics, LiveCrossCheckRunsAndAgrees) {
  const model::Model m = robot();
  sim::PlantConfig cfg;
  cfg.ground = sim::kCarpet;
  sim::Plant plant(m, cfg);
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  q[2] += 0.005;
  plant.reset(q, dynamics::VelocityVector::Zero());
  plant.set_command(holding_drives());
  for (int k = 0; k < 150; ++k) ASSERT_EQ(plant.advance(2e-3), sim::PlantError::kOk) << plant.last_error();
  EXPECT_GT(plant.max_derivative_mismatch(), 0.0) << "never checked";
  EXPECT_LE(plant.max_derivative_mismatch(), kDerivativeTolerance);
}

// A torque source (the firmware-in-the-loop drives' continuous loop) enters every force
// evaluation: a source running the same PD law as a JointCommand gives the same trajectory
// as the command, and the derivative still matches Simbody's with the source in both.
class HoldPd : public sim::JointTorqueSource {
 public:
  explicit HoldPd(const model::Model& m) : m_(m) {}
  void add_joint_torques(const std::array<double, model::kNumJoints>& q, const std::array<double, model::kNumJoints>& v,
                         std::array<double, model::kNumJoints>& tau) const noexcept override {
    for (int j = 0; j < model::kNumJoints; ++j) {
      const double peak = m_.limits.peak_torque_Nm[j];  // the drives clip there too
      tau[j] += std::clamp(200.0 * (0.0 - q[j]) + 5.0 * (0.0 - v[j]), -peak, peak);
    }
  }

 private:
  const model::Model& m_;
};

TEST(PlantDynamics, TorqueSourceActsLikeTheSameCommandLaw) {
  const model::Model m = robot();
  sim::PlantConfig cfg;
  cfg.relative_tolerance = 1e-8;
  cfg.absolute_tolerance = 1e-9;
  sim::Plant a(m, cfg), b(m, cfg);
  const dynamics::ConfigVector q = dropped_pose(m);
  const hal::CommandFrame hold = holding_drives();
  const HoldPd source(m);
  a.reset(q, dynamics::VelocityVector::Zero());
  a.set_command(hold);
  b.reset(q, dynamics::VelocityVector::Zero());
  b.set_command(hal::CommandFrame{});  // all disabled: the source alone drives b
  b.set_torque_source(&source);
  EXPECT_LE(b.derivative_mismatch(), kDerivativeTolerance);
  for (int k = 0; k < 50; ++k) {  // 0.1 s through touchdown
    ASSERT_EQ(a.advance(2e-3), sim::PlantError::kOk) << a.last_error();
    ASSERT_EQ(b.advance(2e-3), sim::PlantError::kOk) << b.last_error();
  }
  EXPECT_LE(b.derivative_mismatch(), kDerivativeTolerance);
  EXPECT_GT((a.truth().q - q).cwiseAbs().maxCoeff(), 1e-3) << "the robot must have moved";
  EXPECT_LE((a.truth().q - b.truth().q).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LE((a.truth().v - b.truth().v).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LE((a.truth().joint_torque_Nm - b.truth().joint_torque_Nm).cwiseAbs().maxCoeff(), 1e-3);
}

}  // namespace
}  // namespace kuavo::test
