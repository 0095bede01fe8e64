#include "firmware/dance_motion.h"

#include <cmath>
#include <memory>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/motion_file.h"

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

bool load_dance_motion(const std::string& path, const model::Model& robot, planner::MotionPlan& plan,
                       planner::BalanceFilterReport& report, std::string& error) {
  // mocap's loader checks magic, version, both checksums, variant, layout and labels.
  mocap::MotionHeader header;
  std::vector<dynamics::ConfigVector> q;
  std::vector<mocap::ContactLabel> labels;
  if (!mocap::load_motion_file(path, robot, header, q, labels, error)) return false;
  if (q.size() < 2 || q.size() > static_cast<std::size_t>(planner::kMaxMotionFrames)) {
    error = path + ": " + std::to_string(q.size()) + " frames; the dance needs 2 to " +
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
  auto data = std::make_unique<dynamics::Data>();
  if (const char* why = dance_motion_start_standing(robot, *data, plan)) {
    error = path + ": " + why;
    return false;
  }
  if (const char* why = planner::motion_plan_finish(plan)) {
    error = path + ": " + why;
    return false;
  }
  auto ws = std::make_unique<planner::BalanceFilterWorkspace>();
  if (const char* why = planner::balance_filter(robot, planner::BalanceFilterConfig{}, plan, *ws, report)) {
    error = path + ": " + why;  // the filter's messages name it
    return false;
  }
  return true;
}

}  // namespace kuavo::firmware
