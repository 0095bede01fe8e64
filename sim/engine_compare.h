// Where the two simulators disagree about one run (kuavo simulate --engine both): the same
// motion, controller, seed and sensors on our Simbody plant and on MuJoCo with Leju's MJCF.
// Neither is the truth; a motion that only one of them carries leans on that one's
// idealisations, and the summary says so in words.
#pragma once

#include <string>
#include <vector>

#include "sim/motion_loop.h"

namespace kuavo::sim {

// Named thresholds. Standing, the two plants agree to a millimetre (tests/sim/
// mujoco_plant_test); a dance's figures differ by more, from the contact laws alone
// (the built-in dance: legs' tracking RMS 0.019 vs 0.022 rad, 42 vs 41 lift-offs).
inline constexpr double kFallTimesApart_s = 1.0;     // both fell, this far apart
inline constexpr double kTrackingRatio = 1.5;        // legs' or arms' RMS tracking error, larger over smaller
inline constexpr double kTrackingFloor_rad = 0.02;   // ... once the larger is above this (below, both track well)
inline constexpr int kLiftOffsApart = 3;             // lift-offs counted (a step taken in one world only)

struct EngineComparison {
  bool agree = true;
  std::vector<std::string> disagreements;  // one sentence each
};

// For a --stand run, MotionSummary::run carries everything and the rest stays zero.
EngineComparison compare_engines(const MotionSummary& simbody, const MotionSummary& mujoco);

// {"engine": "both", "agree": ..., "disagreements": [...], "simbody": {...}, "mujoco": {...}};
// the two objects are the runs' own summaries.
std::string engine_comparison_json(const EngineComparison& c, const std::string& simbody_json,
                                   const std::string& mujoco_json);

}  // namespace kuavo::sim
