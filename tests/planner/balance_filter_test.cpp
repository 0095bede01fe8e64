// Support-polygon geometry against closed forms; the balance filter against the
// cart-table ZMP of its own output (computed here, independently, from kinematics) and
// against a motion that needs no correction.
#include "controllers/planner/balance_filter.h"

#include <gtest/gtest.h>

#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "tests/support/test_robot.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/planner/support_polygon.h"
#include "controllers/standing/standing_controller.h"

namespace kuavo::planner {
namespace {

const model::Model& robot() { return kuavo::test::s45_robot(); }

TEST(SupportPolygon, HullMarginAndProjectionOfASquare) {
  // Unit square corners plus interior and edge points, in scrambled order.
  std::array<Eigen::Vector2d, 8> pts = {Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(1, 1), Eigen::Vector2d(0, 0),
                                        Eigen::Vector2d(1, 0.5),   Eigen::Vector2d(0, 1), Eigen::Vector2d(1, 0),
                                        Eigen::Vector2d(0.2, 0.7), Eigen::Vector2d(0.5, 0)};
  const auto hull = convex_hull<8>(pts, 8);
  ASSERT_EQ(hull.count, 4);
  double area2 = 0.0;  // shoelace: positive for counter-clockwise
  for (int i = 0; i < 4; ++i) {
    const auto& a = hull.vertex[i];
    const auto& b = hull.vertex[(i + 1) % 4];
    area2 += a.x() * b.y() - a.y() * b.x();
  }
  EXPECT_NEAR(area2, 2.0, 1e-12);
  EXPECT_NEAR(signed_margin(hull, Eigen::Vector2d(0.5, 0.5)), 0.5, 1e-12);
  EXPECT_NEAR(signed_margin(hull, Eigen::Vector2d(0.9, 0.5)), 0.1, 1e-12);
  EXPECT_NEAR(signed_margin(hull, Eigen::Vector2d(1.3, 0.5)), -0.3, 1e-12);
  EXPECT_NEAR(signed_margin(hull, Eigen::Vector2d(1.3, 1.4)), -0.5, 1e-12);  // 3-4-5 to the corner
  const Eigen::Vector2d inside = project_into(hull, Eigen::Vector2d(0.5, 0.5), 0.05);
  EXPECT_EQ(inside, Eigen::Vector2d(0.5, 0.5));
  const Eigen::Vector2d pulled = project_into(hull, Eigen::Vector2d(2.0, 0.5), 0.05);
  EXPECT_NEAR(pulled.x(), 0.95, 1e-12);
  EXPECT_NEAR(pulled.y(), 0.5, 1e-12);
}

double worst_zmp_outside(const model::Model& m, const MotionPlan& plan) {
  static dynamics::Data data;
  const double dt = 1.0 / plan.rate_hz;
  std::vector<Eigen::Vector3d> com(plan.frame_count);
  PlanKnot knot;
  for (int i = 0; i < plan.frame_count; ++i) {
    plan_knot_from_state(m, data, plan.q[i], dynamics::VelocityVector::Zero(), {}, 0, knot);
    com[i] = knot.com_position_m;
  }
  double worst = 0.0;
  for (int i = 1; i + 1 < plan.frame_count; ++i) {
    plan_knot_from_state(m, data, plan.q[i], dynamics::VelocityVector::Zero(), {}, 0, knot);
    std::array<Eigen::Vector2d, kNumPoints> pts{};
    int n = 0;
    for (int c = 0; c < kNumPoints; ++c) {
      if (plan.foot_contact[i][c < kCornersPerFoot ? 0 : 1]) pts[n++] = knot.point_position_m.segment<2>(3 * c);
    }
    if (n < 3) continue;
    const double height = com[i].z() - knot.point_position_m[2];
    const Eigen::Vector2d acc = ((com[i + 1] - 2.0 * com[i] + com[i - 1]) / (dt * dt)).head<2>();
    const Eigen::Vector2d zmp = com[i].head<2>() - height / model::kGravity_m_s2 * acc;
    worst = std::max(worst, -signed_margin(convex_hull<kNumPoints>(pts, n), zmp));
  }
  return worst;
}


TEST(BalanceFilter, LeavesABalancedStillMotionAlone) {
  auto plan = std::make_unique<MotionPlan>();
  auto ws = std::make_unique<BalanceFilterWorkspace>();
  plan->rate_hz = 100.0;
  plan->frame_count = 200;
  for (int i = 0; i < plan->frame_count; ++i) plan->q[i] = kuavo::test::standing_configuration(), plan->foot_contact[i] = {true, true};
  ASSERT_EQ(motion_plan_finish(*plan), nullptr);
  BalanceFilterReport report;
  ASSERT_EQ(balance_filter(robot(), BalanceFilterConfig{}, *plan, *ws, report), nullptr);
  EXPECT_LT(report.max_correction_m, 1e-6);
  for (int i = 0; i < plan->frame_count; ++i) EXPECT_LT((plan->q[i] - kuavo::test::standing_configuration()).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(BalanceFilter, BringsAFastWeightShiftsZmpBackIntoTheSupportAndKeepsTheFeet) {
  auto plan = std::make_unique<MotionPlan>();
  auto ws = std::make_unique<BalanceFilterWorkspace>();
  StepInPlaceConfig cfg;
  cfg.steps = 4;
  cfg.shift_s = 0.35;  // far too fast for a quasi-static shift: the ZMP leaves the feet
  cfg.swing_s = 0.4;
  cfg.shift_fraction = 0.9;
  ASSERT_EQ(make_step_in_place(robot(), kuavo::test::standing_configuration(), cfg, *plan), nullptr);
  const double before = worst_zmp_outside(robot(), *plan);
  static dynamics::Data data;
  std::vector<std::array<Vec3, kNumPoints>> corners(plan->frame_count);
  PlanKnot knot;
  for (int i = 0; i < plan->frame_count; ++i) {
    plan_knot_from_state(robot(), data, plan->q[i], dynamics::VelocityVector::Zero(), {}, 0, knot);
    for (int c = 0; c < kNumPoints; ++c) corners[i][c] = knot.point_position_m.segment<3>(3 * c);
  }
  BalanceFilterReport report;
  ASSERT_EQ(balance_filter(robot(), BalanceFilterConfig{}, *plan, *ws, report), nullptr);
  const double after = worst_zmp_outside(robot(), *plan);
  std::printf("cart-table ZMP outside the support: before %.4f m, after %.4f m; correction up to %.4f m\n", before,
              after, report.max_correction_m);
  EXPECT_GT(before, 0.03);
  EXPECT_LT(after, 0.005);
  EXPECT_NEAR(after, report.zmp_outside_after_m, 1e-9);
  double moved = 0.0;
  for (int i = 0; i < plan->frame_count; ++i) {
    plan_knot_from_state(robot(), data, plan->q[i], dynamics::VelocityVector::Zero(), {}, 0, knot);
    for (int c = 0; c < kNumPoints; ++c) moved = std::max(moved, (knot.point_position_m.segment<3>(3 * c) - corners[i][c]).norm());
  }
  EXPECT_LT(moved, 1e-3);  // every corner keeps its path: stance feet stay planted
}

}  // namespace
}  // namespace kuavo::planner
