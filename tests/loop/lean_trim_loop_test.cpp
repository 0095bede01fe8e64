// The lean trim (controllers/stack/lean_trim.h) closed on the Simbody plant: a robot standing
// in double support whose controller is wrong about where its CoM is, once through the IMU (a
// tilt error injected into ideal sensors) and once through the model (every link's CoM moved
// in the plant). Oracles: the injected tilt itself, and the simulator's truth (the plant's CoM
// over its sole corners against the controller's).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "sim/motion_loop.h"
#include "sim/perturbation.h"
#include "tests/support/test_robot.h"

namespace kuavo::test {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

sim::MotionRunConfig standing_config(bool trim) {
  sim::MotionRunConfig cfg;
  cfg.stack.planner = stack::PlannerKind::kMpc;
  cfg.stack.lean_trim.enabled = trim;
  cfg.stack.lean_trim.learn = stack::LeanTrimLearn::kAlways;  // standing: the trim of every quiet phase
  // The observer's loop itself: no dead band (lean_trim.h), so the trim can reach the truth.
  cfg.stack.lean_trim.residual_deadband_N = 0.0;
  cfg.ideal_sensors = true;
  cfg.run.ground = sim::kFloor;
  return cfg;
}

const planner::MotionPlan& standing_10s() {
  static const auto plan = standing_motion(50.0, 501);
  return *plan;
}

// Measured at the time of writing (roll 0.6°, pitch −0.8°, 11 s): the trim ends at (−0.56°,
// +0.75°); the base tilt error against the truth is 1.00° RMS off and 0.44° on (the first
// seconds converging), the CoM over the feet 14.2 mm off at the end and 1.0 mm on.
TEST(LeanTrimLoop, ATiltedImuIsTrimmedToTheTruth) {
  const Eigen::Vector2d tilt(0.6 * kDeg, -0.8 * kDeg);
  sim::MotionRunConfig off_cfg = standing_config(false), on_cfg = standing_config(true);
  off_cfg.imu_tilt_rad = on_cfg.imu_tilt_rad = tilt;
  const sim::MotionSummary off = sim::run_motion(s45_robot(), standing_10s(), off_cfg);
  const sim::MotionSummary on = sim::run_motion(s45_robot(), standing_10s(), on_cfg);
  std::printf("IMU tilt (0.6, -0.8) deg: trim (%.3f, %.3f) deg, tilt error RMS %.3f / %.3f deg, "
              "CoM over feet at the end %.4f / %.4f m (off / on), trim ticks %llu, saturated %llu\n",
              on.lean_trim_roll_deg, on.lean_trim_pitch_deg, off.estimator_tilt_err_deg_rms, on.estimator_tilt_err_deg_rms,
              off.com_over_feet_err_m_end, on.com_over_feet_err_m_end,
              static_cast<unsigned long long>(on.lean_trim_integrated_ticks),
              static_cast<unsigned long long>(on.lean_trim_saturated_ticks));
  ASSERT_TRUE(off.run.ok && on.run.ok);
  EXPECT_FALSE(off.run.fell);
  EXPECT_FALSE(on.run.fell);
  EXPECT_FALSE(off.lean_trim);
  EXPECT_TRUE(on.lean_trim);
  EXPECT_EQ(off.lean_trim_integrated_ticks, 0u);
  EXPECT_EQ(on.lean_trim_saturated_ticks, 0u);
  // The scenario has the error: the controller's CoM is the tilt's lever arm off.
  EXPECT_GT(off.com_over_feet_err_m_end, 0.008);
  // The trim undoes the injected tilt (the oracle), within 0.15° per axis.
  EXPECT_NEAR(on.lean_trim_roll_deg, -0.6, 0.15);
  EXPECT_NEAR(on.lean_trim_pitch_deg, 0.8, 0.15);
  EXPECT_LT(on.com_over_feet_err_m_end, 0.25 * off.com_over_feet_err_m_end);
}

// Every link's CoM 1.5 cm off in the plant in x and y (and z): the whole robot's 1.5 cm too,
// and the controller cannot see it in its state. Measured at the time of writing (11 s): the
// CoM over the feet 20.4 mm off without the trim and 11.1 mm with it, the trim (−0.49°,
// +0.40°); 20 s standing ends the same (10.9 mm): the residual has reached zero with about
// half of the offset left, unlike the tilt (where the plant is the model). Not explained yet;
// a guess is the joints' PD carrying the model's gravity error, which the WBC's forces that
// the residual reads do not contain.
TEST(LeanTrimLoop, AModelCoMErrorIsTrimmedOut) {
  sim::PerturbationSet set;
  set.name = "com";
  set.link_com_m = {0.015, 0.015};
  sim::MotionRunConfig off_cfg = standing_config(false), on_cfg = standing_config(true);
  off_cfg.perturbation = on_cfg.perturbation = sim::draw_perturbation(s45_robot(), set, 1);
  ASSERT_TRUE(off_cfg.perturbation.active);
  const sim::MotionSummary off = sim::run_motion(s45_robot(), standing_10s(), off_cfg);
  const sim::MotionSummary on = sim::run_motion(s45_robot(), standing_10s(), on_cfg);
  std::printf("link CoMs +1.5 cm: trim (%.3f, %.3f) deg, CoM over feet at the end %.4f / %.4f m (off / on)\n",
              on.lean_trim_roll_deg, on.lean_trim_pitch_deg, off.com_over_feet_err_m_end, on.com_over_feet_err_m_end);
  ASSERT_TRUE(off.run.ok && on.run.ok);
  EXPECT_FALSE(off.run.fell);
  EXPECT_FALSE(on.run.fell);
  EXPECT_GT(off.com_over_feet_err_m_end, 0.015);
  EXPECT_LT(on.com_over_feet_err_m_end, 0.65 * off.com_over_feet_err_m_end);
  // A CoM forward and to the left is trimmed as a lean: pitch forward (+), roll left (−).
  EXPECT_GT(on.lean_trim_pitch_deg, 0.2);
  EXPECT_LT(on.lean_trim_roll_deg, -0.2);
}

// kOpening on a motion that stands 2 s and then steps (the right foot up over 2.0–2.4 s): the
// trim learns the injected IMU tilt in the stand, at opening_time_constant_s, and holds it
// from the lift-off on. Oracle: the injected tilt; the opening's length bounds the ticks.
TEST(LeanTrimLoop, TheOpeningLearnsATiltedImuBeforeTheFirstStepAndHoldsIt) {
  static const auto stepping = stepping_motion();
  const Eigen::Vector2d tilt(0.6 * kDeg, -0.8 * kDeg);
  sim::MotionRunConfig cfg = standing_config(true);
  cfg.imu_tilt_rad = tilt;
  cfg.stack.lean_trim.learn = stack::LeanTrimLearn::kOpening;
  const sim::MotionSummary on = sim::run_motion(s45_robot(), *stepping, cfg);
  std::printf("opening trim, IMU tilt (0.6, -0.8) deg: trim (%.3f, %.3f) deg, %llu ticks learned\n",
              on.lean_trim_roll_deg, on.lean_trim_pitch_deg, static_cast<unsigned long long>(on.lean_trim_integrated_ticks));
  ASSERT_TRUE(on.run.ok);
  EXPECT_FALSE(on.run.fell);
  EXPECT_NEAR(on.lean_trim_roll_deg, -0.6, 0.15);
  EXPECT_NEAR(on.lean_trim_pitch_deg, 0.8, 0.15);
  EXPECT_GT(on.lean_trim_integrated_ticks, 0u);
  EXPECT_LT(on.lean_trim_integrated_ticks, 2.0 / 0.002);  // none after the lift-off at 2.0 s
}

}  // namespace
}  // namespace kuavo::test
