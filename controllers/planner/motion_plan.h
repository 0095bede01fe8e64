// A whole-body motion to follow (the retargeted dance, a gait): frames of q at a fixed
// rate with per-foot contact, and real-time sampling into PlanKnots.
//
// Loaded and checked once, before the loop (motion_plan_finish); motion_plan_sample_rt /
// motion_plan_window_rt then run in the planner and control tasks. Layout: per frame q as
// the file stores it (35 doubles, 280 B) and the two contact flags (2 B), 282 B a frame; the
// velocities (34 doubles, which doubled the footprint when stored) are the central
// differences of q, made where a sample needs them (motion_plan_velocity: two quaternion
// differences, far less than the forward kinematics of the knot the sample feeds).
// 8.74 MB at capacity: static storage (or one block allocated at start-up), never a stack.
#pragma once

#include <array>

#include "controllers/planner/plan_knot.h"

namespace kuavo::planner {

// 5 min of dance at 100 Hz plus 10 s for what `kuavo retarget`'s dynamic stage adds around
// it (lead-in 0.8 s, blend 1.0 s, tail 1.0 s: feasibility_repair.h); the clips: 12–46 s.
inline constexpr int kMaxMotionFrames = 31000;
inline constexpr int kLeftFoot = 0, kRightFoot = 1;
// Sole corners 0..3 are the left foot's, 4..7 the right foot's (model tables).
inline constexpr int kCornersPerFoot = kNumPoints / 2;

struct MotionPlan {
  double rate_hz = 100.0;
  int frame_count = 0;
  hal::TimeNs start_ns = 0;  // the instant frame 0 is due
  std::array<dynamics::ConfigVector, kMaxMotionFrames> q{};
  std::array<std::array<bool, 2>, kMaxMotionFrames> foot_contact{};  // [left, right]
};
// The budget the robot image is sized for (firmware/README.md, memory): 282 B a frame.
inline constexpr std::size_t kMotionPlanBudget_bytes = 8'750'000;
static_assert(sizeof(MotionPlan) <= kMotionPlanBudget_bytes, "MotionPlan outgrew its memory budget");

// Start-up: validates the frames (count, rate, finite values, unit quaternions). Returns
// nullptr or what is wrong.
const char* motion_plan_finish(const MotionPlan& plan);

// Velocity of frame i (conventions.h): the central difference of its neighbours; zero at
// the two end frames, where the motion starts and ends at rest. Real-time safe.
dynamics::VelocityVector motion_plan_velocity(const MotionPlan& plan, int i);

double motion_plan_duration_s(const MotionPlan& plan);

// The frame a sample at t_ns takes its contact flags from (the frame at or before t_ns;
// 0 before the start, the last after the end). Real-time safe.
int motion_plan_frame_at(const MotionPlan& plan, hal::TimeNs t_ns);

// The instant frame i is due (start_ns + i / rate). Real-time safe.
hal::TimeNs motion_plan_frame_time(const MotionPlan& plan, int i);

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
