// The lift-off hold on a standing motion that lifts the right foot at 2.0 s. The measured
// robot stands in the motion's pose and translates sideways, so its capture point is
// ξ = c + ċ/ω (closed form, ω from the CoM height over the soles by forward kinematics):
// moving right by 0.05·ω m/s puts ξ 5 cm farther from the left (stance) sole than the
// motion's own ξ, past the 3 cm tolerance; moving left brings it closer. Oracles: the window
// against motion_plan_window_rt sampled at t − lag (an independent call), the lag against
// the call period and the config's limits by arithmetic.
#include "controllers/planner/liftoff_hold.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "tests/support/alloc_trap.h"
#include "tests/support/test_robot.h"

namespace kuavo::planner {
namespace {

using kuavo::test::s45_robot;
using kuavo::test::standing_configuration;
using kuavo::test::stepping_motion;

constexpr double kDt = 0.02;
constexpr int kKnots = 61;
constexpr hal::TimeNs kMs = 1'000'000;
constexpr hal::TimeNs kPeriod = 20 * kMs;
constexpr int kLeft = 0, kRight = 1;


double omega_standing() {
  static dynamics::Data data;
  const dynamics::ConfigVector q = standing_configuration();
  dynamics::compute_all_terms(s45_robot(), data, q, dynamics::VelocityVector::Zero());
  double sole_z = 0.0;
  for (int c = 0; c < kNumPoints; ++c) sole_z += dynamics::frame_position(s45_robot(), data, c).z() / kNumPoints;
  return std::sqrt(model::kGravity_m_s2 / (data.com_m.z() - sole_z));
}

// The whole robot translating sideways at vy (world = base axes for the upright base).
dynamics::VelocityVector sideways(double vy) {
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[1] = vy;
  return v;
}

bool foot_down(const PlanKnot& k, int foot) {
  for (int i = 0; i < kNumPoints / 2; ++i) {
    if (!k.in_contact[foot * kNumPoints / 2 + i]) return false;
  }
  return true;
}

struct Fixture {
  std::unique_ptr<MotionPlan> motion = stepping_motion();
  std::unique_ptr<LiftoffHoldState> state = std::make_unique<LiftoffHoldState>();
  std::unique_ptr<PlanWindow> window = std::make_unique<PlanWindow>();
  std::unique_ptr<PlanWindow> expected = std::make_unique<PlanWindow>();
  dynamics::Data data;
  LiftoffHoldConfig config;
  hal::TimeNs t_ns = 1500 * kMs;
  Fixture() {
    config.enabled = true;
    liftoff_hold_reset(*state);
  }
  // One planner call at t_ns, then t_ns advances by a period.
  void call(double vy) {
    liftoff_hold_window_rt(s45_robot(), config, *state, *motion,
                           test::measured_knot(standing_configuration(), sideways(vy), t_ns), t_ns, kDt, kKnots, true,
                           *window);
    t_ns += kPeriod;
  }
  // The window is the motion at (stamp − lag), stamped on the wall clock.
  void expect_window_is_motion_lagged_by(hal::TimeNs lag) {
    const hal::TimeNs t = t_ns - kPeriod;
    motion_plan_window_rt(s45_robot(), data, *motion, t - lag, kDt, kKnots, *expected);
    ASSERT_EQ(window->count, kKnots);
    for (int k = 0; k < kKnots; ++k) {
      const PlanKnot &a = window->knots[k], &b = expected->knots[k];
      ASSERT_EQ(a.stamp_ns, t + static_cast<hal::TimeNs>(std::llround(k * kDt * 1e9))) << k;
      ASSERT_EQ(a.q, b.q) << k;
      ASSERT_EQ(a.in_contact, b.in_contact) << k;
      ASSERT_EQ(a.point_position_m, b.point_position_m) << k;
    }
  }
};

TEST(LiftoffHold, TheWeightWhereTheMotionHasItHoldsNothing) {
  Fixture f;
  for (int i = 0; i < 100; ++i) {
    f.call(0.0);
    ASSERT_EQ(f.state->lag_ns, 0) << i;
    f.expect_window_is_motion_lagged_by(0);
  }
  EXPECT_EQ(f.state->holds, 0u);
  // At the lift-off the measured ξ is the motion's: excess 0 (to rounding).
  EXPECT_NEAR(f.state->last_excess_m, 0.0, 1e-9);
}

TEST(LiftoffHold, ACapturePointAwayFromTheStanceFootHoldsTheLiftOffUpToItsLimit) {
  Fixture f;
  const double vy = -0.05 * omega_standing();  // ξ 5 cm to the right of the motion's
  int held = 0;
  hal::TimeNs first_hold = -1;
  {
    kuavo::test::AllocTrap trap;
    for (int i = 0; i < 60; ++i) {
      const hal::TimeNs t = f.t_ns;
      const hal::TimeNs before = f.state->lag_ns;
      f.call(vy);
      if (f.state->lag_ns > before) {
        ++held;
        if (first_hold < 0) first_hold = t;
      }
    }
    EXPECT_EQ(trap.count(), 0);
  }
  // The first hold: the lift-off (2.0 s) within look_ahead_s (0.04 s) of the motion's clock.
  EXPECT_EQ(first_hold, 1960 * kMs);
  EXPECT_NEAR(f.state->last_excess_m, 0.05, 1e-5);  // the inner edge is not exactly along x
  // Held max_hold_s / period = 15 calls, then let go (the gate still closed): counted.
  EXPECT_EQ(held, 15);
  EXPECT_EQ(f.state->lag_ns, 300 * kMs);
  EXPECT_EQ(f.state->holds, 1u);
  EXPECT_EQ(f.state->released, 1u);
  EXPECT_EQ(f.state->held_calls, 15u);
  f.expect_window_is_motion_lagged_by(300 * kMs);
}

// ξ 25 cm to the right: beyond the right sole's outer edge (the soles' hull ends ~16 cm out),
// as after a push. Lifting the right foot to step is what catches it: no hold.
TEST(LiftoffHold, ACapturePointBeyondBothFeetLetsTheStepGo) {
  Fixture f;
  const double vy = -0.25 * omega_standing();
  for (int i = 0; i < 60; ++i) f.call(vy);
  EXPECT_GT(f.state->last_excess_m, 0.2);
  EXPECT_EQ(f.state->holds, 0u);
  EXPECT_EQ(f.state->lag_ns, 0);
}

TEST(LiftoffHold, TheFootLiftsOnceTheWeightHasMovedAndTheDanceCatchesUp) {
  Fixture f;
  const double bad = -0.05 * omega_standing();
  while (f.t_ns < 2000 * kMs) f.call(bad);  // holds from 1.96 s: 1.96, 1.98 -> lag 40 ms
  ASSERT_EQ(f.state->lag_ns, 40 * kMs);
  // The weight moves (ξ 2 cm towards the left foot): the foot goes, the lag stays.
  f.call(0.02 * omega_standing());
  EXPECT_EQ(f.state->lag_ns, 40 * kMs);
  EXPECT_EQ(f.state->released, 0u);
  EXPECT_LT(f.state->last_excess_m, -0.019);
  f.expect_window_is_motion_lagged_by(40 * kMs);
  // The right foot is up in the window exactly over the motion's swing, 40 ms late.
  for (int k = 0; k < kKnots; ++k) {
    const hal::TimeNs motion_t = f.window->knots[k].stamp_ns - 40 * kMs;
    const bool up = motion_t >= 2000 * kMs && motion_t < 2400 * kMs;
    EXPECT_EQ(foot_down(f.window->knots[k], kRight), !up) << k;
    EXPECT_TRUE(foot_down(f.window->knots[k], kLeft)) << k;
  }
  // Through the swing nothing changes; once the motion keeps both feet down for
  // catch_up_quiet_s (from its 2.4 s touchdown on) the lag shrinks by rate × period a call.
  hal::TimeNs lag = f.state->lag_ns;
  while (f.state->lag_ns > 0) {
    const hal::TimeNs t = f.t_ns;
    f.call(0.0);
    if (f.state->lag_ns < lag) {
      EXPECT_GE(t - lag, 2400 * kMs) << "caught up before the touchdown";
      EXPECT_EQ(lag - f.state->lag_ns, std::min<hal::TimeNs>(lag, 5 * kMs));  // 0.25 × 20 ms
    } else {
      EXPECT_EQ(f.state->lag_ns, lag);
    }
    lag = f.state->lag_ns;
    ASSERT_LT(f.t_ns, 4000 * kMs);
  }
  EXPECT_EQ(f.state->lag_max_ns, 40 * kMs);
  EXPECT_EQ(f.state->holds, 1u);
}

TEST(LiftoffHold, DisabledOrGatedOffItIsTheMotionsWindow) {
  for (const bool enabled : {false, true}) {
    Fixture f;
    f.config.enabled = enabled;
    for (int i = 0; i < 60; ++i) {
      liftoff_hold_window_rt(s45_robot(), f.config, *f.state, *f.motion,
                             test::measured_knot(standing_configuration(), sideways(-0.1 * omega_standing()), f.t_ns),
                             f.t_ns, kDt, kKnots, /*gate=*/false, *f.window);
      f.t_ns += kPeriod;
      f.expect_window_is_motion_lagged_by(0);
    }
    EXPECT_EQ(f.state->holds, 0u);
  }
}

TEST(LiftoffHold, ValidateNamesWhatIsWrong) {
  LiftoffHoldConfig c;
  EXPECT_EQ(liftoff_hold_validate(c), nullptr);
  c.max_hold_s = 2.0;
  EXPECT_NE(liftoff_hold_validate(c), nullptr);
  c = LiftoffHoldConfig{};
  c.tolerance_m = std::nan("");
  EXPECT_NE(liftoff_hold_validate(c), nullptr);
  c = LiftoffHoldConfig{};
  c.catch_up_rate = -0.1;
  EXPECT_NE(liftoff_hold_validate(c), nullptr);
}

}  // namespace
}  // namespace kuavo::planner
