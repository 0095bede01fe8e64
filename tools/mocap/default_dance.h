// The built-in default dance: a procedural, deterministic human dance written as BVH, used
// when `kuavo retarget` (and the main job) get no input file.
//
// 30 s at 50 fps on a 1.75 m CMU-named skeleton (cm, Y up, facing +Z): a weight-shifting
// intro with arm swings, side steps with arm raises, forward/back strides with opposite arm
// swings, a hip sway with knee bounces and arms overhead, a 360° stepping turn with arms out,
// side steps with arm pumps, and a settle. Feet follow a footstep plan (stance feet never
// slide, swing feet lift 6 cm); legs come from analytic two-link IK, so the clip obeys the
// same contact physics a capture would.
#pragma once

#include <string>

#include "tools/mocap/bvh.h"

namespace kuavo::mocap {

inline constexpr double kDefaultDanceDuration_s = 30.0;
inline constexpr double kDefaultDanceRate_hz = 50.0;

Bvh default_dance_bvh();
std::string default_dance_bvh_text();

}  // namespace kuavo::mocap
