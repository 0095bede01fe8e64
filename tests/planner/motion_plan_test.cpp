// Motion sampling against closed-form motions, the kinematic WBC reference, and the
// step-in-place gait against independent forward kinematics.
#include "controllers/planner/motion_plan.h"

#include <gtest/gtest.h>

#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "tests/support/test_robot.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/planner/wbc_from_plan.h"
#include "controllers/standing/standing_controller.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::planner {
namespace {

const model::Model& robot() { return kuavo::test::s45_robot(); }

MotionPlan& plan_storage() {
  static auto plan = std::make_unique<MotionPlan>();
  return *plan;
}

// Base moving at constant velocity in x, turning at constant yaw rate, joint 3 ramping.
void constant_rate_motion(MotionPlan& plan, double vx, double yaw_rate, double joint_rate, int joint = 3) {
  plan.rate_hz = 100.0;
  plan.frame_count = 201;
  plan.start_ns = 1'000'000'000;
  for (int i = 0; i < plan.frame_count; ++i) {
    const double t = i / plan.rate_hz;
    dynamics::ConfigVector q = dynamics::neutral_configuration(robot());
    q[0] = vx * t;
    q.segment<4>(3) = Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rate * t, Eigen::Vector3d::UnitZ())).coeffs();
    q[7 + joint] = 0.2 + joint_rate * t;
    plan.q[i] = q;
    plan.foot_contact[i] = {i < 100, true};
  }
}

TEST(MotionPlan, SamplesReproduceAConstantRateMotion) {
  MotionPlan& plan = plan_storage();
  constant_rate_motion(plan, 0.3, 0.5, -0.4);
  ASSERT_EQ(motion_plan_finish(plan), nullptr);
  EXPECT_DOUBLE_EQ(motion_plan_duration_s(plan), 2.0);
  static dynamics::Data data;
  PlanKnot knot;
  for (double t : {0.013, 0.5, 0.777, 1.2345}) {
    const hal::TimeNs stamp = plan.start_ns + static_cast<hal::TimeNs>(t * 1e9);
    motion_plan_sample_rt(robot(), data, plan, stamp, knot);
    EXPECT_NEAR(knot.q[0], 0.3 * t, 1e-9);
    EXPECT_NEAR(knot.q[7 + 3], 0.2 - 0.4 * t, 1e-9);
    const Eigen::Quaterniond o(knot.q[6], knot.q[3], knot.q[4], knot.q[5]);
    EXPECT_NEAR(Eigen::AngleAxisd(o).angle(), 0.5 * t, 1e-9);
    // Velocity in base axes: the world x velocity seen from the turned base.
    const Eigen::Vector3d v_world = o * knot.v.head<3>();
    EXPECT_NEAR(v_world.x(), 0.3, 1e-4);
    EXPECT_NEAR(v_world.y(), 0.0, 1e-4);
    EXPECT_NEAR(knot.v[5], 0.5, 1e-6);  // yaw rate (base z = world z)
    EXPECT_NEAR(knot.v[6 + 3], -0.4, 1e-9);
    EXPECT_EQ(knot.in_contact[0], t < 1.0);
    EXPECT_TRUE(knot.in_contact[7]);
    EXPECT_EQ(knot.stamp_ns, stamp);
  }
  // Before the start and after the end: the end frames at rest.
  motion_plan_sample_rt(robot(), data, plan, 0, knot);
  EXPECT_EQ(knot.q, plan.q[0]);
  EXPECT_TRUE(knot.v.isZero());
  motion_plan_sample_rt(robot(), data, plan, plan.start_ns + 5'000'000'000, knot);
  EXPECT_EQ(knot.q, plan.q[200]);
  EXPECT_TRUE(knot.v.isZero());
}

TEST(MotionPlan, RejectsBadFrames) {
  MotionPlan& plan = plan_storage();
  constant_rate_motion(plan, 0.0, 0.0, 0.0);
  plan.q[7][10] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(motion_plan_finish(plan), nullptr);
  constant_rate_motion(plan, 0.0, 0.0, 0.0);
  plan.q[7][6] = 2.0;
  EXPECT_NE(motion_plan_finish(plan), nullptr);
  constant_rate_motion(plan, 0.0, 0.0, 0.0);
  plan.rate_hz = 0.0;
  EXPECT_NE(motion_plan_finish(plan), nullptr);
  plan.rate_hz = 100.0;
  plan.frame_count = 1;
  EXPECT_NE(motion_plan_finish(plan), nullptr);
}

TEST(MotionPlan, WindowAndReferenceAllocateNothingAndCarryTheWeight) {
  MotionPlan& plan = plan_storage();
  // The head yaw turns about a vertical axis: the CoM height does not accelerate.
  constant_rate_motion(plan, 0.1, 0.0, 0.2, model::kHeadFirst);
  ASSERT_EQ(motion_plan_finish(plan), nullptr);
  static dynamics::Data data;
  static PlanWindow window;
  static wbc::WbcReference ref;
  {
    kuavo::test::AllocTrap trap;
    for (int rep = 0; rep < 50; ++rep) {
      motion_plan_window_rt(robot(), data, plan, plan.start_ns + 990'000'000, 0.02, 61, window);
      wbc_reference_from_knots(robot(), window.knots[0], window.knots[1], window.dt_s, ref);
    }
    EXPECT_EQ(trap.count(), 0u);
  }
  ASSERT_EQ(window.count, 61);
  EXPECT_EQ(window.knots[60].stamp_ns - window.knots[0].stamp_ns, 1'200'000'000);
  // knot 0 at 0.99 s: left foot still down (all 8 corners), knot 1 at 1.01 s: left foot up.
  double fz = 0.0;
  for (int c = 0; c < kNumPoints; ++c) fz += ref.contact_force_N[3 * c + 2];
  EXPECT_NEAR(fz, robot().total_mass_kg * model::kGravity_m_s2, 1e-6);
  wbc_reference_from_knots(robot(), window.knots[1], window.knots[2], window.dt_s, ref);
  for (int c = 0; c < kCornersPerFoot; ++c) EXPECT_EQ(ref.contact_force_N[3 * c + 2], 0.0);
  EXPECT_NEAR(ref.contact_force_N[3 * 4 + 2], robot().total_mass_kg * model::kGravity_m_s2 / 4, 1e-6);
  EXPECT_NEAR(ref.joint_velocity_rad_s[model::kHeadFirst], 0.2, 1e-9);
}

TEST(StepInPlace, StanceFeetStayPlantedSwingFeetLiftAndTheComIsOverTheStanceFoot) {
  const model::Model& m = robot();
  static dynamics::Data data;
  const dynamics::ConfigVector q0 = kuavo::test::standing_configuration();
  StepInPlaceConfig cfg;
  cfg.steps = 4;
  MotionPlan& plan = plan_storage();
  ASSERT_EQ(make_step_in_place(m, q0, cfg, plan), nullptr);
  dynamics::forward_kinematics(m, data, q0);
  std::array<Vec3, kNumPoints> home{};
  for (int c = 0; c < kNumPoints; ++c) home[c] = dynamics::frame_position(m, data, c);

  int swings = 0;
  bool was_double = true;
  double max_lift = 0.0, worst_stance_slip = 0.0, worst_com_outside = -1.0;
  PlanKnot knot;
  for (int i = 0; i < plan.frame_count; ++i) {
    plan_knot_from_state(m, data, plan.q[i], motion_plan_velocity(plan, i), {}, 0, knot);
    const bool is_double = plan.foot_contact[i][0] && plan.foot_contact[i][1];
    if (was_double && !is_double) ++swings;
    was_double = is_double;
    for (int foot = 0; foot < 2; ++foot) {
      for (int c = foot * kCornersPerFoot; c < (foot + 1) * kCornersPerFoot; ++c) {
        const Vec3 p = knot.point_position_m.segment<3>(3 * c);
        if (plan.foot_contact[i][foot]) {
          worst_stance_slip = std::max(worst_stance_slip, (p - home[c]).norm());
        } else {
          max_lift = std::max(max_lift, p.z() - home[c].z());
        }
      }
      // Single support: the CoM must be over the stance foot's sole (its corner box).
      if (!is_double && plan.foot_contact[i][foot]) {
        double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
        for (int c = foot * kCornersPerFoot; c < (foot + 1) * kCornersPerFoot; ++c) {
          lo_x = std::min(lo_x, home[c].x()), hi_x = std::max(hi_x, home[c].x());
          lo_y = std::min(lo_y, home[c].y()), hi_y = std::max(hi_y, home[c].y());
        }
        const Vec3 com = knot.com_position_m;
        const double outside = std::max({lo_x - com.x(), com.x() - hi_x, lo_y - com.y(), com.y() - hi_y});
        worst_com_outside = std::max(worst_com_outside, outside);
      }
    }
  }
  EXPECT_EQ(swings, 4);
  EXPECT_LT(worst_stance_slip, 1e-3);
  EXPECT_NEAR(max_lift, cfg.lift_m, 2e-3);
  EXPECT_LT(worst_com_outside, -0.01) << "CoM must be at least 1 cm inside the stance sole";
  EXPECT_EQ(plan.q[0], q0);
}

}  // namespace
}  // namespace kuavo::planner
