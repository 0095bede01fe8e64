// The plan anchor on a standing motion that lifts the right foot over [2.0, 2.4) s. The
// measured robot is the motion's pose translated by d (or the plan's right foot is moved
// against the standing robot), so measured − planned is known in closed form per foot.
// Oracles: the measured sole corners by forward kinematics (dynamics::frame_position, not the
// measured knot handed in), the unshifted window from motion_plan_window_rt, and the ramp's and the
// choice's arithmetic.
#include "controllers/planner/plan_anchor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "controllers/planner/motion_plan.h"
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
constexpr int kRight = 1;
constexpr int kCorners = kNumPoints / 2;


dynamics::ConfigVector translated(const Eigen::Vector2d& d) {
  dynamics::ConfigVector q = standing_configuration();
  q.head<2>() += d;
  return q;
}

struct Fixture {
  std::unique_ptr<MotionPlan> motion = stepping_motion();
  std::unique_ptr<PlanAnchorState> state = std::make_unique<PlanAnchorState>();
  std::unique_ptr<PlanWindow> window = std::make_unique<PlanWindow>();
  std::unique_ptr<PlanWindow> plain = std::make_unique<PlanWindow>();
  dynamics::Data data;
  PlanAnchorConfig config;
  hal::TimeNs t_ns = 500 * kMs;
  Eigen::Vector2d right_foot_planned_shift = Eigen::Vector2d::Zero();
  Fixture() {
    config.enabled = true;
    config.home_share = 0.0;  // the whole error (WithHoming… takes a share)
    plan_anchor_reset(*state);
  }
  // The motion's window at t_ns (the plan's right foot moved by right_foot_planned_shift),
  // anchored to the measured q; t_ns advances by a period.
  void call(const dynamics::ConfigVector& q) {
    motion_plan_window_rt(s45_robot(), data, *motion, t_ns, kDt, kKnots, *plain);
    for (int k = 0; k < plain->count; ++k) {
      for (int i = 0; i < kCorners; ++i) {
        plain->knots[k].point_position_m.segment<2>(3 * (kRight * kCorners + i)) += right_foot_planned_shift;
      }
    }
    *window = *plain;
    plan_anchor_rt(config, *state, test::measured_knot(q, dynamics::VelocityVector::Zero(), t_ns), t_ns, *window);
    t_ns += kPeriod;
  }
  // The window is the plain one with base, CoM and corners moved by d, the rest untouched.
  void expect_shifted_by(const Eigen::Vector2d& d, double tol) {
    ASSERT_EQ(window->count, kKnots);
    for (int k = 0; k < kKnots; ++k) {
      const PlanKnot &a = window->knots[k], &b = plain->knots[k];
      ASSERT_EQ(a.stamp_ns, b.stamp_ns);
      ASSERT_EQ(a.in_contact, b.in_contact);
      ASSERT_EQ(a.v, b.v);
      ASSERT_EQ(a.q.tail<dynamics::kNq - 2>(), b.q.tail<dynamics::kNq - 2>());
      ASSERT_NEAR((a.q.head<2>() - b.q.head<2>() - d).norm(), 0.0, tol) << k;
      ASSERT_NEAR((a.com_position_m.head<2>() - b.com_position_m.head<2>() - d).norm(), 0.0, tol) << k;
      ASSERT_EQ(a.com_position_m.z(), b.com_position_m.z());
      for (int c = 0; c < kNumPoints; ++c) {
        ASSERT_NEAR((a.point_position_m.segment<2>(3 * c) - b.point_position_m.segment<2>(3 * c) - d).norm(), 0.0, tol);
        ASSERT_EQ(a.point_position_m[3 * c + 2], b.point_position_m[3 * c + 2]);
      }
    }
  }
};

TEST(PlanAnchor, ATranslatedRobotGetsThePlanMovedOntoItsFeet) {
  Fixture f;
  const Eigen::Vector2d d(0.03, -0.02);
  const dynamics::ConfigVector q = translated(d);
  for (int i = 0; i < 30; ++i) f.call(q);
  f.expect_shifted_by(d, 1e-12);
  EXPECT_EQ(f.state->reanchors, 1u);
  EXPECT_EQ(f.state->refused, 0u);
  // Knot 0's corners are where the measured robot's soles are (forward kinematics).
  dynamics::compute_all_terms(s45_robot(), f.data, q, dynamics::VelocityVector::Zero());
  for (int c = 0; c < kNumPoints; ++c) {
    const Vec3 p = dynamics::frame_position(s45_robot(), f.data, c);
    EXPECT_NEAR((f.window->knots[0].point_position_m.segment<2>(3 * c) - p.head<2>()).norm(), 0.0, 1e-9) << c;
  }
}

// A reset (a new dance, a restart after a fault) forgets the offset: the next window is the
// motion's until the foot has settled again, then the ramp starts from zero.
TEST(PlanAnchor, AResetForgetsTheOffset) {
  Fixture f;
  const Eigen::Vector2d d(0.03, 0.0);
  const dynamics::ConfigVector q = translated(d);
  for (int i = 0; i < 30; ++i) f.call(q);
  f.expect_shifted_by(d, 1e-12);
  plan_anchor_reset(*f.state);
  EXPECT_EQ(f.state->reanchors, 0u);
  EXPECT_EQ(f.state->offset_max_m, 0.0);
  for (int i = 0; i < 3; ++i) {
    f.call(q);
    f.expect_shifted_by(Eigen::Vector2d::Zero(), 0.0);
  }
  f.call(q);
  f.expect_shifted_by(Eigen::Vector2d::Zero(), 0.0);  // the ramp's first call: share 0
  f.call(q);
  f.expect_shifted_by(0.02 / f.config.ramp_s * d, 1e-12);
}

// A non-finite measured state gives no target: the offset in force stays, nothing counted
// (an infinite base would otherwise be refused as beyond the bound, and counted).
TEST(PlanAnchor, ANonFiniteStateTakesNoTarget) {
  for (const double x : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    Fixture f;
    const Eigen::Vector2d d(0.0, -0.03);
    for (int i = 0; i < 30; ++i) f.call(translated(d));
    ASSERT_EQ(f.state->reanchors, 1u);
    dynamics::ConfigVector bad = translated(d);
    bad[0] = x;
    for (int i = 0; i < 5; ++i) {
      f.call(bad);
      f.expect_shifted_by(d, 1e-12);
    }
    EXPECT_EQ(f.state->reanchors, 1u) << x;
    EXPECT_EQ(f.state->refused, 0u) << x;
    EXPECT_TRUE(f.state->offset.allFinite()) << x;
  }
}

TEST(PlanAnchor, TheOffsetWaitsForTheFootToSettleThenRampsLinearly) {
  Fixture f;
  const Eigen::Vector2d d(0.0, 0.04);
  const dynamics::ConfigVector q = translated(d);
  // Both feet are planned down from the first call: down for settle_s = 0.06 s at call 3.
  for (int i = 0; i < 3; ++i) {
    f.call(q);
    f.expect_shifted_by(Eigen::Vector2d::Zero(), 0.0);
  }
  EXPECT_EQ(f.state->reanchors, 0u);
  for (int k = 0; k <= 12; ++k) {
    f.call(q);
    const double share = std::min(1.0, k * 0.02 / f.config.ramp_s);
    f.expect_shifted_by(share * d, 1e-12);
  }
  EXPECT_EQ(f.state->reanchors, 1u);
  EXPECT_NEAR(f.state->offset_max_m, 0.04, 1e-12);
}

TEST(PlanAnchor, ItAnchorsOnTheFootOfTheNextSingleSupport) {
  // The plan has the right foot 4 cm to the left of where the standing robot has it.
  const Eigen::Vector2d a(0.0, 0.04);
  {
    // From 1.5 s the window reaches the left foot's single support at 2.0 s: the left foot,
    // where the plan has it, is the anchor; no offset (both feet's mean would be −a/2).
    Fixture f;
    f.right_foot_planned_shift = a;
    f.t_ns = 1500 * kMs;
    for (int i = 0; i < 20; ++i) {
      f.call(standing_configuration());
      f.expect_shifted_by(Eigen::Vector2d::Zero(), 0.0);
    }
    EXPECT_EQ(f.state->reanchors, 0u);
  }
  {
    // From 2.6 s no single support is left: both feet, −a/2.
    Fixture f;
    f.right_foot_planned_shift = a;
    f.t_ns = 2600 * kMs;
    for (int i = 0; i < 20; ++i) f.call(standing_configuration());
    f.expect_shifted_by(-0.5 * a, 1e-12);
  }
  {
    // Flight of the right foot at 2.1 s: the left foot stands; the right one's error is
    // not used while it is up (no ramp: the offset at once).
    Fixture f;
    f.config.ramp_s = 0.0;
    f.right_foot_planned_shift = a;
    f.t_ns = 2100 * kMs;
    for (int i = 0; i < 10; ++i) f.call(translated(Eigen::Vector2d(0.01, 0.0)));
    f.expect_shifted_by(Eigen::Vector2d(0.01, 0.0), 1e-12);
  }
}

TEST(PlanAnchor, WithHomingItTakesItsShareOfTheError) {
  Fixture f;
  f.config.home_share = 0.2;
  const Eigen::Vector2d d(0.02, 0.05);
  for (int i = 0; i < 20; ++i) f.call(translated(d));
  f.expect_shifted_by(0.8 * d, 1e-12);
}

TEST(PlanAnchor, ATargetMovingLessThanTheDeadbandIsNotTakenAndARampRestartsFromWhereItIs) {
  Fixture f;
  const Eigen::Vector2d d(0.02, 0.0);
  for (int i = 0; i < 20; ++i) f.call(translated(d));
  f.expect_shifted_by(d, 1e-12);
  // 4 mm more: inside the 5 mm deadband, the offset stays.
  for (int i = 0; i < 5; ++i) f.call(translated(d + Eigen::Vector2d(0.004, 0.0)));
  f.expect_shifted_by(d, 1e-12);
  EXPECT_EQ(f.state->reanchors, 1u);
  // 3 cm more: a new ramp from d; halfway (0.1 s) it is midway, then a new target mid-ramp
  // starts its ramp from the offset reached, not from d or the old target.
  const Eigen::Vector2d e = d + Eigen::Vector2d(0.03, 0.0);
  for (int i = 0; i < 6; ++i) f.call(translated(e));  // re-anchored on the first, 5 ramp steps
  f.expect_shifted_by(0.5 * (d + e), 1e-12);
  const Eigen::Vector2d g(0.0, 0.03);
  f.call(translated(g));  // the new target; ramp share 0 on this call
  f.expect_shifted_by(0.5 * (d + e), 1e-12);
  f.call(translated(g));
  f.expect_shifted_by(0.5 * (d + e) + 0.1 * (g - 0.5 * (d + e)), 1e-12);
  EXPECT_EQ(f.state->reanchors, 3u);
}

TEST(PlanAnchor, ATargetBeyondTheBoundIsRefusedAndCounted) {
  Fixture f;
  const dynamics::ConfigVector q = translated(Eigen::Vector2d(0.3, 0.0));
  for (int i = 0; i < 20; ++i) {
    f.call(q);
    f.expect_shifted_by(Eigen::Vector2d::Zero(), 0.0);
  }
  EXPECT_EQ(f.state->reanchors, 0u);
  EXPECT_EQ(f.state->refused, 20u - 3u);  // every call once the feet had settled
}

TEST(PlanAnchor, DisabledItLeavesTheWindowAndEnabledItDoesNotAllocate) {
  Fixture f;
  f.config.enabled = false;
  const dynamics::ConfigVector q = translated(Eigen::Vector2d(0.02, 0.02));
  for (int i = 0; i < 20; ++i) {
    f.call(q);
    f.expect_shifted_by(Eigen::Vector2d::Zero(), 0.0);
  }
  f.config.enabled = true;
  f.call(q);
  test::AllocTrap trap;
  for (int i = 0; i < 50; ++i) {
    const hal::TimeNs t = f.t_ns + i * kPeriod;
    plan_anchor_rt(f.config, *f.state, test::measured_knot(q, dynamics::VelocityVector::Zero(), t), t, *f.window);
  }
  EXPECT_EQ(trap.count(), 0u);
}

TEST(PlanAnchor, ValidateNamesWhatIsWrong) {
  PlanAnchorConfig c;
  EXPECT_EQ(plan_anchor_validate(c), nullptr);
  c.ramp_s = -1.0;
  EXPECT_NE(plan_anchor_validate(c), nullptr);
  c = PlanAnchorConfig{};
  c.max_offset_m = 0.0;
  EXPECT_NE(plan_anchor_validate(c), nullptr);
  c = PlanAnchorConfig{};
  c.home_share = 0.6;
  EXPECT_NE(plan_anchor_validate(c), nullptr);
  c = PlanAnchorConfig{};
  c.settle_s = std::nan("");
  EXPECT_NE(plan_anchor_validate(c), nullptr);
}

}  // namespace
}  // namespace kuavo::planner
