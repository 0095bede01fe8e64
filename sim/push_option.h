// The --push option of `kuavo simulate` and kuavo_fw_sim: "T:FX,FY,FZ:DURATION" (s, N, s),
// e.g. 5:100,0,0:0.1 is a 10 N·s forward push at t = 5 s. Every field is a whole number token
// (rtos_shim/args.h) inside a range a push on a 55 kg robot can mean:
//  - start 0..600 s (kMaxRunDuration_s, the longest run);
//  - each force component within ±2000 N (~4 body weights: harder is a collision, not a push);
//  - duration in (0, 10] s (longer is a constant force, not a push).
#pragma once

#include "sim/closed_loop.h"
#include "sim/plant.h"

namespace kuavo::sim {

inline constexpr double kPushMaxStart_s = kMaxRunDuration_s, kPushMaxForce_N = 2000.0, kPushMaxDuration_s = 10.0;
inline constexpr const char* kPushValueName =
    "T:FX,FY,FZ:DURATION (T in 0..600 s, forces within ±2000 N, DURATION in (0, 10] s)";

// false (out untouched) unless text is exactly that form within those ranges.
bool parse_push(const char* text, Push& out);

}  // namespace kuavo::sim
