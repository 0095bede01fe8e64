// Contact forces that produce a given motion (offline; allocates).
//
// The dynamic stage's last steps change its motion after the trajectory optimization: the
// stage trajectory (dt = 0.02 s) becomes 100 Hz frames by Catmull-Rom, and the legs are
// re-solved so that stance feet sit exactly on their footholds. The TO's forces then no longer
// produce the frames' accelerations (a base-wrench residual of 27 N on average, 860 N at a
// touchdown, for the built-in dance), and the torques the oracle computes with them carry
// that mismatch.
//
// For each frame, with q̇ and q̈ from the frames by the oracle's own differences
// (frame_rates), the forces f of the stance corners solve the small QP
//
//   minimize   ½ w_f ‖f − f_prior‖² + Σ (½ s_j² + c s_j)
//   subject to Σ J_c,baseᵀ f_c = RNEA_base(q, q̇, q̈)            (the motion's base wrench)
//              |f_x|, |f_y| ≤ μ f_z,  f_z ≥ 0                     (friction pyramids)
//              |τ_j| ≤ limit_j + s_j,  s_j ≥ 0                    (the twelve leg slots)
//
// with τ = RNEA_joints − J_cᵀf; the ankle slots are the two motors of each ankle, as the
// oracle counts them (drivers/transmission/ankle_motors.h). The slack's linear cost c is an
// exact penalty: a slack is non-zero only where no force within the cones holds every leg
// slot at its limit, i.e. where the motion itself needs more than the motors give (single
// support fixes the foot's wrench: nothing to redistribute). Double support's six free
// directions (how the two feet share the load) move the ankles' and knees' torques.
// A frame whose base wrench no forces within the cones supply (the motion needs a pull, or
// more friction than μ) keeps the prior's forces and is counted.
#pragma once

#include <vector>

#include "controllers/model/model.h"
#include "tools/mocap/contact_label.h"
#include "tools/mocap/dynamics_check.h"

namespace kuavo::mocap {

struct ContactForceStats {
  int frames = 0;
  int frames_infeasible = 0;  // no forces in the cones supply the base wrench: prior kept
  int frames_over_limit = 0;  // a leg slot beyond its limit whatever the distribution
  double max_excess_Nm = 0.0; // largest such excess (joint or motor torque)
};

// prior: one force vector per frame (the TO's); forces of swing corners are zero in the result.
void contact_forces_for_motion(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q,
                               const std::vector<ContactLabel>& contacts, double rate_hz,
                               double friction_coefficient, const std::vector<ForceVector>& prior,
                               std::vector<ForceVector>& out, ContactForceStats& stats);

}  // namespace kuavo::mocap
