// Offline leg inverse kinematics for the repair and the dynamic stage: three sole corners
// per foot onto world targets by moving that leg's 6 joints, base and other joints as given.
// Levenberg–Marquardt, each step projected onto the joints' position limits and kept only if
// it lowers the foot's error (controllers/planner/leg_ik is plain Gauss–Newton for start-up
// poses; near a straight knee it overshoots and, frame after frame, walks the joints off by
// multiples of 2π). A target out of reach ends at the nearest reachable pose within limits.
// Returns the largest remaining corner error [m] over the 8 corners; data then holds the
// base's and both legs' kinematics at the returned q (forward_kinematics_chain: enough for
// the corners' frame_position and frame_jacobian; the arms, head and inertias are stale).
// Offline; no allocation.
#pragma once

#include <array>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::mocap {

// JᵀJ of a foot's 9×6 corner Jacobian, bit for bit what Eigen 3.4's jac.transpose() * jac
// gives at -march=x86-64-v3 (6 + 6 + 9 ≥ 20 sends that product to its GEMM, whose blocking
// and packing took 29 % of the leg solve; this is 3.4× faster): the GEMM's fused
// multiply-add chains in its order, so the motions stay as they were. Not symmetric in its
// last bit: entry (i, j) takes column j's order. The test holds it to Eigen's product; should
// Eigen's order change, that test fails, and a plain chain (with the motions verified again)
// is the way out.
Eigen::Matrix<double, 6, 6> leg_jacobian_gram(const Eigen::Matrix<double, 9, 6>& jac);

double leg_ik_lm(const model::Model& robot, dynamics::Data& data,
                 const std::array<dynamics::Vec3, model::kNumContactPoints>& targets, dynamics::ConfigVector& q);

}  // namespace kuavo::mocap
