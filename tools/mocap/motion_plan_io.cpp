#include "tools/mocap/motion_plan_io.h"

#include <cmath>

#include "tools/mocap/contacts.h"
#include "tools/mocap/default_dance.h"
#include "tools/mocap/human_targets.h"
#include "tools/mocap/retarget.h"
#include "tools/mocap/skeleton_map.h"

namespace kuavo::mocap {

bool motion_plan_from_frames(const std::vector<dynamics::ConfigVector>& q, const std::vector<ContactLabel>& labels,
                             double rate_hz, const std::string& what, planner::MotionPlan& plan, std::string& error) {
  if (q.size() != labels.size()) {
    error = what + ": " + std::to_string(q.size()) + " frames but " + std::to_string(labels.size()) + " contact labels";
    return false;
  }
  if (q.size() > static_cast<std::size_t>(planner::kMaxMotionFrames)) {
    error = what + ": " + std::to_string(q.size()) + " frames, more than the controller's capacity of " +
            std::to_string(planner::kMaxMotionFrames);
    return false;
  }
  plan.rate_hz = rate_hz;
  plan.frame_count = static_cast<int>(q.size());
  plan.start_ns = 0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    plan.q[i] = q[i];
    plan.foot_contact[i] = {left_in_contact(labels[i]), right_in_contact(labels[i])};
  }
  if (const char* why = planner::motion_plan_finish(plan)) {
    error = what + ": " + why;
    return false;
  }
  return true;
}

bool built_in_dance_plan(const model::Model& robot, planner::MotionPlan& plan, std::string& error, double first_s) {
  const Bvh bvh = default_dance_bvh();
  SkeletonMap map;
  if (!map_skeleton(bvh, map, error)) return false;
  HumanTargets targets;
  if (!make_targets(bvh, map, robot, {}, targets, error)) return false;
  if (first_s > 0.0) {
    const auto frames = static_cast<std::size_t>(std::llround(first_s * targets.rate_hz)) + 1;
    if (frames < targets.frames.size()) targets.frames.resize(frames);
  }
  const std::vector<ContactLabel> labels = detect_contacts(targets, robot);
  RetargetResult result;
  retarget_motion(robot, targets, labels, RetargetOptions{}, result);
  return motion_plan_from_frames(result.q, result.contacts, targets.rate_hz, "built-in dance", plan, error);
}

}  // namespace kuavo::mocap
