#include "tools/cli/motion_input.h"

#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/standing/standing_controller.h"
#include "tools/mocap/motion_file.h"

namespace kuavo::cli {

bool load_motion_plan(const std::string& path, const model::Model& robot, planner::MotionPlan& plan, std::string& error) {
  mocap::MotionHeader header;
  std::vector<dynamics::ConfigVector> q;
  std::vector<mocap::ContactLabel> labels;
  if (!mocap::load_motion_file(path, robot, header, q, labels, error)) return false;
  if (q.size() > static_cast<std::size_t>(planner::kMaxMotionFrames)) {
    error = path + ": " + std::to_string(q.size()) + " frames, more than the controller's capacity of " +
            std::to_string(planner::kMaxMotionFrames);
    return false;
  }
  plan.rate_hz = header.rate_hz;
  plan.frame_count = static_cast<int>(q.size());
  plan.start_ns = 0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    plan.q[i] = q[i];
    plan.foot_contact[i] = {mocap::left_in_contact(labels[i]), mocap::right_in_contact(labels[i])};
  }
  if (const char* why = planner::motion_plan_finish(plan)) {
    error = path + ": " + why;
    return false;
  }
  return true;
}

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
