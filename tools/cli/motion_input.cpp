#include "tools/cli/motion_input.h"

#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/standing/standing_controller.h"

namespace kuavo::cli {

bool filter_motion_plan(const model::Model& robot, planner::MotionPlan& plan, planner::BalanceFilterReport& report,
                        std::string& error) {
  auto ws = std::make_unique<planner::BalanceFilterWorkspace>();
  if (const char* why = planner::balance_filter(robot, planner::BalanceFilterConfig{}, plan, *ws, report)) {
    error = why;
    return false;
  }
  return true;
}

bool make_step_plan(const model::Model& robot, int steps, planner::MotionPlan& plan, std::string& error) {
  auto data = std::make_unique<dynamics::Data>();
  dynamics::ConfigVector q0 = dynamics::neutral_configuration(robot);
  q0.tail<model::kNumJoints>() = control::centred_standing_pose(robot, *data, control::StandingConfig{}.base_height_m);
  control::place_on_ground(robot, *data, q0);
  planner::StepInPlaceConfig cfg;
  cfg.steps = steps;
  if (const char* why = planner::make_step_in_place(robot, q0, cfg, plan)) {
    error = why;
    return false;
  }
  return true;
}

}  // namespace kuavo::cli
