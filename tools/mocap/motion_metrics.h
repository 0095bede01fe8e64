// Expressiveness of a robot motion against the human it came from: what the report puts
// beside each stage so a repair or an optimization that trades the dance away shows.
#pragma once

#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/contact_label.h"
#include "tools/mocap/human_targets.h"

namespace kuavo::mocap {

struct MotionMetrics {
  // Keypoint position error against the human targets [m]: mean and max per group.
  double hands_mean_m = 0.0, hands_max_m = 0.0;
  double feet_mean_m = 0.0, feet_max_m = 0.0;
  double pelvis_mean_m = 0.0, pelvis_max_m = 0.0;
  // Mean |q̇| per limb group over the frames [rad/s].
  double legs_speed_rad_s = 0.0, arms_speed_rad_s = 0.0, head_speed_rad_s = 0.0;
  double com_path_m = 0.0;  // length of the CoM path (3D)
  int steps = 0;            // swing phases of the contact labels
  double duration_s = 0.0;
};

// The CoM of every frame (forward kinematics and the bodies' masses), world axes [m].
std::vector<dynamics::Vec3> com_trajectory(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q);

// Length of the polyline through p[a] … p[b] (indices clamped to p; 0 if the range is empty
// after clamping). Additive: path_length(p, a, m) + path_length(p, m, b) = path_length(p, a, b).
double path_length(const std::vector<dynamics::Vec3>& p, int a, int b);

// q[first_frame + d] shows targets.frames[d] (first_frame: the frames the motion adds in
// front, e.g. a lead-in). Keypoint errors over the overlap; speeds, CoM path and steps over
// all frames.
void motion_metrics(const model::Model& robot, const HumanTargets& targets, const std::vector<dynamics::ConfigVector>& q,
                    const std::vector<ContactLabel>& contacts, double rate_hz, int first_frame, MotionMetrics& out);

}  // namespace kuavo::mocap
