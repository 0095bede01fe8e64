#include "firmware/dance_motion.h"

#include <cmath>
#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/motion_plan_io.h"

namespace kuavo::firmware {

const char* dance_motion_start_standing(const model::Model& robot, dynamics::Data& data, planner::MotionPlan& plan) {
  if (plan.frame_count < 1) return "the motion has no frames";
  dynamics::forward_kinematics(robot, data, plan.q[0]);
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    if (std::abs(dynamics::frame_position(robot, data, c).z()) > kStartSoleHeight_m) {
      return "the first frame does not stand (a sole corner more than 1 cm off the ground); the robot dances from "
             "standing";
    }
  }
  plan.foot_contact[0] = {true, true};
  return nullptr;
}

bool load_dance_motion(const std::string& path, const model::Model& robot, bool balance_filter,
                       planner::MotionPlan& plan, planner::BalanceFilterReport& report, std::string& error) {
  // mocap's loader checks magic, version, both checksums, variant, layout, labels, length.
  if (!mocap::load_motion_plan(path, robot, plan, error)) return false;
  auto data = std::make_unique<dynamics::Data>();
  if (const char* why = dance_motion_start_standing(robot, *data, plan)) {
    error = path + ": " + why;
    return false;
  }
  report = planner::BalanceFilterReport{};
  if (!balance_filter) return true;
  auto ws = std::make_unique<planner::BalanceFilterWorkspace>();
  if (const char* why = planner::balance_filter(robot, planner::BalanceFilterConfig{}, plan, *ws, report)) {
    error = path + ": " + why;  // the filter's messages name it
    return false;
  }
  return true;
}

}  // namespace kuavo::firmware
