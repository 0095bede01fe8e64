// The online stack (estimator, planner, WBC) following motions on the Simbody plant.
// Oracles: the simulator's ground truth (falls, contact loads, CoM), the plan itself
// (contact schedule), and the byte stream of the log (determinism).
#include "sim/motion_loop.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "tests/support/test_robot.h"
#include "controllers/planner/balance_filter.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/standing/standing_controller.h"

namespace kuavo::test {
namespace {

const model::Model& robot() { return kuavo::test::s45_robot(); }

planner::MotionPlan& step_plan(int steps) {
  static auto plan = std::make_unique<planner::MotionPlan>();
  static auto data = std::make_unique<dynamics::Data>();
  const dynamics::ConfigVector q0 = kuavo::test::standing_configuration();
  planner::StepInPlaceConfig cfg;
  cfg.steps = steps;
  EXPECT_EQ(planner::make_step_in_place(robot(), q0, cfg, *plan), nullptr);
  return *plan;
}

// Lift-offs per foot seen in the simulator: the foot's load falls below 5 N after
// having carried over 100 N for 50 ms at least (the trace's samples are stride ticks
// apart; a shorter touch is the bump of a foot about to lift, not a stance).
std::array<int, 2> lift_offs(const sim::MotionTrace& trace) {
  std::array<int, 2> count{};
  std::array<bool, 2> loaded{true, true};
  std::array<std::size_t, 2> loaded_at{0, 0};
  const double sample_s = trace.stride * sim::kControlPeriod_s;
  for (std::size_t i = 0; i < trace.foot_force_z_N.size(); ++i) {
    const auto& f = trace.foot_force_z_N[i];
    for (int foot = 0; foot < 2; ++foot) {
      if (loaded[foot] && f[foot] < 5.0) {
        count[foot] += (i - loaded_at[foot]) * sample_s >= 0.05 - 1e-9;
        loaded[foot] = false;
      }
      if (!loaded[foot] && f[foot] > 100.0) loaded[foot] = true, loaded_at[foot] = i;
    }
  }
  return count;
}

void print(const char* name, const sim::MotionSummary& s) {
  std::printf("%s: fell %d at %.2f s, legs %.4f rad, arms %.4f rad, CoM err %.3f m, ZMP margin %.4f m (at the edge %.3f s), tilt %.2f deg, est v rms %.4f m/s, drift %.3f m, not-ok ticks %llu\n",
              name, s.run.fell, s.run.fell_at_s, s.tracking_rms_legs_rad, s.tracking_rms_arms_rad, s.com_err_m_max,
              s.zmp_margin_m_min, s.zmp_at_edge_s, s.run.max_tilt_deg, s.estimator_velocity_rms_m_s, s.estimator_position_drift_m,
              static_cast<unsigned long long>(s.wbc_not_ok_ticks));
}

TEST(MotionLoop, StepsInPlaceTwentyTimesOnTheFloorWithTheEstimator) {
  const planner::MotionPlan& plan = step_plan(20);
  sim::MotionRunConfig cfg;
  sim::MotionTrace trace;
  const sim::MotionSummary s = sim::run_motion(robot(), plan, cfg, &trace);
  print("step in place, floor", s);
  ASSERT_TRUE(s.run.ok) << s.run.error;
  EXPECT_FALSE(s.run.fell);
  const auto lifts = lift_offs(trace);
  EXPECT_EQ(lifts[0], 10);  // the plan's 20 swings, alternating, really left the ground
  EXPECT_EQ(lifts[1], 10);
  // The summary's own count of stepping phases: the plan's 20.
  EXPECT_EQ(s.steps, 20);
  // Stepping in place: the CoM sways from foot to foot; the planned sway's path, not zero,
  // and the danced one within a factor of 2 of it.
  EXPECT_GT(s.com_path_plan_m, 0.1);
  EXPECT_GT(s.com_path_m, 0.5 * s.com_path_plan_m);
  EXPECT_LT(s.com_path_m, 2.0 * s.com_path_plan_m);
  RecordProperty("com_path_m", std::to_string(s.com_path_m));
  RecordProperty("com_path_plan_m", std::to_string(s.com_path_plan_m));
  EXPECT_LT(s.run.max_tilt_deg, 5.0);
  EXPECT_LT(s.zmp_at_edge_s, 0.5);  // a foot may roll on an edge briefly at touchdown, not for long
  EXPECT_LT(s.tracking_rms_legs_rad, 0.03);
  EXPECT_LT(s.estimator_velocity_rms_m_s, 0.05);
  EXPECT_EQ(s.wbc_not_ok_ticks, 0u);
  EXPECT_EQ(s.plans_skipped, 0u);
}

TEST(MotionLoop, StepsInPlaceOnCarpet) {
  const planner::MotionPlan& plan = step_plan(6);
  sim::MotionRunConfig cfg;
  cfg.run.ground = sim::kCarpet;
  sim::MotionTrace trace;
  const sim::MotionSummary s = sim::run_motion(robot(), plan, cfg, &trace);
  print("step in place, carpet", s);
  ASSERT_TRUE(s.run.ok) << s.run.error;
  EXPECT_FALSE(s.run.fell);
  const auto lifts = lift_offs(trace);
  EXPECT_EQ(lifts[0], 3);
  EXPECT_EQ(lifts[1], 3);
  EXPECT_EQ(s.steps, 6);
  EXPECT_GT(s.run.max_foot_sink_m, 0.01);  // it is the soft ground
}

TEST(MotionLoop, SameSeedSameLogOtherSeedDiffers) {
  const planner::MotionPlan& plan = step_plan(2);
  sim::MotionRunConfig cfg;
  cfg.run.duration_s = 2.0;
  const std::string a = sim::run_motion(robot(), plan, cfg).run.log_sha256;
  const std::string b = sim::run_motion(robot(), plan, cfg).run.log_sha256;
  cfg.run.seed = 2;
  const std::string c = sim::run_motion(robot(), plan, cfg).run.log_sha256;
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(a.size(), 64u);
}

TEST(MotionLoop, SummaryJsonHasTheIssueKeys) {
  sim::MotionSummary s;
  const std::string json = sim::motion_summary_json(s);
  for (const char* key : {"\"fell\"", "\"sim_time_s\"", "\"real_time_factor\"", "\"max_tilt_deg\"", "\"log_sha256\"",
                          "\"tracking_rms_rad\": {\"legs\"", "\"arms\"", "\"com_err_m_max\"", "\"com_path_m\"", "\"steps\"", "\"zmp_margin_m_min\"",
                          "\"mpc_ms\": {\"p50\"", "\"wbc_us\": {\"p50\"", "\"p99\"", "\"max\"", "\"deadline_misses\""}) {
    EXPECT_NE(json.find(key), std::string::npos) << key;
  }
}

TEST(MotionLoop, PercentilesOfAKnownSample) {
  std::vector<double> v;
  for (int i = 100; i >= 0; --i) v.push_back(i);  // 0..100, shuffled order irrelevant
  const sim::Percentiles p = sim::percentiles(v);
  EXPECT_EQ(p.p50, 50.0);
  EXPECT_EQ(p.p99, 99.0);
  EXPECT_EQ(p.max, 100.0);
}

}  // namespace
}  // namespace kuavo::test
