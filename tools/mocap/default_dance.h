// The built-in default dance: a procedural, deterministic human dance written as BVH, used
// when `kuavo retarget` (and the main job) get no input file.
//
// One 30 s cycle at 50 fps on a 1.75 m CMU-named skeleton (cm, Y up, facing +Z): a
// weight-shifting intro with arm swings, side steps with arm raises, forward/back strides with
// opposite arm swings, a hip sway with knee bounces and arms overhead, a 360° stepping turn with
// arms out, side steps with arm pumps, and a settle. Feet follow a footstep plan (stance feet
// never slide, swing feet lift 6 cm); legs come from analytic two-link IK, so the clip obeys the
// same contact physics a capture would.
//
// A cycle ends where it began (the same footholds, heading a whole turn on, pelvis and sway
// where they started), so a longer dance repeats it: at each seam the settle's arms cross-fade
// into the intro's over 0.4 s centred on the seam (the phases' own fade time); nothing else
// differs from the first cycle. One cycle is the dance
// every figure is made with; `kuavo retarget --duration S` makes longer ones (4 min: 8 cycles).
#pragma once

#include <string>

#include "tools/mocap/bvh.h"

namespace kuavo::mocap {

inline constexpr double kDefaultDanceDuration_s = 30.0;  // one cycle
inline constexpr double kDefaultDanceRate_hz = 50.0;
// Longest built-in dance: 10 cycles = 5 min, the controller's capacity (planner::kMaxMotionFrames
// holds 5 min at 100 Hz plus the dynamic stage's lead-in and tail).
inline constexpr int kDefaultDanceMaxCycles = 10;

// cycles in 1..kDefaultDanceMaxCycles (clamped): kDefaultDanceDuration_s × cycles.
Bvh default_dance_bvh(int cycles = 1);
std::string default_dance_bvh_text();

// The cycles that make duration_s, or 0 when it is not a whole number of cycles in
// 1..kDefaultDanceMaxCycles (within 1 ms).
int default_dance_cycles(double duration_s);

}  // namespace kuavo::mocap
