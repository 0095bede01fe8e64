// Contact forces for a fixed motion (tools/mocap/contact_forces.h), judged by the oracle
// (tools/mocap/dynamics_check.h: its own RNEA, residual, friction and torque counts), not by
// the QP that made them.
#include "tools/mocap/contact_forces.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"
#include "tests/mocap/motion_fixture.h"

namespace kuavo::mocap {
namespace {

using namespace kuavo::mocap::test;

constexpr double kMu = 0.5;
constexpr int kKneeLeft = model::kLeftLegFirst + 3;

std::vector<ConfigVector> repeat(const ConfigVector& q, int n) { return std::vector<ConfigVector>(n, q); }

DynamicsCheck oracle(const model::Model& m, const std::vector<ConfigVector>& q, const std::vector<ContactLabel>& l,
                     const std::vector<ForceVector>* f) {
  DynamicsCheck out;
  check_dynamics(m, q, l, kRate_hz, f, kMu, out);
  return out;
}

// The forces contact_forces_for_motion gives for the frames.
std::vector<ForceVector> solve(const model::Model& m, const std::vector<ConfigVector>& q,
                               const std::vector<ContactLabel>& l, const std::vector<ForceVector>& prior,
                               ContactForceStats& stats) {
  std::vector<ForceVector> out;
  contact_forces_for_motion(m, q, l, kRate_hz, kMu, prior, out, stats);
  return out;
}

// Standing on the left foot, the right one 5 cm up: the standing pose with the pelvis moved
// over the left foot, then by `shift` (x ahead, y to the left, z up).
ConfigVector on_left_foot(const Vec3& shift) {
  const Standing& st = standing();
  Keyframe k = stand_key();
  k.right_down = false;
  k.right.centre.z() = 0.05;
  k.base_shift = Vec3(0.0, 0.5 * (st.feet[0].centre.y() - st.feet[1].centre.y()), 0.0) + shift;
  return frame_of(k, st.q);
}

// A pure pitch couple on each foot, opposite on the two: +d on the left toes and the right
// heels, −d on the left heels and the right toes. No net force, no net moment (the couples
// cancel): the base wrench is unchanged, only the ankles and knees feel it.
ForceVector pitch_couples(double d) {
  ForceVector f = ForceVector::Zero();
  for (int c = 0; c < kCorners; ++c) {
    const bool toe = (c % 4) < 2, left = c < 4;
    f[3 * c + 2] = (toe == left) ? d : -d;
  }
  return f;
}

// A distribution that already produces the frames within every limit comes back as it was.
TEST(mocap_contact_forces, AFeasiblePriorComesBackUnchanged) {
  const int n = 6;
  const auto q = repeat(standing().q, n);
  const std::vector<ContactLabel> labels(n, ContactLabel::kDoubleSupport);
  const DynamicsCheck least_norm = oracle(robot(), q, labels, nullptr);
  ASSERT_EQ(least_norm.torque_violations, 0);
  ASSERT_EQ(least_norm.friction_violations, 0);
  ContactForceStats stats;
  const std::vector<ForceVector> out = solve(robot(), q, labels, least_norm.forces_N, stats);
  ASSERT_EQ(out.size(), static_cast<std::size_t>(n));
  double worst = 0.0;
  for (int i = 0; i < n; ++i) worst = std::max(worst, (out[i] - least_norm.forces_N[i]).cwiseAbs().maxCoeff());
  RecordProperty("max_change_N", number(worst));
  EXPECT_LT(worst, 1e-4);  // the prior's own residual is ~1e-6 N (the oracle's regularization)
  EXPECT_EQ(stats.frames_over_limit, 0);
  EXPECT_EQ(stats.frames_infeasible, 0);
}

// Forces that do not produce the motion (half the weight, all of it on the left toes) become
// forces that do: the oracle's residual vanishes, every corner inside its pyramid.
TEST(mocap_contact_forces, ForcesThatDoNotProduceTheMotionAreReplacedByOnesThatDo) {
  const int n = 4;
  const auto q = repeat(standing().q, n);
  const std::vector<ContactLabel> labels(n, ContactLabel::kDoubleSupport);
  ForceVector wrong = ForceVector::Zero();
  wrong[2] = wrong[5] = 0.25 * weight_N();
  wrong[0] = 100.0;  // and a push beyond its pyramid
  const std::vector<ForceVector> prior(n, wrong);
  const DynamicsCheck before = oracle(robot(), q, labels, &prior);
  ASSERT_GT(before.base_force_residual_N_max, 0.4 * weight_N());
  ASSERT_GT(before.friction_violations, 0);
  ContactForceStats stats;
  const std::vector<ForceVector> out = solve(robot(), q, labels, prior, stats);
  const DynamicsCheck after = oracle(robot(), q, labels, &out);
  RecordProperty("residual_N", number(after.base_force_residual_N_max));
  EXPECT_LT(after.base_force_residual_N_max, 1e-6 * weight_N());
  EXPECT_LT(after.base_moment_residual_Nm_max, 1e-6 * weight_N());
  EXPECT_EQ(after.friction_violations, 0);
  EXPECT_EQ(after.torque_violations, 0);
  EXPECT_EQ(stats.frames_infeasible, 0);
}

// Double support shares the load freely: a distribution that produces the frames but loads
// the left knee beyond its limit (pitch couples, no net wrench) is moved to one within it.
// The limit is set between the two distributions' knee torques as the oracle computes them.
TEST(mocap_contact_forces, DoubleSupportMovesTheLoadOffAJointBeyondItsLimit) {
  const int n = 3;
  const auto q = repeat(standing().q, n);
  const std::vector<ContactLabel> labels(n, ContactLabel::kDoubleSupport);
  const DynamicsCheck least_norm = oracle(robot(), q, labels, nullptr);
  std::vector<ForceVector> prior(n);
  for (int i = 0; i < n; ++i) prior[i] = least_norm.forces_N[i] + pitch_couples(-0.08 * weight_N());
  const DynamicsCheck loaded = oracle(robot(), q, labels, &prior);
  ASSERT_LT(loaded.base_force_residual_N_max, 1e-4);  // still the frames' wrench
  ASSERT_EQ(loaded.friction_violations, 0);           // still inside the pyramids
  const double even = std::abs(least_norm.tau_Nm[0][kKneeLeft]), uneven = std::abs(loaded.tau_Nm[0][kKneeLeft]);
  ASSERT_GT(uneven, even + 5.0);
  model::Model weak = robot();
  weak.limits.torque_Nm[kKneeLeft] = 0.5 * (even + uneven);
  ASSERT_GT(oracle(weak, q, labels, &prior).torque_violations, 0);
  ContactForceStats stats;
  const std::vector<ForceVector> out = solve(weak, q, labels, prior, stats);
  const DynamicsCheck after = oracle(weak, q, labels, &out);
  RecordProperty("knee_Nm", number(std::abs(after.tau_Nm[0][kKneeLeft])));
  EXPECT_EQ(after.torque_violations, 0);
  EXPECT_LE(std::abs(after.tau_Nm[0][kKneeLeft]), weak.limits.torque_Nm[kKneeLeft] + 1e-6);
  EXPECT_LT(after.base_force_residual_N_max, 1e-6 * weight_N());
  EXPECT_EQ(after.friction_violations, 0);
  EXPECT_EQ(stats.frames_over_limit, 0);
}

// Single support fixes the foot's wrench: a knee that needs more than its limit stays beyond
// it, and the excess reported is the oracle's |τ| − limit.
TEST(mocap_contact_forces, SingleSupportReportsTheExcessTheMotionNeeds) {
  const int n = 3;
  const auto q = repeat(on_left_foot(Vec3(0.0, 0.0, -0.03)), n);
  const std::vector<ContactLabel> labels(n, ContactLabel::kLeftSupport);
  const DynamicsCheck least_norm = oracle(robot(), q, labels, nullptr);
  ASSERT_EQ(least_norm.zmp_outside_m_max, 0.0);  // the CoM over the left sole
  ASSERT_EQ(least_norm.friction_violations, 0);
  const double knee = std::abs(least_norm.tau_Nm[0][kKneeLeft]);
  ASSERT_GT(knee, 20.0);
  model::Model weak = robot();
  weak.limits.torque_Nm[kKneeLeft] = 5.0;
  ContactForceStats stats;
  const std::vector<ForceVector> out =
      solve(weak, q, labels, std::vector<ForceVector>(n, ForceVector::Zero()), stats);
  RecordProperty("excess_Nm", number(stats.max_excess_Nm));
  EXPECT_EQ(stats.frames_over_limit, n);
  EXPECT_EQ(stats.frames_infeasible, 0);
  EXPECT_NEAR(stats.max_excess_Nm, knee - 5.0, 1e-3);
  const DynamicsCheck after = oracle(weak, q, labels, &out);
  EXPECT_LT(after.base_force_residual_N_max, 1e-6 * weight_N());
  for (int i = 0; i < n; ++i) {
    for (int c = 4; c < kCorners; ++c) EXPECT_EQ(out[i].segment<3>(3 * c), Vec3::Zero()) << "swing corner";
  }
}

// The ankle slots are its two motors, as the oracle counts them: the CoM over the front
// outer part of the left sole loads pitch and roll together, which no single motor holds at
// 27 N·m, and the excess reported is the oracle's worst motor's.
TEST(mocap_contact_forces, AnAnkleBeyondItsMotorsIsReportedInMotorTorque) {
  const int n = 2;
  const auto q = repeat(on_left_foot(Vec3(0.05, 0.035, -0.03)), n);
  const std::vector<ContactLabel> labels(n, ContactLabel::kLeftSupport);
  const DynamicsCheck least_norm = oracle(robot(), q, labels, nullptr);
  ASSERT_EQ(least_norm.zmp_outside_m_max, 0.0);
  const int worst = least_norm.max_torque_ratio_joint;
  ASSERT_TRUE(worst == model::kLeftLegFirst + 4 || worst == model::kLeftLegFirst + 5) << worst;
  ASSERT_GT(least_norm.max_torque_ratio, 1.05);
  const drivers::AnkleMotors motors = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot()));
  ASSERT_TRUE(motors.active);
  const double limit = motors.limit_Nm[0](worst - model::kLeftLegFirst - 4);
  ContactForceStats stats;
  const std::vector<ForceVector> out =
      solve(robot(), q, labels, std::vector<ForceVector>(n, ForceVector::Zero()), stats);
  RecordProperty("excess_Nm", number(stats.max_excess_Nm));
  EXPECT_EQ(stats.frames_over_limit, n);
  EXPECT_NEAR(stats.max_excess_Nm, (least_norm.max_torque_ratio - 1.0) * limit, 1e-3);
}

// A base wrench no forces inside the pyramids supply (standing on the left foot with the CoM
// between the feet): counted, the forces the nearest within the pyramids, the swing foot's zero.
TEST(mocap_contact_forces, AWrenchOutOfTheConesIsCountedAndStaysInThem) {
  const int n = 3;
  const auto q = repeat(standing().q, n);
  const std::vector<ContactLabel> labels(n, ContactLabel::kLeftSupport);
  ContactForceStats stats;
  const std::vector<ForceVector> out =
      solve(robot(), q, labels, std::vector<ForceVector>(n, ForceVector::Zero()), stats);
  EXPECT_EQ(stats.frames_infeasible, n);
  const DynamicsCheck after = oracle(robot(), q, labels, &out);
  EXPECT_EQ(after.friction_violations, 0);
  EXPECT_GT(after.base_moment_residual_Nm_max, 1.0);  // what the cones cannot give stays a residual
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(out[i].allFinite());
    for (int c = 4; c < kCorners; ++c) EXPECT_EQ(out[i].segment<3>(3 * c), Vec3::Zero()) << "swing corner";
  }
}

}  // namespace
}  // namespace kuavo::mocap
