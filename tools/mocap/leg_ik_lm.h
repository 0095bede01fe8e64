// Offline leg inverse kinematics for the repair and the dynamic stage: three sole corners
// per foot onto world targets by moving that leg's 6 joints, base and other joints as given.
// Levenberg–Marquardt, each step projected onto the joints' position limits and kept only if
// it lowers the foot's error (controllers/planner/leg_ik is plain Gauss–Newton for start-up
// poses; near a straight knee it overshoots and, frame after frame, walks the joints off by
// multiples of 2π). A target out of reach ends at the nearest reachable pose within limits.
// Returns the largest remaining corner error [m] over the 8 corners; data then holds the
// forward kinematics of the returned q. Offline; no allocation.
#pragma once

#include <array>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::mocap {

double leg_ik_lm(const model::Model& robot, dynamics::Data& data,
                 const std::array<dynamics::Vec3, model::kNumContactPoints>& targets, dynamics::ConfigVector& q);

}  // namespace kuavo::mocap
