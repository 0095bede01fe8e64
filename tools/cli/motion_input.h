// What `kuavo simulate` and `kuavo demo` play besides a motion file (which the online loader,
// controllers/motion/load_motion.h, reads as the firmware does): the built-in step-in-place
// gait, and the balance filter over it, as a planner::MotionPlan (allocated once, before the loop).
#pragma once

#include <memory>
#include <string>

#include "controllers/planner/balance_filter.h"
#include "controllers/planner/motion_plan.h"

namespace kuavo::cli {

// The balance filter (controllers/planner/balance_filter.h) over a loaded plan; prints
// nothing, fills report. false with a message when the motion cannot be balanced.
bool filter_motion_plan(const model::Model& robot, planner::MotionPlan& plan, planner::BalanceFilterReport& report,
                        std::string& error);

// The step-in-place gait from the centred standing pose.
bool make_step_plan(const model::Model& robot, int steps, planner::MotionPlan& plan, std::string& error);

}  // namespace kuavo::cli
