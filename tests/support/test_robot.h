// The robot most tests use: the s45 variant at the product-sheet mass, built once, and its
// centred standing configuration with the soles on the ground.
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/planner/motion_plan.h"
#include "controllers/standing/standing_controller.h"

namespace kuavo::test {

inline const model::Model& s45_robot() {
  static model::Model m;
  static const bool built = model::build_model(model::Variant::kS45, 55.0, m) == model::ModelError::kOk;
  EXPECT_TRUE(built);
  return m;
}

inline dynamics::ConfigVector standing_configuration() {
  static dynamics::Data data;
  dynamics::ConfigVector q = dynamics::neutral_configuration(s45_robot());
  q.tail<model::kNumJoints>() = control::centred_standing_pose(s45_robot(), data, 0.78);
  control::place_on_ground(s45_robot(), data, q);
  return q;
}

// The measured state (q, v) at t_ns as the planner's knot (planner::plan_knot_measured), as
// stack_plan_rt hands it to the recovery step, the plan anchor and the lift-off hold. One
// static knot shared by every call: valid until the next measured_knot call (do not hold the
// reference across calls or use two in one expression).
inline const planner::PlanKnot& measured_knot(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                                              hal::TimeNs t_ns) {
  static dynamics::Data data;
  static planner::PlanKnot knot;
  planner::plan_knot_measured(s45_robot(), data, q, v, t_ns, knot);
  return knot;
}

// Standing in standing_configuration(), both feet down, frame_count frames at rate_hz.
inline std::unique_ptr<planner::MotionPlan> standing_motion(double rate_hz, int frame_count) {
  auto m = std::make_unique<planner::MotionPlan>();
  m->rate_hz = rate_hz;
  m->frame_count = frame_count;
  for (int i = 0; i < m->frame_count; ++i) m->q[i] = standing_configuration(), m->foot_contact[i] = {true, true};
  EXPECT_EQ(planner::motion_plan_finish(*m), nullptr);
  return m;
}

// Standing 6 s at 100 Hz in standing_configuration(); the right foot up over [2.0, 2.4) s
// (the planner tests' one step).
inline std::unique_ptr<planner::MotionPlan> stepping_motion() {
  auto m = standing_motion(100.0, 600);
  for (int i = 200; i < 240; ++i) m->foot_contact[i][1] = false;
  EXPECT_EQ(planner::motion_plan_finish(*m), nullptr);
  return m;
}

}  // namespace kuavo::test
