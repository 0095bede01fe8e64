// Leg inverse kinematics on the sole corners: moves the 12 leg joints so three corners
// of each foot reach their world targets, base and the other joints as given
// (Gauss–Newton on the corners' Jacobians, ≤ 20 iterations). Used by the planner's motion
// generators and filters at start-up, and in the planning task by the recovery step
// (recovery_step.h): fixed-size, allocation-free, bounded. Returns the largest remaining
// corner error [m].
#pragma once

#include <array>

#include "controllers/planner/plan_knot.h"

namespace kuavo::planner {

double solve_leg_ik(const model::Model& model, dynamics::Data& data, const std::array<Vec3, kNumPoints>& targets,
                    dynamics::ConfigVector& q);

}  // namespace kuavo::planner
