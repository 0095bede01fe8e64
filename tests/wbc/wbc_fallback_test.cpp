// The fallback is defined: a failed tick repeats the last good command for hold_ticks, then
// switches to gravity-compensated PD; bad input never reaches the drives as NaN; a good
// tick brings the QP back.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/wbc/wbc_fixture.h"

namespace kuavo::test {
namespace {

struct Rig {
  wbc::WbcConfig cfg;
  dynamics::ConfigVector q = bent_standing_configuration();
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  wbc::WbcReference ref;
  hal::CommandFrame command;
};

Rig& rig(const model::Model& m = wbc_robot()) {
  static Rig r;
  r.cfg = wbc::WbcConfig{};
  wbc::wbc_init(m, r.cfg, wbc_workspace());
  wbc::wbc_reference_hold_state(m, wbc_workspace(), r.q, 0, r.ref);
  return r;
}

void expect_finite(const hal::CommandFrame& c) {
  for (const auto& j : c.joints) {
    EXPECT_TRUE(std::isfinite(j.torque_ff_Nm) && std::isfinite(j.position_ref_rad) &&
                std::isfinite(j.velocity_ref_rad_s) && std::isfinite(j.kp_Nm_per_rad) && std::isfinite(j.kd_Nm_s_per_rad));
  }
}

TEST(WbcFallback, NonFiniteReferenceWithoutHistoryGoesStraightToGravityPd) {
  Rig& r = rig();
  r.ref.com_position_m.x() = std::numeric_limits<double>::quiet_NaN();
  const auto status = wbc::wbc_step_rt(wbc_robot(), r.cfg, wbc_workspace(), r.q, r.v, r.ref, 0, r.command);
  EXPECT_EQ(status, wbc::WbcStatus::kFallbackPd);
  EXPECT_EQ(wbc_workspace().diagnostics.failure, wbc::WbcFailure::kReferenceInvalid);
  expect_finite(r.command);
  // Holds the measured pose with the standing gains; the feed-forward carries the weight
  // (knee torque has the gravity sign: positive on this model with the knees bent).
  for (int j = 0; j < model::kNumJoints; ++j) {
    EXPECT_EQ(r.command.joints[j].position_ref_rad, r.q[7 + j]);
    EXPECT_EQ(r.command.joints[j].velocity_ref_rad_s, 0.0);
  }
  EXPECT_EQ(r.command.joints[0].kp_Nm_per_rad, r.cfg.fallback_leg_kp[0]);
  EXPECT_GT(std::abs(r.command.joints[3].torque_ff_Nm), 5.0);
}

TEST(WbcFallback, StaleReferenceHoldsLastCommandThenFallsBackThenRecovers) {
  Rig& r = rig();
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  ASSERT_EQ(wbc::wbc_step_rt(m, r.cfg, ws, r.q, r.v, r.ref, 0, r.command), wbc::WbcStatus::kOk);
  const hal::CommandFrame good = r.command;
  const hal::TimeNs stale_ns = r.cfg.max_reference_age_ns + 1;
  for (int tick = 1; tick <= r.cfg.hold_ticks; ++tick) {
    ASSERT_EQ(wbc::wbc_step_rt(m, r.cfg, ws, r.q, r.v, r.ref, stale_ns, r.command),
              wbc::WbcStatus::kHoldingLastCommand) << tick;
    EXPECT_EQ(ws.diagnostics.failure, wbc::WbcFailure::kReferenceStale);
    EXPECT_EQ(r.command.joints[3].torque_ff_Nm, good.joints[3].torque_ff_Nm);
    EXPECT_EQ(r.command.stamp_ns, stale_ns);
  }
  EXPECT_EQ(wbc::wbc_step_rt(m, r.cfg, ws, r.q, r.v, r.ref, stale_ns, r.command), wbc::WbcStatus::kFallbackPd);
  expect_finite(r.command);
  // The fallback holds the last good reference pose.
  for (int j = 0; j < model::kNumJoints; ++j) EXPECT_EQ(r.command.joints[j].position_ref_rad, good.joints[j].position_ref_rad);
  r.ref.stamp_ns = stale_ns;  // fresh again
  EXPECT_EQ(wbc::wbc_step_rt(m, r.cfg, ws, r.q, r.v, r.ref, stale_ns, r.command), wbc::WbcStatus::kOk);
  EXPECT_EQ(ws.diagnostics.failed_ticks, 0);
}

TEST(WbcFallback, InfeasibleQpIsReportedAndFallsBack) {
  // Joints that may not accelerate, torque limits of 0.5 N·m and the body spinning at
  // 8 rad/s about the vertical. Holding the arms on a spinning body takes shoulder torques
  // (centripetal loads) that no base acceleration can cancel for both arms at once, and the
  // foot contact forces do not reach the arm joints. (Without the spin the problem is
  // feasible: a free fall with locked joints needs no torque.)
  static model::Model weak;
  weak = wbc_robot();
  weak.limits.torque_Nm.setConstant(0.5);
  Rig& r = rig(weak);
  r.cfg.max_joint_acceleration_rad_s2 = 1e-9;
  dynamics::VelocityVector v = r.v;
  v[5] = 8.0;  // base angular velocity about z (linear part first)
  wbc::WbcWorkspace& ws = wbc_workspace();
  const auto status = wbc::wbc_step_rt(weak, r.cfg, ws, r.q, v, r.ref, 0, r.command);

  // Independent certificate of infeasibility from the QP's own rows, not from its solver:
  // an arm or head joint's torque row is C_b a_b + C_j q̈_j (+ no force columns) within
  // [lo, hi]. With |q̈_j| ≤ 1e-9, the joint part is below `slack`. If even the best base
  // acceleration (least squares to the middle of the boxes) leaves a 2-norm residual larger
  // than √m·(half width + slack), some row is outside its box for every a_b.
  constexpr int kNj = model::kNumJoints, kFirst = model::kLeftArmFirst, kRows = kNj - kFirst;
  constexpr int kTorqueRow0 = wbc::kNumInequalities - kNj;  // the torque rows come last
  const auto& C = ws.qp.C;
  Eigen::Matrix<double, kRows, 6> Cb;
  Eigen::Matrix<double, kRows, 1> mid, half;
  double slack = 0.0;
  for (int i = 0; i < kRows; ++i) {
    const int row = kTorqueRow0 + kFirst + i;
    Cb.row(i) = C.row(row).head<6>();
    ASSERT_EQ(C.row(row).tail<wbc::kNumForces>().cwiseAbs().maxCoeff(), 0.0) << "forces reach joint " << kFirst + i;
    mid(i) = 0.5 * (ws.qp.c_lower(row) + ws.qp.c_upper(row));
    half(i) = 0.5 * (ws.qp.c_upper(row) - ws.qp.c_lower(row));
    slack = std::max(slack, C.row(row).segment<kNj>(6).cwiseAbs().sum() * 1e-9);
  }
  ASSERT_NEAR(half.maxCoeff(), 0.5 - 1e-6, 1e-12);  // the torque rows (planned 1 µN·m inside the limit)
  const Eigen::Matrix<double, 6, 1> a_b = Cb.colPivHouseholderQr().solve(mid);
  const double residual = (Cb * a_b - mid).norm();
  std::printf("infeasible QP: certificate residual %.2f N·m > bound %.2f; solver status %s after %d iterations\n",
              residual, std::sqrt(double(kRows)) * (0.5 + slack), qp::to_string(ws.diagnostics.qp_status),
              ws.diagnostics.qp_iterations);
  ASSERT_GT(residual, std::sqrt(double(kRows)) * (0.5 + slack));

  EXPECT_EQ(status, wbc::WbcStatus::kFallbackPd);
  EXPECT_EQ(ws.diagnostics.failure, wbc::WbcFailure::kQpFailed);
  EXPECT_EQ(ws.diagnostics.qp_status, qp::QpStatus::kInfeasible);
  expect_finite(r.command);
  for (const auto& j : r.command.joints) EXPECT_LE(std::abs(j.torque_ff_Nm), 0.5 + 1e-12);
}

TEST(WbcFallback, ExtremeReferenceStaysSoftNonFiniteOneIsRefusedAndHeld) {
  // All points "in contact" but the reference asks the torso to be 1.5 rad pitched with a
  // huge CoM acceleration: the QP is feasible (tasks are soft) so this must stay kOk ...
  Rig& r = rig();
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  ASSERT_EQ(wbc::wbc_step_rt(m, r.cfg, ws, r.q, r.v, r.ref, 0, r.command), wbc::WbcStatus::kOk);
  r.ref.base_euler_zyx_rad[1] = 1.5;
  r.ref.momentum_rate[2] = 1e5;
  const auto soft = wbc::wbc_step_rt(m, r.cfg, ws, r.q, r.v, r.ref, 0, r.command);
  EXPECT_EQ(soft, wbc::WbcStatus::kOk);
  expect_finite(r.command);
  for (int j = 0; j < model::kNumJoints; ++j) {
    EXPECT_LE(std::abs(ws.diagnostics.torque_Nm[j]), m.limits.torque_Nm[j] + 1e-6);
  }
  // ... while an infinite one is refused and the last good command is held.
  r.ref.momentum_rate[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(wbc::wbc_step_rt(m, r.cfg, ws, r.q, r.v, r.ref, 0, r.command), wbc::WbcStatus::kHoldingLastCommand);
  EXPECT_EQ(ws.diagnostics.failure, wbc::WbcFailure::kReferenceInvalid);
  expect_finite(r.command);
}

TEST(WbcFallback, IterationCapIsAFailure) {
  Rig& r = rig();
  r.cfg.qp_max_iterations = 1;
  wbc::wbc_init(wbc_robot(), r.cfg, wbc_workspace());
  // A moving state needs several working-set changes.
  dynamics::VelocityVector v = r.v;
  v.setConstant(0.5);
  for (int c = 0; c < 4; ++c) r.ref.in_contact[c] = false;
  const auto status = wbc::wbc_step_rt(wbc_robot(), r.cfg, wbc_workspace(), r.q, v, r.ref, 0, r.command);
  EXPECT_EQ(wbc_workspace().diagnostics.qp_status, qp::QpStatus::kMaxIterations);
  EXPECT_EQ(status, wbc::WbcStatus::kFallbackPd);
  expect_finite(r.command);
}

TEST(WbcFallback, NonFiniteStateCommandsDamping) {
  Rig& r = rig();
  dynamics::VelocityVector v = r.v;
  v[10] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(wbc::wbc_step_rt(wbc_robot(), r.cfg, wbc_workspace(), r.q, v, r.ref, 0, r.command), wbc::WbcStatus::kDamping);
  for (const auto& j : r.command.joints) {
    EXPECT_EQ(j.mode, hal::JointMode::kDamping);
    EXPECT_EQ(j.torque_ff_Nm, 0.0);
    EXPECT_EQ(j.kd_Nm_s_per_rad, r.cfg.damping_kd);
  }
}

TEST(WbcConfig, DefaultsAreValidAndBadValuesAreNamed) {
  wbc::WbcConfig c;
  EXPECT_EQ(wbc::wbc_validate_config(c), nullptr);
  c.weight_contact_force = 0.0;
  EXPECT_NE(wbc::wbc_validate_config(c), nullptr);
  c = wbc::WbcConfig{};
  c.friction_coefficient = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(wbc::wbc_validate_config(c), nullptr);
  EXPECT_STREQ(wbc::to_string(wbc::WbcStatus::kFallbackPd), "fallback_pd");
  EXPECT_EQ(static_cast<int>(wbc::WbcStatus::kDamping), 3);  // stable numbers
  EXPECT_EQ(static_cast<int>(wbc::WbcFailure::kStateInvalid), 5);
}

}  // namespace
}  // namespace kuavo::test
