// What `kuavo simulate` and `kuavo demo` play: a motion file, or the built-in
// step-in-place gait, as a planner::MotionPlan (allocated once, before the loop).
#pragma once

#include <memory>
#include <string>

#include "controllers/planner/balance_filter.h"
#include "controllers/planner/motion_plan.h"

namespace kuavo::cli {

// Reads and validates a motion file (variant, layout, checksums, frames) into plan.
// false with a message naming the file and the problem.
bool load_motion_plan(const std::string& path, const model::Model& robot, planner::MotionPlan& plan, std::string& error);

// The balance filter (controllers/planner/balance_filter.h) over a loaded plan; prints
// nothing, fills report. false with a message when the motion cannot be balanced.
bool filter_motion_plan(const model::Model& robot, planner::MotionPlan& plan, planner::BalanceFilterReport& report,
                        std::string& error);

// The step-in-place gait from the centred standing pose.
bool make_step_plan(const model::Model& robot, int steps, planner::MotionPlan& plan, std::string& error);

}  // namespace kuavo::cli
