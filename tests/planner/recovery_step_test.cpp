// The recovery step on a standing robot whose measured CoM velocity puts its capture point
// outside the feet. Oracles: the closed-form capture point of the linear inverted pendulum
// (ξ = c + ċ/ω, ξ(T) = p + (ξ − p)e^{ωT}), the sole corners by forward kinematics of the
// rewritten knots (not the knots' own corner fields), and finite differences of those
// corners for their velocities.
#include "controllers/planner/recovery_step.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>

#include "controllers/planner/support_polygon.h"
#include "tests/support/alloc_trap.h"
#include "tests/support/test_robot.h"

namespace kuavo::planner {
namespace {

using kuavo::test::s45_robot;
using kuavo::test::standing_configuration;
using Vec2 = Eigen::Vector2d;

constexpr double kDt = 0.02;
constexpr int kKnots = 61;  // the MPC's 1.2 s horizon plus its terminal knot
constexpr hal::TimeNs kMs = 1'000'000;

// Standing still for 6 s at 100 Hz, both feet down, except where the test lifts one.
std::unique_ptr<MotionPlan> standing_motion() {
  auto m = std::make_unique<MotionPlan>();
  m->rate_hz = 100.0;
  m->frame_count = 600;
  for (int i = 0; i < m->frame_count; ++i) m->q[i] = standing_configuration(), m->foot_contact[i] = {true, true};
  EXPECT_EQ(motion_plan_finish(*m), nullptr);
  return m;
}

void lift_in_motion(MotionPlan& m, int foot, double from_s, double to_s) {
  for (int i = static_cast<int>(std::lround(from_s * 100.0)); i < static_cast<int>(std::lround(to_s * 100.0)); ++i) {
    m.foot_contact[i][foot] = false;
  }
}

struct Standing {
  std::array<Vec3, kNumPoints> corner;  // by forward kinematics
  Vec3 com;
  double omega;
  double heel_x = 1e9;    // the soles' rear edge
  double outer_y = -1e9;  // the left sole's outer edge
  // The whole robot's velocity that puts ξ = c + ċ/ω at x = xi_x (on the CoM's line along x).
  Vec2 towards(double xi_x) const { return Vec2((xi_x - com.x()) * omega, 0.0); }
  // ... `behind` metres behind the heels.
  Vec2 backwards(double behind) const { return towards(heel_x - behind); }
};

Standing standing_geometry() {
  static dynamics::Data data;
  const dynamics::ConfigVector q = standing_configuration();
  dynamics::compute_all_terms(s45_robot(), data, q, dynamics::VelocityVector::Zero());
  Standing s;
  double sole_z = 0.0;
  for (int c = 0; c < kNumPoints; ++c) {
    s.corner[c] = dynamics::frame_position(s45_robot(), data, c);
    sole_z += s.corner[c].z() / kNumPoints;
  }
  s.com = data.com_m;
  s.omega = std::sqrt(model::kGravity_m_s2 / (s.com.z() - sole_z));
  for (const Vec3& c : s.corner) s.heel_x = std::min(s.heel_x, c.x()), s.outer_y = std::max(s.outer_y, c.y());
  return s;
}

// The whole robot moving at `velocity` (world, horizontal), joints still: ċ = velocity.
dynamics::VelocityVector translating(const Vec2& velocity) {
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v.head<2>() = velocity;  // base axes = world axes for the upright standing base
  return v;
}

struct Fixture {
  std::unique_ptr<MotionPlan> motion = standing_motion();
  std::unique_ptr<RecoveryStepState> state = std::make_unique<RecoveryStepState>();
  std::unique_ptr<PlanWindow> window = std::make_unique<PlanWindow>();
  std::unique_ptr<PlanWindow> untouched = std::make_unique<PlanWindow>();
  dynamics::Data data;
  RecoveryStepConfig config;
  Fixture() {
    config.settle_s = 0.0;
    recovery_step_reset(*state);
  }
  // With the trigger's holdable soles at this pitch (0: the soles' corners).
  explicit Fixture(double ankle_pitch_capacity_Nm) : Fixture() {
    config.ankle_pitch_capacity_Nm = ankle_pitch_capacity_Nm;
  }
  // Applied to each sampled window before the call (empty: the motion's window as sampled).
  std::function<void(PlanWindow&)> shape_plan;
  // One planner call at t (s) with the robot standing and moving at `velocity`.
  void call(double t, const Vec2& velocity, const Vec2& plan_offset = Vec2::Zero()) {
    const hal::TimeNs t_ns = static_cast<hal::TimeNs>(std::llround(t * 1e9));
    motion_plan_window_rt(s45_robot(), data, *motion, t_ns, kDt, kKnots, *window);
    if (shape_plan) shape_plan(*window);
    *untouched = *window;
    recovery_step_rt(s45_robot(), config, *state, *motion,
                     kuavo::test::measured_knot(standing_configuration(), translating(velocity), t_ns), *window, 0,
                     plan_offset);
  }
  bool window_unchanged() const {
    for (int k = 0; k < kKnots; ++k) {
      const PlanKnot &a = window->knots[k], &b = untouched->knots[k];
      if (a.q != b.q || a.v != b.v || a.in_contact != b.in_contact || a.point_position_m != b.point_position_m) return false;
    }
    return true;
  }
};

// Sole corners of a knot by forward kinematics of its q.
std::array<Vec3, kNumPoints> corners_of(const PlanKnot& knot) {
  static dynamics::Data data;
  dynamics::forward_kinematics(s45_robot(), data, knot.q);
  std::array<Vec3, kNumPoints> out;
  for (int c = 0; c < kNumPoints; ++c) out[c] = dynamics::frame_position(s45_robot(), data, c);
  return out;
}

// ξ's signed margin at touchdown inside the support after a step of foot `swing` (closed form:
// the centre of pressure at the standing stance sole's point nearest ξ for t_s, then the stance
// sole and the swing sole where forward kinematics of `landed_knot` puts it).
double touchdown_margin(const Standing& s, const PlanKnot& landed_knot, int swing, const Vec2& xi, double t_s) {
  const int stance = 1 - swing;
  const auto landed = corners_of(landed_knot);
  std::array<Vec2, kNumPoints> after;
  std::array<Vec2, kCornersPerFoot> stance_sole;
  for (int i = 0; i < kCornersPerFoot; ++i) {
    after[stance * kCornersPerFoot + i] = stance_sole[i] = s.corner[stance * kCornersPerFoot + i].head<2>();
    after[swing * kCornersPerFoot + i] = landed[swing * kCornersPerFoot + i].head<2>();
  }
  const Vec2 p = project_into(convex_hull<kCornersPerFoot>(stance_sole, kCornersPerFoot), xi, 0.0);
  const Vec2 xi_t = p + (xi - p) * std::exp(s.omega * t_s);
  return signed_margin(convex_hull<kNumPoints>(after, kNumPoints), xi_t);
}

bool foot_in_contact(const PlanKnot& k, int foot) {
  bool all = true, any = false;
  for (int i = 0; i < kCornersPerFoot; ++i) all = all && k.in_contact[foot * kCornersPerFoot + i], any = any || k.in_contact[foot * kCornersPerFoot + i];
  EXPECT_EQ(all, any) << "a foot's corners must share one flag";
  return all;
}

TEST(RecoveryStep, StandingStillChangesNothing) {
  Fixture f;
  for (int i = 0; i < 50; ++i) {
    f.call(1.0 + kDt * i, Vec2::Zero());
    ASSERT_TRUE(f.window_unchanged()) << "call " << i;
  }
  EXPECT_EQ(f.state->steps, 0u);
  EXPECT_LT(f.state->last_outside_m, -0.05);  // ξ = c, well inside
}

// ξ 4 cm behind the heels: the ankles cannot stop the CoM, a step back does.
TEST(RecoveryStep, CaptureLostBackwardsStepsBackAndCapturesIt) {
  Fixture f;
  const Standing s = standing_geometry();
  const double heel_x = s.heel_x;
  const double xi_x = heel_x - 0.04;
  const Vec2 velocity = s.backwards(0.04);

  f.call(1.0, velocity);
  EXPECT_EQ(f.state->steps, 0u) << "one call outside is not yet a trigger";
  EXPECT_TRUE(f.window_unchanged());
  EXPECT_NEAR(f.state->last_outside_m, 0.04, 2e-3);  // the pendulum's ξ, measured by the step's own polygon

  {
    kuavo::test::AllocTrap trap;
    f.call(1.0 + kDt, velocity);
    EXPECT_EQ(trap.count(), 0u);
  }
  ASSERT_EQ(f.state->steps, 1u);
  const int swing = f.state->foot[0].active ? 0 : 1;
  ASSERT_TRUE(f.state->foot[swing].active);
  ASSERT_FALSE(f.state->foot[1 - swing].active);
  const int stance = 1 - swing;

  // Contact: the swing foot is up on [lift, land) and nowhere else; the stance foot stays down.
  const hal::TimeNs now = f.window->knots[0].stamp_ns;
  const hal::TimeNs lift = now + static_cast<hal::TimeNs>(std::llround(f.config.lift_delay_s * 1e9));
  const hal::TimeNs land = lift + static_cast<hal::TimeNs>(std::llround(f.config.swing_s * 1e9));
  int up = 0;
  for (int k = 0; k < kKnots; ++k) {
    const PlanKnot& knot = f.window->knots[k];
    const bool in_swing = knot.stamp_ns >= lift && knot.stamp_ns < land;
    EXPECT_EQ(foot_in_contact(knot, swing), !in_swing) << k;
    EXPECT_TRUE(foot_in_contact(knot, stance)) << k;
    up += in_swing ? 1 : 0;
  }
  EXPECT_EQ(up, static_cast<int>(std::lround(f.config.swing_s / kDt)));

  // Every knot's legs reach their corners: the stance foot where it stands, the swing foot
  // on its arc, then at its new place (forward kinematics of the rewritten q).
  const PlanKnot& last = f.window->knots[kKnots - 1];
  const auto landed = corners_of(last);
  Vec2 shift = Vec2::Zero();
  for (int i = 0; i < kCornersPerFoot; ++i) {
    const int c = swing * kCornersPerFoot + i;
    shift += (landed[c] - s.corner[c]).head<2>() / kCornersPerFoot;
    EXPECT_NEAR(landed[c].z(), s.corner[c].z(), 1e-3) << "the landed sole is on the ground";
  }
  for (int i = 0; i < kCornersPerFoot; ++i) {
    const int c = stance * kCornersPerFoot + i;
    for (int k = 0; k < kKnots; ++k) EXPECT_LT((corners_of(f.window->knots[k])[c] - s.corner[c]).norm(), 1e-3) << k;
  }
  EXPECT_LT(shift.x(), -0.05) << "the foot steps back";
  EXPECT_LE(shift.norm(), f.config.max_step_m + 1e-9);

  // Capture: ξ at touchdown (CoP at the stance heel until then) is inside the new support.
  Vec2 p(heel_x, 0.0);
  double y_lo = 1e9, y_hi = -1e9;
  for (int i = 0; i < kCornersPerFoot; ++i) {
    y_lo = std::min(y_lo, s.corner[stance * kCornersPerFoot + i].y());
    y_hi = std::max(y_hi, s.corner[stance * kCornersPerFoot + i].y());
  }
  p.y() = std::clamp(s.com.y(), y_lo, y_hi);
  const Vec2 xi(xi_x, s.com.y());
  const Vec2 xi_t = p + (xi - p) * std::exp(s.omega * (f.config.lift_delay_s + f.config.swing_s));
  std::array<Vec2, kNumPoints> after;
  for (int c = 0; c < kNumPoints; ++c) after[c] = landed[c].head<2>();
  EXPECT_GT(signed_margin(convex_hull<kNumPoints>(after, kNumPoints), xi_t), f.config.step_capture_margin_m - 1e-3);
  // … which the feet as they stood do not hold.
  std::array<Vec2, kNumPoints> before;
  for (int c = 0; c < kNumPoints; ++c) before[c] = s.corner[c].head<2>();
  EXPECT_LT(signed_margin(convex_hull<kNumPoints>(before, kNumPoints), xi_t), -0.1);

  // The arc: mid-swing the sole is lift_height_m up; corner velocities are the corners' rates.
  const int mid = static_cast<int>(std::lround((f.config.lift_delay_s + 0.5 * f.config.swing_s) / kDt));
  const auto apex = corners_of(f.window->knots[mid]);
  for (int i = 0; i < kCornersPerFoot; ++i) {
    const int c = swing * kCornersPerFoot + i;
    EXPECT_NEAR(apex[c].z() - s.corner[c].z(), f.config.lift_height_m, 2e-3);
  }
  double peak = 0.0;
  for (int k = 1; k + 1 < kKnots; ++k) {
    const auto a = corners_of(f.window->knots[k - 1]), b = corners_of(f.window->knots[k + 1]);
    for (int i = 0; i < kCornersPerFoot; ++i) {
      const int c = swing * kCornersPerFoot + i;
      const Vec3 rate = (b[c] - a[c]) / (2.0 * kDt);
      peak = std::max(peak, rate.norm());
      EXPECT_LT((f.window->knots[k].point_velocity_m_s.segment<3>(3 * c) - rate).norm(), 0.03) << k;
    }
  }
  EXPECT_GT(peak, 0.3) << "the swing foot moves";

  // No second step while this one swings, however far out ξ stays.
  for (int i = 2; i < 10; ++i) f.call(1.0 + kDt * i, velocity);
  EXPECT_EQ(f.state->steps, 1u);
}

// The fast swing (RecoveryStepConfig::fast_swing_s; kuavo simulate --recovery-fast-swing) lets ξ
// diverge for less time: ξ far enough behind the heels that, by the closed form, no landing
// within max_step_m holds it after lift-off + swing_s, while after lift-off + 0.25 s one does.
// Off (the default) that is declined; on, the step swings for 0.25 s. Where the swing_s step
// captures, it is the one taken, fast swing on or off.
TEST(RecoveryStep, TheFastSwingCapturesWhatTheDefaultSwingCannot) {
  const Standing s = standing_geometry();
  const RecoveryStepConfig d;
  constexpr double kFast = 0.25;
  // Along x (ξ on the CoM's line, the centre of pressure at the stance heel): after swing_s ξ
  // is farther behind the heels than a sole moved max_step_m back holds with step_capture_margin_m
  // (any D > lo); after kFast it is within one moved max_step_m back less overshoot_m and the
  // margin (D < hi).
  const double reach = d.max_step_m - d.step_capture_margin_m;
  const double lo = reach / std::exp(s.omega * (d.lift_delay_s + d.swing_s));
  const double hi = (reach - d.overshoot_m - d.step_capture_margin_m) / std::exp(s.omega * (d.lift_delay_s + kFast));
  ASSERT_LT(lo, hi) << "the premise: a gap between the two";
  const double behind = 0.5 * (lo + hi);
  const Vec2 velocity = s.backwards(behind);
  const auto swing_knots = [](const Fixture& f, int foot) {
    int up = 0;
    for (int k = 0; k < kKnots; ++k) up += foot_in_contact(f.window->knots[k], foot) ? 0 : 1;
    return up;
  };

  Fixture off;
  ASSERT_EQ(off.config.fast_swing_s, 0.0) << "off by default";
  for (int i = 0; i < 5; ++i) off.call(1.0 + kDt * i, velocity);
  EXPECT_EQ(off.state->steps, 0u);
  EXPECT_GT(off.state->declined, 0u);
  EXPECT_TRUE(off.window_unchanged());

  Fixture f;
  f.config.fast_swing_s = kFast;
  ASSERT_EQ(recovery_step_validate(f.config), nullptr);
  {
    kuavo::test::AllocTrap trap;
    for (int i = 0; i < f.config.trigger_calls; ++i) f.call(1.0 + kDt * i, velocity);
    EXPECT_EQ(trap.count(), 0u);
  }
  ASSERT_EQ(f.state->steps, 1u);
  EXPECT_EQ(f.state->fast_steps, 1u);
  const int swing = f.state->foot[0].active ? 0 : 1;
  EXPECT_EQ(swing_knots(f, swing), static_cast<int>(std::lround(kFast / kDt)));
  // ξ at touchdown inside the support the landed sole makes.
  EXPECT_GT(touchdown_margin(s, f.window->knots[kKnots - 1], swing, Vec2(s.heel_x - behind, s.com.y()),
                             f.config.lift_delay_s + kFast),
            f.config.step_capture_margin_m - 2e-3);

  // ξ 4 cm behind the heels, which the swing_s step captures (CaptureLostBackwards…): that
  // step, the same with the fast swing on.
  Fixture slow_off, slow_on;
  slow_on.config.fast_swing_s = kFast;
  for (int i = 0; i < 2; ++i) {
    slow_off.call(1.0 + kDt * i, s.backwards(0.04));
    slow_on.call(1.0 + kDt * i, s.backwards(0.04));
  }
  ASSERT_EQ(slow_on.state->steps, 1u);
  EXPECT_EQ(slow_on.state->fast_steps, 0u);
  const int slow_swing = slow_on.state->foot[0].active ? 0 : 1;
  EXPECT_EQ(swing_knots(slow_on, slow_swing), static_cast<int>(std::lround(d.swing_s / kDt)));
  for (int k = 0; k < kKnots; ++k) {
    EXPECT_EQ(slow_on.window->knots[k].q, slow_off.window->knots[k].q) << k;
  }
}

// The plan anchor adds its offset to the window after the step is written: the step's
// landing (chosen on the measured state) has it taken off, so that window + offset lands
// where the step without an offset lands, and the capture decision is the same.
TEST(RecoveryStep, TheAnchorsOffsetIsTakenOffTheLanding) {
  const Standing s = standing_geometry();
  const Vec2 velocity = s.backwards(0.02);
  const Vec2 offset(0.02, -0.01);
  Fixture a, b;
  for (int i = 0; i < 2; ++i) a.call(1.0 + kDt * i, velocity), b.call(1.0 + kDt * i, velocity, offset);
  ASSERT_EQ(a.state->steps, 1u);
  ASSERT_EQ(b.state->steps, 1u);
  const int swing = a.state->foot[0].active ? 0 : 1;
  ASSERT_TRUE(b.state->foot[swing].active);
  const PlanKnot &la = a.window->knots[kKnots - 1], &lb = b.window->knots[kKnots - 1];
  for (int c = 0; c < kNumPoints; ++c) {
    const Vec2 expected = la.point_position_m.segment<2>(3 * c) - (c / kCornersPerFoot == swing ? offset : Vec2::Zero());
    EXPECT_NEAR((lb.point_position_m.segment<2>(3 * c) - expected).norm(), 0.0, 1e-12) << c;
  }
  // The step (0.26 m) moved the foot by more than the offset: the comparison is not trivially met.
  EXPECT_GT((la.point_position_m.segment<2>(3 * swing * kCornersPerFoot) -
             a.untouched->knots[kKnots - 1].point_position_m.segment<2>(3 * swing * kCornersPerFoot)).norm(),
            2.0 * offset.norm());
}

// A creep (perfume's push-alone falls, stop 54): ξ held just past the edge, short of
// trigger_outside_m, while the loaded ankle sits at its motor limit. It triggers after
// creep_calls calls in a row, not after trigger_calls.
TEST(RecoveryStep, ACreepJustPastTheEdgeStepsAfterCreepCalls) {
  Fixture f;
  ASSERT_GT(f.config.creep_calls, f.config.trigger_calls) << "the premise: the creep count is the longer one";
  ASSERT_LT(0.005, f.config.trigger_outside_m) << "the premise: 5 mm out is short of the fast trigger";
  const Standing s = standing_geometry();
  const Vec2 velocity = s.backwards(0.005);
  for (int i = 0; i + 1 < f.config.creep_calls; ++i) {
    f.call(1.0 + kDt * i, velocity);
    EXPECT_TRUE(f.window_unchanged()) << i;
    EXPECT_NEAR(f.state->last_outside_m, 0.005, 2e-3) << i;
  }
  EXPECT_EQ(f.state->steps + f.state->declined, 0u);
  f.call(1.0 + kDt * (f.config.creep_calls - 1), velocity);
  ASSERT_EQ(f.state->steps, 1u);
  // It steps back: the swing sole's centre lands behind where it stood.
  const int swing = f.state->foot[0].active ? 0 : 1;
  const auto landed = corners_of(f.window->knots[kKnots - 1]);
  double dx = 0.0;
  for (int i = 0; i < kCornersPerFoot; ++i) {
    const int c = swing * kCornersPerFoot + i;
    dx += (landed[c].x() - s.corner[c].x()) / kCornersPerFoot;
  }
  EXPECT_LT(dx, -0.02);
}

// The creep threshold from both sides: ξ 15 mm inside the edge never triggers, 5 mm inside
// does (where no step captures, it is declined: the trigger fired all the same).
TEST(RecoveryStep, TheCreepThresholdIsCreepOutsideM) {
  ASSERT_NEAR(RecoveryStepConfig{}.creep_outside_m, -0.01, 1e-12) << "the premise of the two cases";
  const Standing s = standing_geometry();
  Fixture inside;
  for (int i = 0; i < 3 * inside.config.creep_calls; ++i) {
    inside.call(1.0 + kDt * i, s.backwards(-0.015));
    EXPECT_TRUE(inside.window_unchanged()) << i;
  }
  EXPECT_NEAR(inside.state->last_outside_m, -0.015, 2e-3);
  EXPECT_EQ(inside.state->steps + inside.state->declined, 0u);
  Fixture near;
  for (int i = 0; i < near.config.creep_calls; ++i) near.call(1.0 + kDt * i, s.backwards(-0.005));
  EXPECT_NEAR(near.state->last_outside_m, -0.005, 2e-3);
  EXPECT_EQ(near.state->steps + near.state->declined, 1u);
}

// Holdable soles (ankle_pitch_capacity_Nm = P > 0). Oracle: the ankle's place from Leju's
// contact-point table (FACTS.md §2.2: toe corners 0.17084 m ahead of the ankle axis, heels
// 0.073164 behind) and the standing soles by forward kinematics; each foot's load by the lever
// rule on the CoM's place between the feet, worked here from the corners.
struct HoldableFront {
  double ankle_x = 0.0;                 // both ankles (standing: feet parallel to x)
  double y_left = 0.0, y_right = 0.0;  // the soles' outer edges
  double reach_left = 0.0, reach_right = 0.0;
  // The front edge of the two holdable soles' hull at lateral position y.
  double at(double y) const {
    return ankle_x + reach_right + (reach_left - reach_right) * (y - y_right) / (y_left - y_right);
  }
};
constexpr double kToeAheadOfAnkle = 0.17084;
constexpr double kHeelBehindAnkle = 0.073164;

HoldableFront holdable_front(const Standing& s, double capacity_Nm) {
  HoldableFront h;
  h.ankle_x = s.corner[0].x() - kToeAheadOfAnkle;
  EXPECT_NEAR(s.corner[2].x(), h.ankle_x - kHeelBehindAnkle, 1e-6) << "the premise: level feet along x";
  double yl = 0.0, yr = 0.0;
  h.y_left = -1e9, h.y_right = 1e9;
  for (int i = 0; i < kCornersPerFoot; ++i) {
    yl += s.corner[i].y() / kCornersPerFoot, yr += s.corner[kCornersPerFoot + i].y() / kCornersPerFoot;
    h.y_left = std::max(h.y_left, s.corner[i].y()), h.y_right = std::min(h.y_right, s.corner[kCornersPerFoot + i].y());
  }
  const double w_left = (s.com.y() - yr) / (yl - yr);
  const double weight_N = s45_robot().total_mass_kg * model::kGravity_m_s2;
  h.reach_left = std::min(kToeAheadOfAnkle, capacity_Nm / (w_left * weight_N));
  h.reach_right = std::min(kToeAheadOfAnkle, capacity_Nm / ((1.0 - w_left) * weight_N));
  return h;
}

// Standing (about half the weight on each foot), the trigger's polygon ends where the ankles'
// pitch holds each foot's load, P / F ahead of the ankle, not at the toes: ξ 5 mm past that
// front is 5 mm out and creeps into a trigger; with the soles' corners it is 6 cm inside.
TEST(RecoveryStep, HoldableSolesEndWhereTheAnklesHoldTheLoad) {
  constexpr double kCapacity = 30.0;
  const Standing s = standing_geometry();
  const HoldableFront front = holdable_front(s, kCapacity);
  ASSERT_LT(front.reach_left, kToeAheadOfAnkle - 0.03) << "the premise: the capacity binds well short of the toes";
  const double xi_x = front.at(s.com.y()) + 0.005;
  const Vec2 velocity = s.towards(xi_x);

  Fixture held(kCapacity);
  Fixture corners(0.0);
  for (int i = 0; i + 1 < held.config.creep_calls; ++i) {
    held.call(1.0 + kDt * i, velocity);
    corners.call(1.0 + kDt * i, velocity);
    EXPECT_NEAR(held.state->last_outside_m, 0.005, 1.5e-3) << i;
    EXPECT_NEAR(corners.state->last_outside_m, xi_x - (front.ankle_x + kToeAheadOfAnkle), 1.5e-3) << i;
  }
  EXPECT_EQ(held.state->steps + held.state->declined, 0u) << "5 mm out is a creep: creep_calls calls";
  held.call(1.0 + kDt * (held.config.creep_calls - 1), velocity);
  corners.call(1.0 + kDt * (corners.config.creep_calls - 1), velocity);
  EXPECT_EQ(held.state->steps + held.state->declined, 1u);
  EXPECT_EQ(corners.state->steps + corners.state->declined, 0u);
  EXPECT_TRUE(corners.window_unchanged());
}

// The default trigger is the holdable soles at kHoldableAnklePitch_Nm (stop 66): standing, ξ
// 5 mm past their front (3 mm inside the toes) is 5 mm out with the default config and creeps
// into a trigger; with the soles' corners (capacity 0, `kuavo simulate --holdable-soles off`)
// it is inside (it creeps there too: within 1 cm of the edge).
TEST(RecoveryStep, TheDefaultTriggerIsTheHoldableSoles) {
  const Standing s = standing_geometry();
  const HoldableFront front = holdable_front(s, kHoldableAnklePitch_Nm);
  const double xi_x = front.at(s.com.y()) + 0.005;
  ASSERT_LT(xi_x, front.ankle_x + kToeAheadOfAnkle - 0.002) << "the premise: inside the soles";
  const Vec2 velocity = s.towards(xi_x);
  Fixture by_default;
  Fixture corners(0.0);
  for (int i = 0; i < by_default.config.creep_calls; ++i) {
    by_default.call(1.0 + kDt * i, velocity);
    corners.call(1.0 + kDt * i, velocity);
  }
  EXPECT_NEAR(by_default.state->last_outside_m, 0.005, 1.5e-3);
  EXPECT_EQ(by_default.state->steps + by_default.state->declined, 1u);
  EXPECT_NEAR(corners.state->last_outside_m, xi_x - (front.ankle_x + kToeAheadOfAnkle), 1.5e-3);
  EXPECT_LT(corners.state->last_outside_m, 0.0);
}

// A forward exit the ankles cannot hold (ξ 2 cm past the holdable front, 4 cm inside the
// toes) is a fast trigger, and the step is planned on the soles as before: ξ propagated from
// the stance sole's point nearest it (closed form) is inside, by step_capture_margin_m, the support
// of the stance sole and the swing sole where forward kinematics puts it. With the soles'
// corners (capacity 0) ξ is inside them and nothing happens.
TEST(RecoveryStep, AForwardExitTheAnklesCannotHoldSteps) {
  constexpr double kCapacity = 30.0;
  const Standing s = standing_geometry();
  const HoldableFront front = holdable_front(s, kCapacity);
  const double xi_x = front.at(s.com.y()) + 0.02;
  ASSERT_LT(xi_x, front.ankle_x + kToeAheadOfAnkle - 0.03) << "the premise: ξ is inside the soles";
  const Vec2 velocity = s.towards(xi_x);
  Fixture corners(0.0);
  Fixture f(kCapacity);
  for (int i = 0; i < 3 * f.config.creep_calls; ++i) {
    corners.call(1.0 + kDt * i, velocity);
    EXPECT_TRUE(corners.window_unchanged()) << i;
  }
  EXPECT_EQ(corners.state->steps + corners.state->declined, 0u);
  for (int i = 0; i < f.config.trigger_calls; ++i) f.call(1.0 + kDt * i, velocity);
  ASSERT_EQ(f.state->steps, 1u);
  const int swing = f.state->foot[0].active ? 0 : 1;
  const auto landed = corners_of(f.window->knots[kKnots - 1]);
  EXPECT_GT(touchdown_margin(s, f.window->knots[kKnots - 1], swing, Vec2(xi_x, s.com.y()),
                             f.config.lift_delay_s + f.config.swing_s),
            f.config.step_capture_margin_m - 2e-3);
  double dx = 0.0;
  for (int i = 0; i < kCornersPerFoot; ++i) {
    const int c = swing * kCornersPerFoot + i;
    dx += (landed[c].x() - s.corner[c].x()) / kCornersPerFoot;
  }
  EXPECT_GT(dx, 0.02) << "the foot steps ahead";
}

// step_capture_margin_m decides: the forward exit above steps when its landing holds ξ by at
// least the margin and is declined when the margin asks for more (the landing's margin from
// the closed form, touchdown_margin, within its 2 mm).
TEST(RecoveryStep, AStepIsTakenOnlyWithStepCaptureMargin) {
  constexpr double kCapacity = 30.0;
  const Standing s = standing_geometry();
  const double xi_x = holdable_front(s, kCapacity).at(s.com.y()) + 0.02;
  const Vec2 velocity = s.towards(xi_x);
  Fixture f(kCapacity);
  for (int i = 0; i < f.config.trigger_calls; ++i) f.call(1.0 + kDt * i, velocity);
  ASSERT_EQ(f.state->steps, 1u);
  const int swing = f.state->foot[0].active ? 0 : 1;
  const double margin = touchdown_margin(s, f.window->knots[kKnots - 1], swing, Vec2(xi_x, s.com.y()),
                                         f.config.lift_delay_s + f.config.swing_s);
  ASSERT_GT(margin, f.config.step_capture_margin_m + 0.005) << "the premise: room above the default";

  Fixture asks_more(kCapacity);
  asks_more.config.step_capture_margin_m = margin + 0.005;
  ASSERT_EQ(recovery_step_validate(asks_more.config), nullptr);
  for (int i = 0; i < asks_more.config.trigger_calls; ++i) asks_more.call(1.0 + kDt * i, velocity);
  EXPECT_EQ(asks_more.state->steps, 0u);
  EXPECT_GT(asks_more.state->declined, 0u);
  EXPECT_TRUE(asks_more.window_unchanged());

  Fixture asks_less(kCapacity);
  asks_less.config.step_capture_margin_m = margin - 0.005;
  for (int i = 0; i < asks_less.config.trigger_calls; ++i) asks_less.call(1.0 + kDt * i, velocity);
  EXPECT_EQ(asks_less.state->steps, 1u);

  RecoveryStepConfig negative;
  negative.step_capture_margin_m = -0.01;
  EXPECT_NE(recovery_step_validate(negative), nullptr);
}

// The creep count is of calls in a row: one call well inside starts it again.
TEST(RecoveryStep, ACreepInterruptedCountsAgain) {
  Fixture f;
  const Standing s = standing_geometry();
  const Vec2 velocity = s.backwards(0.005);
  double t = 1.0;
  for (int i = 0; i + 1 < f.config.creep_calls; ++i, t += kDt) f.call(t, velocity);
  f.call(t, Vec2::Zero());  // ξ = c, well inside
  t += kDt;
  for (int i = 0; i + 1 < f.config.creep_calls; ++i, t += kDt) f.call(t, velocity);
  EXPECT_EQ(f.state->steps + f.state->declined, 0u);
  f.call(t, velocity);
  EXPECT_EQ(f.state->steps, 1u);
}

// ξ 4 cm beside the left foot: the right foot cannot land beyond it (it stays on its own
// side) and standing on the right foot throws ξ farther out: nothing captures, no step.
TEST(RecoveryStep, SidewaysBeyondReachIsDeclined) {
  Fixture f;
  const Standing s = standing_geometry();
  const Vec2 velocity(0.0, (s.outer_y + 0.04 - s.com.y()) * s.omega);
  for (int i = 0; i < 5; ++i) {
    f.call(1.0 + kDt * i, velocity);
    EXPECT_TRUE(f.window_unchanged()) << i;
  }
  EXPECT_EQ(f.state->steps, 0u);
  EXPECT_GT(f.state->declined, 0u);
}

// The motion lifts a foot 0.3 s from now: the step would overlap it, so the MPC's own
// touchdown adaptation is left to handle it.
TEST(RecoveryStep, NoStepWhenTheMotionStepsSoon) {
  Fixture f;
  lift_in_motion(*f.motion, kRightFoot, 1.34, 1.74);
  const Standing s = standing_geometry();
  const Vec2 velocity = s.backwards(0.04);
  for (int i = 0; i < 3; ++i) {
    f.call(1.0 + kDt * i, velocity);
    EXPECT_TRUE(f.window_unchanged()) << i;
  }
  EXPECT_EQ(f.state->steps, 0u);
}

// After the step the foot stays displaced until the motion lifts it; over that swing it
// returns, and it lands where the motion has it.
TEST(RecoveryStep, TheDisplacedFootReturnsOverTheMotionsNextSwing) {
  Fixture f;
  const Standing s = standing_geometry();
  const Vec2 velocity = s.backwards(0.04);
  f.call(1.0, velocity);
  f.call(1.0 + kDt, velocity);
  ASSERT_EQ(f.state->steps, 1u);
  const int swing = f.state->foot[0].active ? 0 : 1;
  lift_in_motion(*f.motion, swing, 3.0, 3.4);

  // At 2.5 s the window (to 3.7 s) holds the whole return swing.
  f.call(2.5, Vec2::Zero());
  EXPECT_EQ(f.state->steps, 1u);
  for (int k = 0; k < kKnots; ++k) {
    const PlanKnot& knot = f.window->knots[k];
    const double t = 2.5 + kDt * k;
    const auto c = corners_of(knot);
    Vec2 offset = Vec2::Zero();
    for (int i = 0; i < kCornersPerFoot; ++i) offset += (c[swing * kCornersPerFoot + i] - s.corner[swing * kCornersPerFoot + i]).head<2>() / kCornersPerFoot;
    if (t < 2.999) {
      EXPECT_LT(offset.x(), -0.05) << t << ": still displaced";
    }
    if (t > 3.401) {
      EXPECT_LT(offset.norm(), 1e-3) << t << ": back where the motion has it";
    }
    EXPECT_EQ(foot_in_contact(knot, swing), !(t > 2.999 && t < 3.399)) << t;
  }
  // Once the return swing has landed, the displacement is forgotten.
  f.call(3.5, Vec2::Zero());
  EXPECT_FALSE(f.state->foot[swing].active);
  EXPECT_TRUE(f.window_unchanged());
}

// Consecutive calls reuse the previous call's re-solved knots: the window they give is the
// one a state without that cache gives, bit for bit, all through a step, its hold and the
// moment its return swing is found (which changes the displacement of knots met before).
TEST(RecoveryStep, ReusingThePreviousCallsKnotsChangesNoBit) {
  Fixture f;
  const Standing s = standing_geometry();
  const Vec2 velocity = s.backwards(0.04);
  auto fresh = std::make_unique<RecoveryStepState>();
  auto fresh_window = std::make_unique<PlanWindow>();
  int reused = 0;
  for (int i = 0; i < 40; ++i) {
    const double t = 1.0 + kDt * i;
    const Vec2 v = i < 2 ? velocity : Vec2::Zero();
    *fresh = *f.state;
    fresh->cache_count = 0;
    const hal::TimeNs t_ns = static_cast<hal::TimeNs>(std::llround(t * 1e9));
    motion_plan_window_rt(s45_robot(), f.data, *f.motion, t_ns, kDt, kKnots, *fresh_window);
    if (f.shape_plan) f.shape_plan(*fresh_window);
    recovery_step_rt(s45_robot(), f.config, *fresh, *f.motion,
                     kuavo::test::measured_knot(standing_configuration(), translating(v), t_ns), *fresh_window);
    {
      kuavo::test::AllocTrap trap;
      f.call(t, v);
      EXPECT_EQ(trap.count(), 0u) << "call " << i;
    }
    if (i == 1) {  // the step is taken: the motion lifts that foot at 2.0 s, so its return enters the window
      ASSERT_EQ(f.state->steps, 1u);
      lift_in_motion(*f.motion, f.state->foot[0].active ? 0 : 1, 2.0, 2.4);
    }
    for (int k = 0; k < kKnots; ++k) {
      const PlanKnot &a = f.window->knots[k], &b = fresh_window->knots[k];
      ASSERT_TRUE(a.q == b.q && a.v == b.v && a.in_contact == b.in_contact && a.point_position_m == b.point_position_m &&
                  a.point_velocity_m_s == b.point_velocity_m_s && a.com_position_m == b.com_position_m &&
                  a.com_velocity_m_s == b.com_velocity_m_s)
          << "call " << i << " knot " << k;
      reused += f.state->hit[k] >= 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(f.state->steps, 1u);
  EXPECT_TRUE(f.state->foot[0].return_known || f.state->foot[1].return_known);
  EXPECT_GT(reused, 30 * 50) << "most knots come from the previous call";
}

// Early touchdown. The motion swings the left foot over [1.0, 1.8) s; at 1.1 s the robot,
// on its right foot, moves left so that ξ lies at the left sole's outer edge. Propagated to
// the motion's touchdown (0.7 s on, the centre of pressure at the right sole's inner edge) ξ
// is far beyond the left foot's landing; 0.15 s on it is not yet: the left foot lands then,
// beyond it. The motion's own ξ (its knots' CoM velocity; the frames stand still) sits on the
// right sole's inner edge, so its touchdown holds it (the motion's margin there is positive,
// as in the rescues measured: recovery_step.h). Oracle: the pendulum in closed form on the
// soles' axis-aligned edges, and the rewritten knots' corners by forward kinematics.
struct EarlyTouchdown {
  Fixture f;
  Standing s = standing_geometry();
  double inner_y = -1e9;  // the right sole's inner edge
  double toe_x = -1e9;
  Vec2 velocity;
  explicit EarlyTouchdown(double xi_beyond_outer_m, double touchdown_s = 1.8, double lift_s = 1.0) {
    lift_in_motion(*f.motion, kLeftFoot, lift_s, touchdown_s);
    for (int i = 0; i < kCornersPerFoot; ++i) inner_y = std::max(inner_y, s.corner[kRightFoot * kCornersPerFoot + i].y());
    for (const Vec3& c : s.corner) toe_x = std::max(toe_x, c.x());
    velocity = Vec2(0.0, (s.outer_y + xi_beyond_outer_m - s.com.y()) * s.omega);
    plan_xi_at(Vec2(s.com.x(), inner_y));
  }
  // The whole robot's velocity that puts ξ at `xi` (horizontal).
  Vec2 velocity_to(const Vec2& xi) const { return (xi - s.com.head<2>()) * s.omega; }
  // Every knot's CoM velocity puts the motion's own ξ at `xi`.
  void plan_xi_at(const Vec2& xi) {
    const Vec2 v = velocity_to(xi);
    f.shape_plan = [v](PlanWindow& w) {
      for (int k = 0; k < w.count; ++k) w.knots[k].com_velocity_m_s.head<2>() = v;
    };
  }
  // ξ after t seconds with the centre of pressure at the right sole's point nearest ξ.
  Vec2 xi_after(double t) const { return xi_after(t, velocity); }
  Vec2 xi_after(double t, const Vec2& v) const {
    const Vec2 xi = s.com.head<2>() + v / s.omega;
    const Vec2 p(std::clamp(xi.x(), s.heel_x, toe_x), inner_y);
    return p + (xi - p) * std::exp(s.omega * t);
  }
  Vec2 left_centre(const std::array<Vec3, kNumPoints>& c) const {
    Vec2 out = Vec2::Zero();
    for (int i = 0; i < kCornersPerFoot; ++i) out += c[kLeftFoot * kCornersPerFoot + i].head<2>() / kCornersPerFoot;
    return out;
  }
};

TEST(RecoveryStep, ASwingThatCannotCatchLandsEarlyBeyondTheCapturePoint) {
  EarlyTouchdown e(0.0);
  Fixture& f = e.f;
  const Standing& s = e.s;
  // The motion's touchdown misses ξ then by far (the trigger's premise, in closed form).
  EXPECT_GT(e.xi_after(0.7).y() - s.outer_y, 0.3);

  f.call(1.1, e.velocity);
  EXPECT_EQ(f.state->early_touchdowns, 0u) << "one call is not yet a trigger";
  EXPECT_TRUE(f.window_unchanged());
  {
    kuavo::test::AllocTrap trap;
    f.call(1.1 + kDt, e.velocity);
    EXPECT_EQ(trap.count(), 0u);
  }
  ASSERT_EQ(f.state->early_touchdowns, 1u);
  EXPECT_EQ(f.state->steps, 0u);
  const double now = 1.1 + kDt, land = now + f.config.early_lead_s;

  // Where it lands: overshoot_m beyond ξ at the early touchdown, on the line from the CoP.
  const Vec2 xi_land = e.xi_after(f.config.early_lead_s);
  const Vec2 p(std::clamp(xi_land.x(), s.heel_x, e.toe_x), e.inner_y);
  const Vec2 expected = xi_land + f.config.overshoot_m * (xi_land - p).normalized();
  const Vec2 right_centre = 0.5 * (s.corner[kRightFoot * kCornersPerFoot].head<2>() + s.corner[kRightFoot * kCornersPerFoot + 3].head<2>());
  ASSERT_LT(expected.y() - right_centre.y(), f.config.max_width_m) << "the test's target is within reach";

  for (int k = 0; k < kKnots; ++k) {
    const PlanKnot& knot = f.window->knots[k];
    const double t = now + kDt * k;
    const auto c = corners_of(knot);
    EXPECT_TRUE(foot_in_contact(knot, kRightFoot)) << t;
    EXPECT_EQ(foot_in_contact(knot, kLeftFoot), t > land - 1e-6) << t;
    if (t > land - 1e-6) {
      EXPECT_LT((e.left_centre(c) - expected).norm(), 2e-3) << t << ": on the landing, before and after the motion's touchdown";
      for (int i = 0; i < kCornersPerFoot; ++i) {
        const int ci = kLeftFoot * kCornersPerFoot + i;
        EXPECT_NEAR(c[ci].z(), s.corner[ci].z(), 1e-3) << t << ": on the ground";
      }
    }
  }
  // The support it makes holds ξ at touchdown by capture_margin_m; the motion's would not.
  const auto landed = corners_of(f.window->knots[kKnots - 1]);
  std::array<Vec2, kNumPoints> after, before;
  for (int c = 0; c < kNumPoints; ++c) after[c] = landed[c].head<2>(), before[c] = s.corner[c].head<2>();
  EXPECT_GT(signed_margin(convex_hull<kNumPoints>(after, kNumPoints), xi_land), f.config.capture_margin_m - 1e-3);
  EXPECT_LT(signed_margin(convex_hull<kNumPoints>(before, kNumPoints), e.xi_after(0.7)), -0.3);

  // Nothing more while it is under way.
  for (int i = 2; i < 10; ++i) f.call(1.1 + kDt * i, e.velocity);
  EXPECT_EQ(f.state->early_touchdowns, 1u);
  EXPECT_EQ(f.state->steps, 0u);
}

// ξ over the stance sole's centre: it stays there, the motion's touchdown holds it, nothing
// changes; the push above with early touchdown off changes nothing either.
TEST(RecoveryStep, NoEarlyTouchdownWhenTheMotionsTouchdownCatches) {
  EarlyTouchdown e(0.0);
  Vec2 right_centre = Vec2::Zero();
  for (int i = 0; i < kCornersPerFoot; ++i) right_centre += e.s.corner[kRightFoot * kCornersPerFoot + i].head<2>() / kCornersPerFoot;
  const Vec2 velocity = (right_centre - e.s.com.head<2>()) * e.s.omega;
  for (int i = 0; i < 10; ++i) {
    e.f.call(1.1 + kDt * i, velocity);
    EXPECT_TRUE(e.f.window_unchanged()) << i;
  }
  EXPECT_EQ(e.f.state->early_touchdowns, 0u);

  EarlyTouchdown off(0.0);
  off.f.config.early_touchdown = false;
  for (int i = 0; i < 5; ++i) {
    off.f.call(1.1 + kDt * i, off.velocity);
    EXPECT_TRUE(off.f.window_unchanged()) << i;
  }
  EXPECT_EQ(off.f.state->early_touchdowns, 0u);
}

// The motion's own state (the knots stand still, ξ between the feet) throws ξ far beyond the
// left foot's landing on one foot: a dance's swing may plan that (the next double support
// brings it back). Measured = planned: nothing changes.
TEST(RecoveryStep, NoEarlyTouchdownWhereTheMotionItselfPlansCapturePointOutside) {
  EarlyTouchdown e(0.0);
  e.f.shape_plan = nullptr;  // the frames' own CoM velocity: zero
  EXPECT_GT(e.xi_after(0.7, Vec2::Zero()).y() - e.s.outer_y, 0.2) << "the premise: the plan's ξ misses by far";
  for (int i = 0; i < 5; ++i) {
    e.f.call(1.1 + kDt * i, Vec2::Zero());
    EXPECT_TRUE(e.f.window_unchanged()) << i;
  }
  EXPECT_EQ(e.f.state->early_touchdowns, 0u);
}

// perfume's case (stop 67): the motion's own ξ at its touchdown 6 cm outside the support that
// touchdown makes (a stride its next steps catch), the measured ξ much farther out, a landing
// 0.15 s from now would capture it: the relative trigger holds, but the motion's own
// touchdown does not hold its ξ (early_plan_margin_min_m 0): it lands on the motion's clock.
// The control: with the gate lowered past the motion's margin it lands early.
TEST(RecoveryStep, NoEarlyTouchdownWhereTheMotionsOwnTouchdownMissesItsCapturePoint) {
  const auto plan_6cm_out = [](EarlyTouchdown& e) {
    // ξ now such that 0.69 s on (between the two calls' times to touchdown) it lies 6 cm
    // beyond the left sole's outer edge, the support's edge on that side.
    const double t = 0.7 - 0.5 * kDt;
    const Vec2 p(e.s.com.x(), e.inner_y);
    e.plan_xi_at(p + Vec2(0.0, e.s.outer_y + 0.06 - e.inner_y) * std::exp(-e.s.omega * t));
  };
  EarlyTouchdown e(0.0), control(0.0);
  plan_6cm_out(e);
  plan_6cm_out(control);
  control.f.config.early_plan_margin_min_m = -0.2;
  EXPECT_GT(e.xi_after(0.7).y() - e.s.outer_y, 0.3) << "the premise: the measured ξ misses by far more";
  for (int i = 0; i < 3; ++i) {
    e.f.call(1.1 + kDt * i, e.velocity);
    EXPECT_TRUE(e.f.window_unchanged()) << i;
    control.f.call(1.1 + kDt * i, control.velocity);
  }
  EXPECT_EQ(e.f.state->early_touchdowns, 0u);
  EXPECT_EQ(control.f.state->early_touchdowns, 1u);
}

// ξ 2 cm left of the CoM (the plan's on the right sole's inner edge), the motion's touchdown
// 0.4 s away: ξ then misses the motion's landing by several cm more than the plan's, but a
// landing within the reach box on the motion's clock captures it: that is the MPC's (it adapts
// the spot), nothing changes. With the reach box narrowed below that landing, the foot lands
// early instead.
TEST(RecoveryStep, NoEarlyTouchdownWhenALandingOnTheMotionsClockCaptures) {
  EarlyTouchdown e(0.0, 1.5);
  const Vec2 velocity(0.0, 0.02 * e.s.omega);
  const double t_motion = 1.5 - 1.1 - kDt;
  const Vec2 xi_meas = e.xi_after(t_motion, velocity);
  const Vec2 xi_plan = e.xi_after(t_motion, e.velocity_to(Vec2(e.s.com.x(), e.inner_y)));
  EXPECT_GT(xi_meas.y() - xi_plan.y(), 0.05) << "the premise: beyond the plan's by more than early_trigger_m";
  EXPECT_GT(xi_meas.y(), e.s.outer_y + e.f.config.early_trigger_m) << "the premise: the motion's landing misses it";
  Vec2 right_centre = Vec2::Zero();
  for (int i = 0; i < kCornersPerFoot; ++i) right_centre += e.s.corner[kRightFoot * kCornersPerFoot + i].head<2>() / kCornersPerFoot;
  const double width = xi_meas.y() + e.f.config.overshoot_m - right_centre.y();
  ASSERT_LT(width, e.f.config.max_width_m - 0.01) << "the premise: a landing on the clock within reach";
  for (int i = 0; i < 3; ++i) {
    e.f.call(1.1 + kDt * i, velocity);
    EXPECT_TRUE(e.f.window_unchanged()) << i;
  }
  EXPECT_EQ(e.f.state->early_touchdowns, 0u);

  EarlyTouchdown narrow(0.0, 1.5);
  narrow.f.config.max_width_m = width - 0.08;  // ξ then 1 cm inside the sole: short of capture_margin_m
  narrow.f.config.early_min_swing_s = 0.0;     // its 0.5 s swing: not this test's question
  for (int i = 0; i < 3; ++i) narrow.f.call(1.1 + kDt * i, velocity);
  EXPECT_EQ(narrow.f.state->early_touchdowns, 1u);
}

// The motion lands 0.2 s from now, within early_lead_s + early_min_gain_s: landing early gains
// too little (and a landing on the motion's clock within reach catches ξ): nothing changes.
TEST(RecoveryStep, NoEarlyTouchdownWhenTheMotionLandsSoonAnyway) {
  EarlyTouchdown e(0.0);
  for (int i = 0; i < 5; ++i) {
    e.f.call(1.6 + kDt * i, e.velocity);
    EXPECT_TRUE(e.f.window_unchanged()) << i;
  }
  EXPECT_EQ(e.f.state->early_touchdowns, 0u);
  // The control: the same state half a second earlier in the swing lands early.
  EarlyTouchdown early(0.0);
  for (int i = 0; i < 2; ++i) early.f.call(1.1 + kDt * i, early.velocity);
  EXPECT_EQ(early.f.state->early_touchdowns, 1u);
}

// A short swing like cmu_05_07's (0.34 s, lifted at 1.08 s, down at 1.42 s), the same push just
// after lift-off: the trigger's conditions hold (with early_min_swing_s 0 it lands early, the
// control), but the swing is shorter than early_min_swing_s: it lands on the motion's clock.
TEST(RecoveryStep, NoEarlyTouchdownInAShortSwing) {
  EarlyTouchdown e(0.0, 1.42, 1.08);
  ASSERT_LT(0.34, e.f.config.early_min_swing_s) << "the premise: a swing short of the default minimum";
  for (int i = 0; i < 5; ++i) {
    e.f.call(1.1 + kDt * i, e.velocity);
    EXPECT_TRUE(e.f.window_unchanged()) << i;
  }
  EXPECT_EQ(e.f.state->early_touchdowns, 0u);
  EarlyTouchdown control(0.0, 1.42, 1.08);
  control.f.config.early_min_swing_s = 0.0;
  for (int i = 0; i < 2; ++i) control.f.call(1.1 + kDt * i, control.velocity);
  EXPECT_EQ(control.f.state->early_touchdowns, 1u);
  // The boundary: a swing of 0.36 s passes a minimum of 0.355 s and fails one of 0.365 s (a
  // lift-off found one frame, 0.01 s, early or late fails one of the two).
  EarlyTouchdown pass(0.0, 1.44, 1.08), fail(0.0, 1.44, 1.08);
  pass.f.config.early_min_swing_s = 0.355;
  fail.f.config.early_min_swing_s = 0.365;
  for (int i = 0; i < 2; ++i) {
    pass.f.call(1.1 + kDt * i, pass.velocity);
    fail.f.call(1.1 + kDt * i, fail.velocity);
  }
  EXPECT_EQ(pass.f.state->early_touchdowns, 1u);
  EXPECT_EQ(fail.f.state->early_touchdowns, 0u);
}

// The plan anchor adds its offset to the window after this call: the early landing (chosen
// on the measured state) has it taken off, so window + offset lands where the landing without
// an offset does (the blend before it starts from the motion's sole, which the offset moves).
TEST(RecoveryStep, AnEarlyLandingHasTheAnchorsOffsetTakenOff) {
  const Vec2 offset(0.02, -0.01);
  EarlyTouchdown a(0.0), b(0.0);
  for (int i = 0; i < 2; ++i) {
    a.f.call(1.1 + kDt * i, a.velocity);
    b.f.call(1.1 + kDt * i, b.velocity, offset);
  }
  ASSERT_EQ(a.f.state->early_touchdowns, 1u);
  ASSERT_EQ(b.f.state->early_touchdowns, 1u);
  bool moved = false;
  for (int k = 0; k < kKnots; ++k) {
    const PlanKnot &ka = a.f.window->knots[k], &kb = b.f.window->knots[k];
    if (!foot_in_contact(ka, kLeftFoot)) continue;  // the blend
    for (int i = 0; i < kCornersPerFoot; ++i) {
      const int c = kLeftFoot * kCornersPerFoot + i;
      const Vec2 expected = ka.point_position_m.segment<2>(3 * c) - offset;
      EXPECT_LT((kb.point_position_m.segment<2>(3 * c) - expected).norm(), 1e-9) << k;
      moved = moved || (ka.point_position_m.segment<2>(3 * c) - a.f.untouched->knots[k].point_position_m.segment<2>(3 * c)).norm() > 2.0 * offset.norm();
    }
  }
  EXPECT_TRUE(moved) << "the landing moved the foot by more than the offset: the comparison is not trivially met";
}

// After the motion's touchdown the early landing's displacement is held; a step of that foot
// (pushed backwards in the double support after it) is an ordinary step: the foot leaves
// contact over its swing and arcs lift_height_m up, from where it was held.
TEST(RecoveryStep, AStepOfAFootHeldByAnEarlyTouchdownSwingsLikeAnyStep) {
  EarlyTouchdown e(0.0);
  Fixture& f = e.f;
  f.call(1.1, e.velocity);
  f.call(1.1 + kDt, e.velocity);
  ASSERT_EQ(f.state->early_touchdowns, 1u);
  const Vec2 held = f.state->foot[kLeftFoot].to;
  // Both feet down after 1.8 s; ξ 2 cm behind the heels: the held left foot takes the step
  // (2 cm: the left; 4 cm: the right, at the time of writing).
  const Vec2 back = e.s.backwards(0.02);
  f.call(2.0, back);
  f.call(2.0 + kDt, back);
  ASSERT_EQ(f.state->steps, 1u) << "declined " << f.state->declined;
  const int swing = kLeftFoot;
  ASSERT_GT(f.state->foot[swing].lift_ns, 1'900'000'000) << "the left foot must be the one that steps";
  EXPECT_FALSE(f.state->foot[swing].early);
  const hal::TimeNs lift = f.state->foot[swing].lift_ns, land = f.state->foot[swing].land_ns;
  double apex = 0.0;
  for (int k = 0; k < kKnots; ++k) {
    const PlanKnot& knot = f.window->knots[k];
    const bool in_swing = knot.stamp_ns >= lift && knot.stamp_ns < land;
    EXPECT_EQ(foot_in_contact(knot, swing), !in_swing) << k;
    const auto c = corners_of(knot);
    for (int i = 0; i < kCornersPerFoot; ++i) {
      const int ci = swing * kCornersPerFoot + i;
      apex = std::max(apex, c[ci].z() - e.s.corner[ci].z());
    }
  }
  EXPECT_NEAR(apex, f.config.lift_height_m, 2e-3);
  // It swings from the early landing: the first knot still has the held displacement.
  const auto c0 = corners_of(f.window->knots[0]);
  EXPECT_LT((e.left_centre(c0) - e.left_centre(e.s.corner) - held).norm(), 2e-3);
}

// The knot cache through an early touchdown, its hold, the motion's touchdown and the return
// over the motion's next swing: bit for bit the window a state without the cache gives.
TEST(RecoveryStep, ReusingKnotsThroughAnEarlyTouchdownChangesNoBit) {
  EarlyTouchdown e(0.0);
  Fixture& f = e.f;
  lift_in_motion(*f.motion, kLeftFoot, 2.3, 2.7);
  auto fresh = std::make_unique<RecoveryStepState>();
  auto fresh_window = std::make_unique<PlanWindow>();
  int reused = 0;
  for (int i = 0; i < 60; ++i) {
    const double t = 1.1 + kDt * i;
    const Vec2 v = i < 2 ? e.velocity : Vec2::Zero();
    *fresh = *f.state;
    fresh->cache_count = 0;
    const hal::TimeNs t_ns = static_cast<hal::TimeNs>(std::llround(t * 1e9));
    motion_plan_window_rt(s45_robot(), f.data, *f.motion, t_ns, kDt, kKnots, *fresh_window);
    if (f.shape_plan) f.shape_plan(*fresh_window);
    recovery_step_rt(s45_robot(), f.config, *fresh, *f.motion,
                     kuavo::test::measured_knot(standing_configuration(), translating(v), t_ns), *fresh_window);
    f.call(t, v);
    for (int k = 0; k < kKnots; ++k) {
      const PlanKnot &a = f.window->knots[k], &b = fresh_window->knots[k];
      ASSERT_TRUE(a.q == b.q && a.v == b.v && a.in_contact == b.in_contact && a.point_position_m == b.point_position_m &&
                  a.point_velocity_m_s == b.point_velocity_m_s)
          << "call " << i << " knot " << k;
      reused += f.state->hit[k] >= 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(f.state->early_touchdowns, 1u);
  EXPECT_TRUE(f.state->foot[kLeftFoot].return_known);
  EXPECT_GT(reused, 20 * 50) << "most knots come from the previous call";
}

TEST(RecoveryStep, ConfigValidation) {
  EXPECT_EQ(recovery_step_validate(RecoveryStepConfig{}), nullptr);
  RecoveryStepConfig c;
  c.swing_s = 0.05;
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.max_width_m = 0.1;  // below min_width_m
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.trigger_outside_m = std::nan("");
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.trigger_calls = 0;
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.creep_calls = 0;
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.creep_outside_m = std::nan("");
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.creep_outside_m = c.trigger_outside_m + 0.001;  // a creep trigger farther out than the fast one
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c.creep_outside_m = c.trigger_outside_m;
  EXPECT_EQ(recovery_step_validate(c), nullptr);
  for (double fast : {0.05, 0.41, -0.2, std::nan("")}) {  // below 0.1 s, beyond swing_s, negative, NaN
    c = {};
    c.fast_swing_s = fast;
    EXPECT_NE(recovery_step_validate(c), nullptr) << fast;
  }
  for (double fast : {0.0, 0.1, 0.25, 0.40}) {
    c = {};
    c.fast_swing_s = fast;
    EXPECT_EQ(recovery_step_validate(c), nullptr) << fast;
  }
  c = {};
  c.early_lead_s = 0.02;  // no foot comes down from its arc that fast
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.early_trigger_m = std::nan("");
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.early_min_swing_s = -0.1;
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c.early_min_swing_s = std::nan("");
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.early_plan_margin_min_m = std::nan("");
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c = {};
  c.ankle_pitch_capacity_Nm = -1.0;
  EXPECT_NE(recovery_step_validate(c), nullptr);
  c.ankle_pitch_capacity_Nm = std::nan("");
  EXPECT_NE(recovery_step_validate(c), nullptr);
}

}  // namespace
}  // namespace kuavo::planner
