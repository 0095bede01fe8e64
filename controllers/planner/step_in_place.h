// A procedural gait: stepping in place, written as a MotionPlan so it runs through the
// same planner path as a dance. Quasi-static: in double support the base shifts over
// the next stance foot, then the other foot lifts and comes down where it was. Legs by
// Gauss–Newton inverse kinematics on the sole corners (arms, head and base orientation
// held). Start-up only (not real-time).
#pragma once

#include "controllers/planner/motion_plan.h"

namespace kuavo::planner {

struct StepInPlaceConfig {
  int steps = 20;             // swing phases, alternating, the left foot first
  double rate_hz = 100.0;
  double lead_in_s = 1.0;     // standing still before the first shift
  // Double support: the base moves to the next stance side on a minimum-jerk profile.
  // The plan is kinematic, so its CoM acceleration a needs a ZMP offset z/g·a that the
  // feet can carry: 1 s for the ~0.11 m shift peaks at 0.64 m/s² → 5 cm.
  double shift_s = 1.0;
  double swing_s = 0.6;       // single support: the other foot lifts and lands
  double lift_m = 0.05;       // swing-foot apex height
  double shift_fraction = 0.75;  // base shift as a fraction of the foot's lateral offset
  double tail_s = 1.0;        // standing still after returning to the centre
};

// q_stand: the standing configuration (feet flat on the ground). Fills plan (frames,
// contact, velocities via motion_plan_finish). Returns nullptr or what went wrong
// (bad config, too long, IK did not reach the foot targets within 1 mm).
const char* make_step_in_place(const model::Model& model, const dynamics::ConfigVector& q_stand,
                               const StepInPlaceConfig& config, MotionPlan& plan);

}  // namespace kuavo::planner
