// Stepping in place: the swing rows (zero force, normal velocity) and the shifted warm start.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "tests/mpc/mpc_fixture.h"

namespace kuavo::test {
namespace {

using mpc::MpcStatus;

// Sole-corner positions (world) of the MPC's predicted state x_k.
Eigen::Matrix<double, 24, 1> predicted_corners(MpcFixture& f, int k) {
  const dynamics::ConfigVector q = mpc::configuration_from_state(f.ws.x[k], f.ws.head_rad[k]);
  dynamics::forward_kinematics(f.model, f.data, q);
  Eigen::Matrix<double, 24, 1> p;
  for (int c = 0; c < 8; ++c) p.segment<3>(3 * c) = dynamics::frame_position(f.model, f.data, c);
  return p;
}

TEST(MpcStepping, ConvergedPlanLiftsTheSwingFootAndLeansOverTheStanceFoot) {
  MpcFixture& f = mpc_fixture();
  const SteppingPlan plan;
  stepping_window(f, 0, plan);
  const dynamics::VelocityVector v0 = dynamics::VelocityVector::Zero();
  for (int it = 0; it < 15; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan), MpcStatus::kOk) << it;
  }
  std::printf("stepping: violation after 15 iterations %.2e\n", f.plan.constraint_violation);
  EXPECT_LT(f.plan.constraint_violation, 1e-6);
  const int T = f.ws.horizon;
  const double y_left = f.window.knots[0].point_position_m[1], y_right = f.window.knots[0].point_position_m[13];
  double max_z_err = 0.0, max_swing_force = 0.0, min_stance_fz = 1e9;
  bool saw_swing = false;
  for (int k = 0; k < T; ++k) {
    const planner::PlanKnot& knot = f.window.knots[k];
    const Eigen::Matrix<double, 24, 1> p = predicted_corners(f, k);
    for (int c = 0; c < 8; ++c) {
      if (knot.in_contact[c]) {
        min_stance_fz = std::min(min_stance_fz, f.ws.u[k][3 * c + 2]);
        continue;
      }
      saw_swing = true;
      max_swing_force = std::max(max_swing_force, f.ws.u[k].segment<3>(3 * c).cwiseAbs().maxCoeff());
      max_z_err = std::max(max_z_err, std::abs(p[3 * c + 2] - knot.point_position_m[3 * c + 2]));
    }
  }
  // Where is the CoM (from the plan knots' kinematics) in the middle of the left swing (k = 25)?
  const dynamics::ConfigVector q25 = mpc::configuration_from_state(f.ws.x[25], f.ws.head_rad[25]);
  dynamics::forward_kinematics(f.model, f.data, q25);
  dynamics::crba(f.model, f.data);
  const double lean = (f.data.com_m.y() - 0.5 * (y_left + y_right)) / (y_right - 0.5 * (y_left + y_right));
  std::printf("swing corner z error max %.2f mm, swing force max %.2e N, min stance fz %.1f N, CoM at mid-swing %.0f %% of the way to the stance foot\n",
              1e3 * max_z_err, max_swing_force, min_stance_fz, 100 * lean);
  EXPECT_TRUE(saw_swing);
  EXPECT_LT(max_swing_force, 1e-6);
  EXPECT_LT(max_z_err, 0.01);  // the normal-velocity rows track z with gain 20/s
  EXPECT_GT(min_stance_fz, -1.0);
  EXPECT_GT(lean, 0.5);  // the CoM is moved over the stance foot
}

// 50 Hz calls with the window advancing one stage each time and the "measured" state taken from
// the previous prediction (perfect tracking): the warm start is shifted, every call succeeds,
// and the linearization stays consistent through lift-offs and touchdowns.
TEST(MpcStepping, ShiftedWarmStartThroughFourSteps) {
  MpcFixture& f = mpc_fixture();
  const SteppingPlan plan;
  static mpc::CentroidalPoint point;
  dynamics::ConfigVector q = f.q0;
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  double max_violation = 0.0, max_tail_violation = 0.0;
  const int calls = static_cast<int>(4 * (plan.stance_s + plan.swing_s) / f.config.dt_s);
  for (int call = 0; call < calls; ++call) {
    stepping_window(f, static_cast<hal::TimeNs>(call) * 20'000'000, plan);
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, q, v, f.window, f.plan), MpcStatus::kOk) << call;
    ASSERT_EQ(f.plan.count, mpc::kMpcPlanKnots);
    // Consistency of the linearization point over the knots the WBC reads (the newest tail stage
    // is a guess by construction and shows up in plan.constraint_violation, up to ~0.4 here).
    for (int k = 0; call >= 3 && k < mpc::kMpcPlanKnots; ++k) {
      const auto& st = f.ws.qp.stages[k];
      max_violation = std::max(max_violation, st.b.cwiseAbs().maxCoeff());
      if (st.num_eq > 0) max_violation = std::max(max_violation, st.e.head(st.num_eq).cwiseAbs().maxCoeff());
    }
    max_tail_violation = std::max(max_tail_violation, f.plan.constraint_violation);
    // Next measured state = predicted x_1 (and the base twist that goes with it).
    mpc::centroidal_evaluate(f.model, f.ws.x[1], f.ws.u[1], f.ws.head_rad[1], point);
    q = mpc::configuration_from_state(f.ws.x[1], f.ws.head_rad[1]);
    v.setZero();
    v.head<6>() = point.base_twist;
    v.segment<mpc::kNumMpcJoints>(6) = f.ws.u[1].segment<mpc::kNumMpcJoints>(mpc::kUJointVelocity);
  }
  std::printf("4 steps: max violation at the linearization point, knots 0-9 %.2e, whole horizon %.2e; final base z %.3f m, y %.3f m\n",
              max_violation, max_tail_violation, q[2], q[1]);
  EXPECT_LT(max_violation, 1e-3);
  EXPECT_NEAR(q[2], f.q0[2], 0.03);
  EXPECT_NEAR(q[1], f.q0[1], 0.05);
}

}  // namespace
}  // namespace kuavo::test

namespace kuavo::test {
namespace {

// Every allowed horizon converges on the stepping problem (1.4 s uses the full capacity, 70).
class MpcHorizon : public ::testing::TestWithParam<double> {};

TEST_P(MpcHorizon, ConvergesOnTheSteppingProblem) {
  mpc::MpcConfig cfg;
  cfg.horizon_s = GetParam();
  MpcFixture& f = mpc_fixture(cfg);
  EXPECT_EQ(f.ws.horizon, static_cast<int>(std::lround(GetParam() / 0.02)));
  stepping_window(f, 0, SteppingPlan{});
  for (int it = 0; it < 12; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, dynamics::VelocityVector::Zero(), f.window, f.plan),
              mpc::MpcStatus::kOk);
  }
  EXPECT_LT(f.plan.constraint_violation, 1e-6);
  EXPECT_EQ(f.plan.count, mpc::kMpcPlanKnots);
}

INSTANTIATE_TEST_SUITE_P(Horizons, MpcHorizon, ::testing::Values(0.6, 0.8, 1.0, 1.4),
                         [](const auto& info) { return std::to_string(static_cast<int>(std::lround(info.param * 1000))) + "ms"; });

}  // namespace
}  // namespace kuavo::test
