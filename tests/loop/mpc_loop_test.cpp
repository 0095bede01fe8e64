// The online stack with the centroidal RTI-MPC as its planner, closed on the Simbody plant
// with the state estimator: the built-in dance end to end (BVH → retargeting → balance
// filter → MPC + WBC), and stepping in place. Oracles: the simulator's truth (falls, loads),
// the motion (tracking), the MPC's own status.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "tests/support/test_robot.h"
#include "controllers/planner/balance_filter.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/standing/standing_controller.h"
#include "sim/motion_loop.h"
#include "tools/mocap/motion_plan_io.h"

namespace kuavo::test {
namespace {

const model::Model& robot() { return kuavo::test::s45_robot(); }

// The built-in dance as `kuavo retarget` makes it, then the balance filter.
planner::MotionPlan& dance_plan() {
  static auto plan = std::make_unique<planner::MotionPlan>();
  static bool made = false;
  if (made) return *plan;
  std::string error;
  EXPECT_TRUE(mocap::built_in_dance_plan(robot(), *plan, error)) << error;
  auto ws = std::make_unique<planner::BalanceFilterWorkspace>();
  planner::BalanceFilterReport report;
  EXPECT_EQ(planner::balance_filter(robot(), planner::BalanceFilterConfig{}, *plan, *ws, report), nullptr);
  made = true;
  return *plan;
}

void print(const char* name, const sim::MotionSummary& s) {
  std::printf("%s: fell %d at %.2f s of %.1f, legs %.4f rad, arms %.4f rad, CoM err %.3f m, ZMP at edge %.3f s, "
              "est v rms %.4f m/s, MPC p50 %.2f ms, WBC p50 %.0f us, mpc failures %llu, not-ok ticks %llu\n",
              name, s.run.fell, s.run.fell_at_s, s.run.sim_time_s, s.tracking_rms_legs_rad, s.tracking_rms_arms_rad,
              s.com_err_m_max, s.zmp_at_edge_s, s.estimator_velocity_rms_m_s, s.mpc_ms.p50, s.wbc_us.p50,
              static_cast<unsigned long long>(s.mpc_failures), static_cast<unsigned long long>(s.wbc_not_ok_ticks));
}

TEST(MpcLoop, TheBuiltInDanceOnTheFloorWithTheEstimator) {
  const planner::MotionPlan& plan = dance_plan();
  sim::MotionRunConfig cfg;
  cfg.stack.planner = stack::PlannerKind::kMpc;
  const sim::MotionSummary s = sim::run_motion(robot(), plan, cfg);
  print("dance, floor, MPC", s);
  ASSERT_TRUE(s.run.ok) << s.run.error;
  EXPECT_FALSE(s.run.fell);
  EXPECT_GE(s.run.sim_time_s, planner::motion_plan_duration_s(plan));
  EXPECT_LT(s.tracking_rms_legs_rad, 0.05);
  EXPECT_LT(s.tracking_rms_arms_rad, 0.05);
  EXPECT_EQ(s.mpc_failures, 0u);
  EXPECT_GT(s.plans_applied, 1400u);  // 50 Hz over 31 s
  // The estimator against the simulator's truth over the whole dance (measured 0.029 m/s
  // and 0.12 m: leg odometry cannot see the feet slipping on the floor).
  EXPECT_LT(s.estimator_velocity_rms_m_s, 0.05);
  EXPECT_LT(s.estimator_position_drift_m, 0.25);
}

// The paper's horizon experiment: on carpet, with a 10 N·s sideways push mid-dance, the
// 1.2 s horizon must carry the dance to the end. The 0.6 s run is reported beside it (at
// the time of writing it falls at ~25 s, in the side steps with arm pumps).
TEST(MpcLoop, HorizonExperimentOnCarpetWithAPush) {
  const planner::MotionPlan& plan = dance_plan();
  sim::MotionRunConfig cfg;
  cfg.stack.planner = stack::PlannerKind::kMpc;
  cfg.run.ground = sim::kCarpet;
  cfg.run.push.start_s = 15.0;
  cfg.run.push.duration_s = 0.1;
  cfg.run.push.force_N = sim::Vec3(0.0, 100.0, 0.0);
  sim::MotionTrace long_trace, short_trace;
  cfg.stack.mpc.horizon_s = 1.2;
  const sim::MotionSummary long_h = sim::run_motion(robot(), plan, cfg, &long_trace);
  cfg.stack.mpc.horizon_s = 0.6;
  const sim::MotionSummary short_h = sim::run_motion(robot(), plan, cfg, &short_trace);
  print("dance, carpet, push, horizon 1.2 s", long_h);
  print("dance, carpet, push, horizon 0.6 s", short_h);
  auto knee_range = [](const sim::MotionTrace& t) {
    double lo = 1e9, hi = -1e9;
    for (const auto& q : t.q) lo = std::min(lo, q[model::kLeftLegFirst + 3]), hi = std::max(hi, q[model::kLeftLegFirst + 3]);
    return hi - lo;
  };
  std::printf("left knee range: 1.2 s %.3f rad, 0.6 s %.3f rad\n", knee_range(long_trace), knee_range(short_trace));
  ASSERT_TRUE(long_h.run.ok) << long_h.run.error;
  EXPECT_FALSE(long_h.run.fell);
  EXPECT_GT(long_h.run.max_foot_sink_m, 0.01);  // the soft ground
  EXPECT_EQ(long_h.mpc_failures, 0u);
  EXPECT_LT(long_h.tracking_rms_legs_rad, 0.08);
  EXPECT_LT(long_h.estimator_velocity_rms_m_s, 0.05);
}

// The whole online stack holding a standing pose for 30 s on the floor and on carpet.
TEST(MpcLoop, StandsThirtySeconds) {
  static auto plan = std::make_unique<planner::MotionPlan>();
  plan->rate_hz = 50.0;
  plan->frame_count = 1501;  // 30 s
  const dynamics::ConfigVector q0 = kuavo::test::standing_configuration();
  for (int i = 0; i < plan->frame_count; ++i) plan->q[i] = q0, plan->foot_contact[i] = {true, true};
  ASSERT_EQ(planner::motion_plan_finish(*plan), nullptr);
  for (const sim::GroundParams* ground : {&sim::kFloor, &sim::kCarpet}) {
    sim::MotionRunConfig cfg;
    cfg.stack.planner = stack::PlannerKind::kMpc;
    cfg.run.ground = *ground;
    const sim::MotionSummary s = sim::run_motion(robot(), *plan, cfg);
    print(ground->name, s);
    ASSERT_TRUE(s.run.ok) << s.run.error;
    EXPECT_FALSE(s.run.fell) << ground->name;
    EXPECT_GE(s.run.sim_time_s, 30.0);
    EXPECT_LT(s.run.max_tilt_deg, 3.0) << ground->name;
    // Measured 0.010 m on the floor (0.049 m before the estimator had its acceleration-bias
    // state: the IMU's tilt error made the estimate drift and the robot followed it).
    EXPECT_LT(s.com_err_m_max, 0.03) << ground->name;
    EXPECT_LT(s.estimator_position_drift_m, 0.03) << ground->name;
    EXPECT_EQ(s.mpc_failures, 0u);
    EXPECT_EQ(s.wbc_not_ok_ticks, 0u);
  }
}

TEST(MpcLoop, StepsInPlaceOnCarpet) {
  static auto plan = std::make_unique<planner::MotionPlan>();
  static dynamics::Data data;
  const dynamics::ConfigVector q0 = kuavo::test::standing_configuration();
  planner::StepInPlaceConfig gait;
  gait.steps = 6;
  ASSERT_EQ(planner::make_step_in_place(robot(), q0, gait, *plan), nullptr);
  sim::MotionRunConfig cfg;
  cfg.stack.planner = stack::PlannerKind::kMpc;
  cfg.run.ground = sim::kCarpet;
  const sim::MotionSummary s = sim::run_motion(robot(), *plan, cfg);
  print("steps, carpet, MPC", s);
  ASSERT_TRUE(s.run.ok) << s.run.error;
  EXPECT_FALSE(s.run.fell);
  EXPECT_LT(s.tracking_rms_legs_rad, 0.03);
  EXPECT_EQ(s.mpc_failures, 0u);
  EXPECT_EQ(s.wbc_not_ok_ticks, 0u);
}

}  // namespace
}  // namespace kuavo::test
