#include "tools/mocap/motion_metrics.h"

#include <algorithm>
#include <memory>

#include "tools/mocap/dynamics_check.h"
#include "tools/mocap/feasibility_repair.h"

namespace kuavo::mocap {

std::vector<dynamics::Vec3> com_trajectory(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q) {
  std::vector<dynamics::Vec3> out;
  out.reserve(q.size());
  auto data = std::make_unique<dynamics::Data>();
  for (const dynamics::ConfigVector& qi : q) {
    dynamics::forward_kinematics(robot, *data, qi);
    dynamics::crba(robot, *data);
    out.push_back(data->com_m);
  }
  return out;
}

double path_length(const std::vector<dynamics::Vec3>& p, int a, int b) {
  a = std::max(a, 0);
  b = std::min(b, static_cast<int>(p.size()) - 1);
  double length = 0.0;
  for (int i = a + 1; i <= b; ++i) length += (p[i] - p[i - 1]).norm();
  return length;
}

void motion_metrics(const model::Model& robot, const HumanTargets& targets, const std::vector<dynamics::ConfigVector>& q,
                    const std::vector<ContactLabel>& contacts, double rate_hz, int first_frame, MotionMetrics& out) {
  out = MotionMetrics{};
  const int n = static_cast<int>(q.size());
  if (n == 0) return;
  const auto keypoints = robot_keypoints(robot);
  auto data = std::make_unique<dynamics::Data>();
  const auto point = [&](int kp) {
    const RobotKeypoint& k = keypoints[kp];
    return Vec3(data->position_m[k.body] + data->rotation[k.body] * k.point_m);
  };
  struct Acc {
    double sum = 0.0, max = 0.0;
    int count = 0;
    void add(double e) {
      sum += e;
      max = std::max(max, e);
      ++count;
    }
    double mean() const { return count ? sum / count : 0.0; }
  } hands, feet, pelvis;
  const int kp_hands[] = {kKpLeftHand, kKpRightHand};
  const int kp_feet[] = {kKpLeftAnkle, kKpRightAnkle};
  out.com_path_m = path_length(com_trajectory(robot, q), 0, n - 1);
  for (int i = 0; i < n; ++i) {
    const int d = i - first_frame;
    if (d < 0 || d >= static_cast<int>(targets.frames.size())) continue;
    dynamics::forward_kinematics(robot, *data, q[i]);
    const TargetFrame& t = targets.frames[d];
    for (int kp : kp_hands) {
      if (targets.present[kp]) hands.add((point(kp) - t.position_m[kp]).norm());
    }
    for (int kp : kp_feet) feet.add((point(kp) - t.position_m[kp]).norm());
    const Vec3 hip_mid = 0.5 * (point(kKpLeftHip) + point(kKpRightHip));
    pelvis.add((hip_mid - t.position_m[kKpPelvis]).norm());
  }
  out.hands_mean_m = hands.mean(), out.hands_max_m = hands.max;
  out.feet_mean_m = feet.mean(), out.feet_max_m = feet.max;
  out.pelvis_mean_m = pelvis.mean(), out.pelvis_max_m = pelvis.max;
  std::vector<dynamics::VelocityVector> v, a;
  frame_rates(q, rate_hz, v, a);
  for (int i = 0; i < n; ++i) {
    out.legs_speed_rad_s += v[i].segment<2 * model::kLegJoints>(6).cwiseAbs().mean();
    out.arms_speed_rad_s += v[i].segment<2 * model::kArmJoints>(6 + 2 * model::kLegJoints).cwiseAbs().mean();
    out.head_speed_rad_s += v[i].tail<2>().cwiseAbs().mean();
  }
  out.legs_speed_rad_s /= n;
  out.arms_speed_rad_s /= n;
  out.head_speed_rad_s /= n;
  out.steps = count_steps(contacts);
  out.duration_s = (n - 1) / rate_hz;
}

}  // namespace kuavo::mocap
