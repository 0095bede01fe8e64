// A whole-body motion to follow (the retargeted dance, a gait): frames of q at a fixed
// rate with per-foot contact, their velocities, and real-time sampling into PlanKnots.
//
// Loaded and finished once, before the loop (motion_plan_finish: checks and central-
// difference velocities); motion_plan_sample_rt / motion_plan_window_rt then run in the
// planner and control tasks. ~6.6 MB at capacity: static storage (or one block allocated
// at start-up), never a stack.
#pragma once

#include <array>

#include "controllers/planner/plan_knot.h"

namespace kuavo::planner {

inline constexpr int kMaxMotionFrames = 12000;  // 2 min at 100 Hz (the clips: 12–46 s)
inline constexpr int kLeftFoot = 0, kRightFoot = 1;
// Sole corners 0..3 are the left foot's, 4..7 the right foot's (model tables).
inline constexpr int kCornersPerFoot = kNumPoints / 2;

struct MotionPlan {
  double rate_hz = 100.0;
  int frame_count = 0;
  hal::TimeNs start_ns = 0;  // the instant frame 0 is due
  std::array<dynamics::ConfigVector, kMaxMotionFrames> q{};
  std::array<dynamics::VelocityVector, kMaxMotionFrames> v{};  // motion_plan_finish fills these
  std::array<std::array<bool, 2>, kMaxMotionFrames> foot_contact{};  // [left, right]
};

// Start-up: validates the frames (count, rate, finite values, unit quaternions) and
// computes velocities by central differences (one-sided at the ends; zero at the two
// end frames, where the motion starts and ends at rest). Returns nullptr or what is wrong.
const char* motion_plan_finish(MotionPlan& plan);

double motion_plan_duration_s(const MotionPlan& plan);

// The knot at absolute time t_ns: q interpolated between the neighbouring frames
// (joints and base position linearly, orientation by slerp), v linearly; before the
// start the first frame, after the end the last, both at rest. Contact flags of the
// earlier frame. data is scratch. Real-time safe.
void motion_plan_sample_rt(const model::Model& model, dynamics::Data& data, const MotionPlan& plan, hal::TimeNs t_ns,
                           PlanKnot& knot);

// count knots from t0_ns every dt_s (count ≤ kMaxWindowKnots). Real-time safe.
void motion_plan_window_rt(const model::Model& model, dynamics::Data& data, const MotionPlan& plan, hal::TimeNs t0_ns,
                           double dt_s, int count, PlanWindow& window);

}  // namespace kuavo::planner
