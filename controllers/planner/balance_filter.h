// Balance filter: makes a kinematic motion's CoM trajectory one the feet can carry.
//
// A retargeted dance moves the CoM as the human did; with the robot's mass distribution
// and feet, its zero-moment point (cart-table model: p = c − z_c/g·c̈) often leaves the
// support polygon during fast weight shifts and side steps, and the robot tips however
// well the WBC tracks. This is the classic ZMP preview problem (Kajita et al. 2003):
// per horizontal axis, a finite-horizon LQ tracking problem over the whole motion on the
// cart-table model (state [c, ċ, c̈], input jerk) whose ZMP follows a reference inside
// the support polygon — the motion's own CoM projected into the support of that frame,
// pulled in by a margin — while the CoM stays near the motion's. One backward Riccati
// pass and one forward rollout (3 states: exact, O(frames)). The base is then moved
// horizontally by the CoM correction and the legs re-solved so every foot corner keeps
// its world trajectory (stance feet stay planted; arms, head and orientation unchanged).
//
// It is the light, offline stand-in for the paper's dynamic retargeting: frames in
// flight get no ZMP target. Start-up only (not real-time); the workspace is ~1 MB.
#pragma once

#include "controllers/planner/motion_plan.h"

namespace kuavo::planner {

struct BalanceFilterConfig {
  double zmp_weight = 1.0;          // per m² of ZMP error
  double com_weight = 0.02;         // per m² of CoM deviation from the motion's CoM
  double jerk_weight = 1e-6;        // per (m/s³)²  (Kajita: Q = 1, R = 1e-6)
  double support_margin_m = 0.025;  // ZMP reference this far inside the support polygon's edge
  double max_correction_m = 0.25;   // a larger base shift means the motion is not balanceable
};

struct BalanceFilterReport {
  double max_correction_m = 0.0;         // largest horizontal base shift applied
  double zmp_outside_before_m = 0.0;     // worst cart-table ZMP distance outside the support, input motion
  double zmp_outside_after_m = 0.0;      // the same for the filtered motion
  int frames_in_flight = 0;
};

struct BalanceFilterWorkspace {
  std::array<std::array<double, 4>, kMaxMotionFrames> gain_x{}, gain_y{};  // [K (3), k] per frame
  std::array<Eigen::Vector2d, kMaxMotionFrames> com{}, zmp_ref{}, filtered_com{};
  std::array<bool, kMaxMotionFrames> has_support{};
  std::array<double, kMaxMotionFrames> com_height{};
  dynamics::Data data;
};

// Filters plan in place (its frames and velocities). Returns nullptr or what went wrong
// (IK missed a corner by more than 1 mm, or the correction exceeded max_correction_m).
const char* balance_filter(const model::Model& model, const BalanceFilterConfig& config, MotionPlan& plan,
                           BalanceFilterWorkspace& ws, BalanceFilterReport& report);

}  // namespace kuavo::planner
