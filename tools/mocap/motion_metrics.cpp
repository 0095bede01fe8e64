#include "tools/mocap/motion_metrics.h"

#include <algorithm>
#include <memory>

#include "tools/mocap/dynamics_check.h"
#include "tools/mocap/feasibility_repair.h"

namespace kuavo::mocap {

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
  Vec3 com_prev = Vec3::Zero();
  for (int i = 0; i < n; ++i) {
    dynamics::forward_kinematics(robot, *data, q[i]);
    dynamics::crba(robot, *data);
    const Vec3 com = data->com_m;
    if (i > 0) out.com_path_m += (com - com_prev).norm();
    com_prev = com;
    const int d = i - first_frame;
    if (d < 0 || d >= static_cast<int>(targets.frames.size())) continue;
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
