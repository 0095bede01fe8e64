// From the offline pipeline's outputs to the controller's MotionPlan (start-up, allocates):
// a motion file as `kuavo retarget` writes it, or the built-in dance retargeted in memory.
// Used by the `kuavo` tool, the firmware image (`kuavo_fw --dance`), tests and benchmarks.
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

// Reads and validates a motion file (variant, layout, checksums, frames) into plan.
// false with a message naming the file and the problem.
bool load_motion_plan(const std::string& path, const model::Model& robot, planner::MotionPlan& plan, std::string& error);

// The built-in dance (default_dance.h) retargeted with the default options, exactly as
// `kuavo retarget` without an input file makes it (no balance filter). first_s > 0: only
// the dance's first first_s seconds (retargeted alone: a shorter test motion).
bool built_in_dance_plan(const model::Model& robot, planner::MotionPlan& plan, std::string& error,
                         double first_s = 0.0);

}  // namespace kuavo::mocap
