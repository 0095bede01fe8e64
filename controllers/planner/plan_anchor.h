// Plan anchor: the motion's footholds re-anchored to where the stance foot measures
// (issue 20).
//
// The motion is a world-frame plan: the base, the CoM and every planted sole corner are fixed
// world points. The robot only knows its world position through the estimator, whose base
// drifts (leg odometry and IMU: +3.1 cm sideways by 8 s in the built-in dance's seed-39 show
// run), and the real feet land centimetres from the plan (a tile step, a push, a recovery
// step). The MPC holds its stance feet where they measure (no stance foothold gain online)
// but tracks the base and the CoM at the plan's world positions, so every centimetre of
// drift or of a foot landed off is a centimetre of CoM put beside the foot it stands on.
//
// What it does, once per planner call, on the window the MPC is about to track:
//   anchor foot  the foot the next single support in the window stands on (now, if the
//                motion is on one foot); with no single support in the window, both feet
//                down (their mean).
//   target       the anchor foot's in-contact corners: measured (kinematics of the state)
//                minus planned, horizontal, their mean. Only once the foot has been down in
//                the plan for settle_s (a touchdown is not measured before it has landed).
//   offset       moves to a target more than deadband_m from the one it is going to, in a
//                straight line over ramp_s; between re-anchorings it is constant, so the
//                MPC's reference cache (mpc.h) keeps its hits.
//   shift        every knot's base, CoM and sole corners move by the offset (velocities,
//                joints and contact flags unchanged): the dance goes on relative to the
//                foot the robot stands on, and the next swing lands where the plan has it
//                relative to that foot.
//   home         (home_share β > 0) the target is (1 − β) of the measured error: β of it is
//                left for the MPC to pull back towards the motion's place on the stage
//                (several robots share it). Without it the robot's place walks with every
//                foot it sets down off the plan (the built-in dance on the floor, nominal
//                plant: 9 cm to the left by 28 s, a centimetre or two a step, always the same
//                way); the price is β of the error back between the CoM and the stance foot.
// A target beyond max_offset_m is not followed (the offset stays; the calls that met one are
// counted in `refused`). A recovery step (recovery_step.h) runs before this and aims its
// landing at a measured point: it takes the offset off (recovery_step_rt's plan_offset).
//
// On by default (`kuavo simulate --plan-anchor off` for the world footholds). Measured (show
// campaign: carpet, `show` set, one 10 N·s push; the built-in dance, seeds 1–100): without it
// 1/100 (seed 39: the +3.1 cm estimate drift and a 1.8° tilt put the CoM beside the stance
// foot); with it, β = 0, 0/100 but the robot's CoM ends up a median 0.20 m (p90 0.31) from the
// motion's, against 0.08 (0.14) without; β = 0.3, 0/100 and 0.10 (0.17). Perfume (seeds 1–60)
// with β = 0: 22/60 as without it (its falls are its last single support drifting sideways).
// The whole ctest suite passes with it on (719 tests).
//
// Real-time: fixed-size state, no allocation; no kinematics of its own (it reads the measured
// knot stack_plan_rt computes once per call).
#pragma once

#include <cstdint>

#include "controllers/planner/plan_knot.h"

namespace kuavo::planner {

struct PlanAnchorConfig {
  bool enabled = true;
  double settle_s = 0.06;      // a foot planned down this long counts as landed
  double deadband_m = 0.005;   // re-anchor when the target moved this far
  double ramp_s = 0.20;        // the offset goes to a new target over this long
  double max_offset_m = 0.25;  // targets farther than this are refused (counted)
  double home_share = 0.3;     // β: the share of the measured error left to pull back
};

// nullptr if usable, else what is wrong. Load time.
const char* plan_anchor_validate(const PlanAnchorConfig& config);

struct PlanAnchorState {
  bool started = false;
  hal::TimeNs last_call_ns = 0;
  std::array<double, 2> down_s{};  // how long each foot has been planned down (window knot 0)
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();  // applied this call
  Eigen::Vector2d from = Eigen::Vector2d::Zero();    // the ramp's start …
  Eigen::Vector2d to = Eigen::Vector2d::Zero();      // … and end
  hal::TimeNs ramp_start_ns = 0;
  std::uint64_t reanchors = 0;  // targets taken
  std::uint64_t refused = 0;    // calls whose target was beyond max_offset_m
  double offset_max_m = 0.0;    // largest |offset| applied since the reset
};

void plan_anchor_reset(PlanAnchorState& state);

// Shifts window (its knot 0 at t_ns) by the anchor's offset. measured: the measured state at
// t_ns as a knot (plan_knot_measured). Disabled: the window is left as it is. Real-time safe.
void plan_anchor_rt(const PlanAnchorConfig& config, PlanAnchorState& state, const PlanKnot& measured,
                    hal::TimeNs t_ns, PlanWindow& window);

}  // namespace kuavo::planner
