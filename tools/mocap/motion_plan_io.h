// From the offline pipeline's in-memory outputs to the controller's MotionPlan (allocates):
// frames and labels, or the built-in dance retargeted in memory. Used by the `kuavo` tool,
// tests and benchmarks. A motion *file* is loaded by the online code's one loader
// (controllers/motion/load_motion.h), as the firmware loads it.
#pragma once

#include <string>
#include <vector>

#include "controllers/planner/motion_plan.h"
#include "tools/mocap/contact_label.h"

namespace kuavo::mocap {

// Frames and contact labels (one per frame) → plan, with motion_plan_finish. false with a
// message (prefixed by `what`) when the motion is longer than the controller's capacity or
// motion_plan_finish refuses it.
bool motion_plan_from_frames(const std::vector<dynamics::ConfigVector>& q, const std::vector<ContactLabel>& labels,
                             double rate_hz, const std::string& what, planner::MotionPlan& plan, std::string& error);

// The built-in dance (default_dance.h) retargeted with the default options, exactly as
// `kuavo retarget` without an input file makes it (no balance filter). first_s > 0: only
// the dance's first first_s seconds (retargeted alone: a shorter test motion).
bool built_in_dance_plan(const model::Model& robot, planner::MotionPlan& plan, std::string& error,
                         double first_s = 0.0);

}  // namespace kuavo::mocap
