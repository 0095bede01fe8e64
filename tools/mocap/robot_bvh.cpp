#include "tools/mocap/robot_bvh.h"

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "tools/mocap/human_targets.h"

namespace kuavo::mocap {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// Robot axes (x forward, y left, z up) → BVH axes (X left, Y up, Z forward).
Mat3 robot_to_bvh() {
  Mat3 p;
  p << 0, 1, 0,  //
      0, 0, 1,   //
      1, 0, 0;
  return p;
}

}  // namespace

Bvh robot_bvh(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q, double frame_time_s,
              double units_per_m) {
  const Mat3 p = robot_to_bvh();
  const auto kps = robot_keypoints(robot);
  Bvh b;
  // Body → BVH joint index; End Sites after the leaf bodies they belong to.
  std::vector<int> joint_of_body(model::kNumBodies, -1);
  const auto end_site_point = [&](int body, Vec3& point) {
    for (int k : {kKpLeftToe, kKpRightToe, kKpLeftHand, kKpRightHand, kKpHead})
      if (kps[k].body == body) {
        point = kps[k].point_m;
        return true;
      }
    return false;
  };
  for (int body = 0; body < model::kNumBodies; ++body) {
    BvhJoint j;
    j.name = robot.tables->bodies[body].link_name;
    j.parent = body == 0 ? -1 : joint_of_body[robot.bodies[body].parent];
    j.offset = body == 0 ? Vec3::Zero() : Vec3(units_per_m * (p * robot.bodies[body].joint_position_m));
    if (body == 0) {
      j.channels = {BvhChannel::kXposition, BvhChannel::kYposition, BvhChannel::kZposition,
                    BvhChannel::kZrotation, BvhChannel::kXrotation, BvhChannel::kYrotation};
    } else {
      j.channels = {BvhChannel::kZrotation, BvhChannel::kXrotation, BvhChannel::kYrotation};
    }
    j.first_column = b.channel_count;
    b.channel_count += static_cast<int>(j.channels.size());
    joint_of_body[body] = static_cast<int>(b.joints.size());
    b.joints.push_back(j);
    Vec3 point;
    if (end_site_point(body, point)) {
      BvhJoint e;
      e.name = j.name + "_End";
      e.parent = joint_of_body[body];
      e.end_site = true;
      e.offset = units_per_m * (p * point);
      b.joints.push_back(e);
    }
    // Thumbs and heels: a channel-less joint on the hand / foot link (with its own End Site).
    for (int k : {kKpLeftThumb, kKpRightThumb, kKpLeftHeel, kKpRightHeel}) {
      if (kps[k].body != body) continue;
      BvhJoint t;
      constexpr const char* kNames[] = {"zarm_l7_thumb", "zarm_r7_thumb", "leg_l6_heel", "leg_r6_heel"};
      t.name = kNames[k - kKpLeftThumb];
      t.parent = joint_of_body[body];
      t.offset = units_per_m * (p * kps[k].point_m);
      t.first_column = b.channel_count;
      b.joints.push_back(t);
      BvhJoint e;
      e.name = t.name + "_End";
      e.parent = static_cast<int>(b.joints.size()) - 1;
      e.end_site = true;
      e.offset = units_per_m * Vec3(0, -0.02, 0);
      b.joints.push_back(e);
    }
  }
  b.frame_count = static_cast<int>(q.size());
  b.frame_time_s = frame_time_s;
  b.motion.assign(static_cast<std::size_t>(b.frame_count) * b.channel_count, 0.0);
  for (int f = 0; f < b.frame_count; ++f) {
    double* row = b.motion.data() + static_cast<std::size_t>(f) * b.channel_count;
    const Vec3 pos = units_per_m * (p * q[f].head<3>());
    const Eigen::Quaterniond quat(q[f][6], q[f][3], q[f][4], q[f][5]);
    const Mat3 r = p * quat.toRotationMatrix() * p.transpose();
    const Vec3 euler = r.eulerAngles(2, 0, 1);  // R = Rz·Rx·Ry, the root's channel order
    row[0] = pos.x();
    row[1] = pos.y();
    row[2] = pos.z();
    row[3] = euler[0] * kRadToDeg;
    row[4] = euler[1] * kRadToDeg;
    row[5] = euler[2] * kRadToDeg;
    for (int body = 1; body < model::kNumBodies; ++body) {
      // The joint axis is a signed unit axis of the robot; in BVH axes it is ±X, ±Y or ±Z.
      const Vec3 axis = p * robot.bodies[body].axis;
      int a = 0;
      axis.cwiseAbs().maxCoeff(&a);
      const double angle_deg = q[f][6 + body] * (axis[a] > 0 ? 1.0 : -1.0) * kRadToDeg;
      const int column = b.joints[joint_of_body[body]].first_column;
      // Channels are Z, X, Y: column offsets 0, 1, 2 for BVH axes Z, X, Y.
      const int slot = a == 2 ? 0 : (a == 0 ? 1 : 2);
      row[column + slot] = angle_deg;
    }
  }
  return b;
}

std::vector<dynamics::ConfigVector> robot_test_motion(const model::Model& robot, int frames, double rate_hz) {
  std::vector<dynamics::ConfigVector> out(static_cast<std::size_t>(frames));
  const double two_pi = 2.0 * 3.14159265358979323846;
  for (int f = 0; f < frames; ++f) {
    const double t = f / rate_hz;
    dynamics::ConfigVector& q = out[f];
    q.setZero();
    const double yaw = 0.6 * (1.0 - std::cos(0.4 * t));  // starts at 0, turns ~70° and back
    const Eigen::Quaterniond quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()) *
                                  Eigen::AngleAxisd(0.08 * std::sin(0.9 * t), Vec3::UnitY()) *
                                  Eigen::AngleAxisd(0.05 * std::sin(0.7 * t), Vec3::UnitX()));
    q[0] = 0.3 * std::sin(0.5 * t);
    q[1] = 0.2 * std::sin(0.3 * t);
    q[2] = 1.2 + 0.05 * std::sin(1.1 * t);  // well above the ground: no contact
    q[3] = quat.x();
    q[4] = quat.y();
    q[5] = quat.z();
    q[6] = quat.w();
    for (int j = 0; j < model::kNumJoints; ++j) {
      const double lo = robot.limits.position_min_rad[j], hi = robot.limits.position_max_rad[j];
      const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
      // A third of each range around its middle: knees and elbows stay bent (observable hinge
      // plane) and the three-axis hip and shoulder stay clear of gimbal lock, where the
      // angles are not a function of the keypoints any more.
      const double value = mid + 0.35 * half * std::sin(two_pi * (0.15 + 0.013 * j) * t + 0.7 * j);
      q[7 + j] = value;
    }
  }
  return out;
}

}  // namespace kuavo::mocap
