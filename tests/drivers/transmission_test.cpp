// Ankle parallel linkage and linear (knee) transmission: zero pose, position
// round trip over the joint range, Jacobian vs finite differences, torque
// mapping vs virtual work, and no heap in the maps.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drivers/transmission/ankle_linkage.h"
#include "drivers/transmission/linear_transmission.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers {
namespace {

// Joint ranges, FACTS.md §2.2 (leg_l5 pitch, leg_l6 roll).
constexpr double kPitchMin = -0.8727, kPitchMax = 0.3491;
constexpr double kRollMin = -0.2618, kRollMax = 0.2618;

class Ankle : public ::testing::TestWithParam<int> {
 protected:
  AnkleGeometry g = GetParam() == 0 ? make_left_ankle() : make_right_ankle();
};

TEST_P(Ankle, ZeroPoseAndPublishedRodLengths) {
  Vec2 m;
  ASSERT_TRUE(ankle_motor_from_joint_rt(g, Vec2::Zero(), m));
  EXPECT_NEAR(m[0], 0.0, 1e-12);
  EXPECT_NEAR(m[1], 0.0, 1e-12);
  // FACTS.md §2.4: rods 0.256 m and 0.193 m (rounded to the mm).
  EXPECT_NEAR(g.rod_length_m[0], 0.256, 1e-3);
  EXPECT_NEAR(g.rod_length_m[1], 0.193, 1e-3);
}

TEST_P(Ankle, PositionRoundTripOverTheJointRange) {
  int max_iterations = 0;
  for (int i = 0; i <= 20; ++i) {
    for (int k = 0; k <= 20; ++k) {
      const Vec2 q(kPitchMin + (kPitchMax - kPitchMin) * i / 20.0, kRollMin + (kRollMax - kRollMin) * k / 20.0);
      Vec2 m;
      ASSERT_TRUE(ankle_motor_from_joint_rt(g, q, m)) << q.transpose();
      Vec2 back = Vec2::Zero();  // cold start: the hardest case
      int iterations = 0;
      ASSERT_EQ(ankle_joint_from_motor_rt(g, m, back, &iterations), DriverError::kOk) << q.transpose();
      EXPECT_NEAR(back[0], q[0], 1e-9);
      EXPECT_NEAR(back[1], q[1], 1e-9);
      max_iterations = std::max(max_iterations, iterations);
    }
  }
  EXPECT_LT(max_iterations, kAnkleNewtonMaxIterations);
}

TEST_P(Ankle, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> up(kPitchMin, kPitchMax), ur(kRollMin, kRollMax);
  const double h = 1e-6;
  for (int n = 0; n < 50; ++n) {
    const Vec2 q(up(rng), ur(rng));
    Vec2 m;
    ASSERT_TRUE(ankle_motor_from_joint_rt(g, q, m));
    const Mat2 J = ankle_jacobian_rt(g, q, m);
    for (int j = 0; j < 2; ++j) {
      Vec2 qp = q, qm = q, mp, mm;
      qp[j] += h;
      qm[j] -= h;
      ASSERT_TRUE(ankle_motor_from_joint_rt(g, qp, mp));
      ASSERT_TRUE(ankle_motor_from_joint_rt(g, qm, mm));
      const Vec2 fd = (mp - mm) / (2 * h);
      EXPECT_NEAR(J(0, j), fd[0], 1e-6);
      EXPECT_NEAR(J(1, j), fd[1], 1e-6);
    }
  }
}

TEST_P(Ankle, LinkageActsLikeAnAnkle) {
  // Pitch turns both cranks the same way; roll turns them against each other.
  Vec2 m;
  ASSERT_TRUE(ankle_motor_from_joint_rt(g, Vec2::Zero(), m));
  const Mat2 J = ankle_jacobian_rt(g, Vec2::Zero(), m);
  EXPECT_GT(J(0, 0) * J(1, 0), 0.0);
  EXPECT_LT(J(0, 1) * J(1, 1), 0.0);
}

TEST_P(Ankle, TorqueMappingConservesPower) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> up(kPitchMin, kPitchMax), ur(kRollMin, kRollMax), u(-10, 10);
  for (int n = 0; n < 50; ++n) {
    const Vec2 q(up(rng), ur(rng));
    Vec2 m;
    ASSERT_TRUE(ankle_motor_from_joint_rt(g, q, m));
    const Mat2 J = ankle_jacobian_rt(g, q, m);
    const Vec2 qd(u(rng), u(rng)), tau_m(u(rng), u(rng));
    const Vec2 md = ankle_motor_velocity_rt(J, qd);
    const Vec2 tau_j = ankle_joint_torque_rt(J, tau_m);
    // Virtual work: tau_jointᵀ qd_joint = tau_motorᵀ qd_motor.
    EXPECT_NEAR(tau_j.dot(qd), tau_m.dot(md), 1e-9);
    // The inverse maps invert.
    EXPECT_LT((ankle_motor_torque_rt(J, tau_j) - tau_m).norm(), 1e-9);
    EXPECT_LT((ankle_joint_velocity_rt(J, md) - qd).norm(), 1e-9);
  }
}

TEST_P(Ankle, UnreachableMotorAnglesAreReported) {
  Vec2 q(0.1, 0.05);
  EXPECT_EQ(ankle_joint_from_motor_rt(g, Vec2(3.0, -3.0), q), DriverError::kTransmissionUnsolved);
  EXPECT_DOUBLE_EQ(q[0], 0.1);  // unchanged on failure
  // A rod far too short for the crank to reach the foot.
  AnkleGeometry broken = g;
  broken.rod_length_m[0] = 0.1;
  Vec2 m(7.0, 7.0);
  EXPECT_FALSE(ankle_motor_from_joint_rt(broken, Vec2::Zero(), m));
  EXPECT_DOUBLE_EQ(m[0], 7.0);
}

TEST_P(Ankle, MapsDoNotAllocate) {
  Vec2 q(0.2, -0.1), m, back = Vec2::Zero();
  test::AllocTrap trap;
  ankle_motor_from_joint_rt(g, q, m);
  (void)ankle_joint_from_motor_rt(g, m, back);
  const Mat2 J = ankle_jacobian_rt(g, q, m);
  const Vec2 t = ankle_motor_torque_rt(J, Vec2(1, 2));
  EXPECT_EQ(trap.count(), 0u);
  EXPECT_TRUE(t.allFinite());
}

INSTANTIATE_TEST_SUITE_P(BothLegs, Ankle, ::testing::Values(0, 1),
                         [](const auto& info) { return info.param == 0 ? "Left" : "Right"; });

TEST(LinearTransmission, ReversedKneeKeepsPowerAndRoundTrips) {
  const LinearTransmission knee{-1.0, 0.1};
  EXPECT_DOUBLE_EQ(motor_position_rad(knee, 0.5), -0.4);
  EXPECT_DOUBLE_EQ(joint_position_rad(knee, motor_position_rad(knee, 1.2)), 1.2);
  EXPECT_DOUBLE_EQ(motor_velocity_rad_s(knee, 2.0), -2.0);
  EXPECT_DOUBLE_EQ(joint_velocity_rad_s(knee, -2.0), 2.0);
  const LinearTransmission geared{3.0, 0.0};
  const double qd = 1.5, tau = 9.0;
  EXPECT_DOUBLE_EQ(motor_torque_Nm(geared, tau) * motor_velocity_rad_s(geared, qd), tau * qd);
  EXPECT_DOUBLE_EQ(joint_torque_Nm(knee, motor_torque_Nm(knee, 7.0)), 7.0);
}

}  // namespace
}  // namespace kuavo::drivers
