#include "tools/mocap/retarget.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "tools/mocap/box_qp.h"

namespace kuavo::mocap {
namespace {

using dynamics::FrameJacobian;
using dynamics::kNv;
using dynamics::VelocityVector;
using Hessian = Eigen::Matrix<double, kNv, kNv>;

constexpr int kFootBody[2] = {6, 12};             // leg_l6_link, leg_r6_link
constexpr int kLeftHipYaw = 1, kRightHipYaw = 7;  // joint indices (leg_l2, leg_r2)
constexpr int kLeftKnee = 3, kRightKnee = 9, kLeftElbow = 15, kRightElbow = 22;
constexpr double kColdStartBend_rad = 0.3;
constexpr int kColdStartSteps = 20;
// The first frame starts far from the answer: a firmer Levenberg damping keeps its steps short.
constexpr double kColdStartDamping = 1e-3;
// Stance feet stay this far inside the hip yaw range, leaving the pelvis room to turn.
constexpr double kHipYawMargin_rad = 0.17;
constexpr int kAnkleKp[2] = {kKpLeftAnkle, kKpRightAnkle};
constexpr int kToeKp[2] = {kKpLeftToe, kKpRightToe};
constexpr int kCornersPerFoot = model::kNumContactPoints / 2;
// Levenberg damping of the stance projection: tiny, so the correction is minimum-norm.
constexpr double kProjectionDamping = 1e-9;
// A landing foot locks when its ankle is this close to flat-foot height and its sole this
// close to level: the soft settling after the lock then moves a sole corner by well under
// 0.1 mm per frame (0.06 m × 0.01 rad spread over kSettleFrames).
constexpr double kLandHeight_m = 0.003;
constexpr double kLandTilt_rad = 0.01;
// Frames after touchdown during which the vertical part of a pin is soft, and its weight.
constexpr int kSettleFrames = 10;
constexpr double kSettleWeight = 1e-3;
// A corner pushed out of the floor is lifted to this height [m] (above round-off).
constexpr double kGroundClearance_m = 2e-4;
// Ankle-target height above flat-foot height below which a free foot is drawn flat [m]:
// a human swing clears 5–10 cm, so feet flatten in the last third of their descent.
constexpr double kFlatFootHeight_m = 0.08;

Vec3 rotation_log(const Mat3& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

Mat3 yaw_rotation(double yaw) {
  return Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
}

double heading_of(const Mat3& r) {
  return std::atan2(r(1, 0), r(0, 0));
}

}  // namespace

struct Retargeter::Workspace {
  dynamics::Data data;
  FrameJacobian jacobian;
  Hessian h;
  VelocityVector g, lo, hi, dx;
};

Retargeter::Retargeter(const model::Model& robot, const RetargetOptions& options, double rate_hz)
    : robot_(robot),
      options_(options),
      dt_s_(1.0 / rate_hz),
      ankle_height_m_(robot_ankle_height_m(robot)),
      keypoints_(robot_keypoints(robot)),
      ws_(std::make_unique<Workspace>()) {
  const RetargetWeights& w = options.weights;
  position_weight_.fill(0.0);
  position_weight_[kKpPelvis] = w.pelvis_position;
  position_weight_[kKpLeftAnkle] = position_weight_[kKpRightAnkle] = w.ankle;
  position_weight_[kKpLeftToe] = position_weight_[kKpRightToe] = w.toe;
  position_weight_[kKpLeftHeel] = position_weight_[kKpRightHeel] = w.toe;
  position_weight_[kKpLeftKnee] = position_weight_[kKpRightKnee] = w.knee;
  position_weight_[kKpLeftShoulder] = position_weight_[kKpRightShoulder] = w.shoulder;
  position_weight_[kKpLeftElbow] = position_weight_[kKpRightElbow] = w.elbow;
  position_weight_[kKpLeftWrist] = position_weight_[kKpRightWrist] = w.wrist;
  position_weight_[kKpLeftHand] = position_weight_[kKpRightHand] = w.hand;
  position_weight_[kKpHead] = w.head;
  position_weight_[kKpLeftThumb] = position_weight_[kKpRightThumb] = w.thumb;
  reset();
}

Retargeter::~Retargeter() = default;

void Retargeter::reset() {
  q_ = ConfigVector::Zero();
  q_[6] = 1.0;
  started_ = false;
  locked_ = {false, false};
}

void Retargeter::solve(const TargetFrame& target, const std::array<bool, kNumKeypoints>& present, const FootPins& pins,
                       int iterations, bool velocity_bounds, bool cold_start, bool smooth) {
  Workspace& ws = *ws_;
  const model::JointLimits& lim = robot_.limits;
  const ConfigVector& q_prev = q_prev_;
  const RetargetWeights& w = options_.weights;
  // A foot is pinned where it touches down. Once the schedule says stance, the foot first
  // lands: it is drawn flat onto the floor where it is (no horizontal jump). When it is
  // within kLandHeight_m and kLandTilt_rad of that, it locks: its pose (x, y, yaw) is held
  // exactly until liftoff. The planned pose (mean human foot over the phase) only guides
  // the approach, so a landing that velocity limits kept short never drags the feet, and
  // the robot's own contact labels (contact_label()) start at the real touchdown.
  std::array<FootPose2d, 2> stance = pins.stance;
  bool kinematics_fresh = false;
  for (int side = 0; side < 2; ++side) {
    if (!pins.pinned[side] || !options_.pin_stance_feet) {
      locked_[side] = false;
      continue;
    }
    ++locked_frames_[side];
    if (!locked_[side]) {
      if (!kinematics_fresh) dynamics::forward_kinematics(robot_, ws.data, q_);
      kinematics_fresh = true;
      const Vec3 p = ws.data.position_m[kFootBody[side]];
      const Mat3& r = ws.data.rotation[kFootBody[side]];
      locked_pose_[side] = {Vec3(p.x(), p.y(), ankle_height_m_), heading_of(r), 1.0};
      if (p.z() - ankle_height_m_ < kLandHeight_m && std::acos(std::clamp(r(2, 2), -1.0, 1.0)) < kLandTilt_rad) {
        locked_[side] = true;
        locked_frames_[side] = 0;
      }
    }
    stance[side] = locked_pose_[side];
  }
  // After the weighted solve, a few projection iterations put the stance feet exactly on
  // their pins (a minimum-norm correction under the same bounds): the weighted terms alone
  // leave millimetres of compromise whenever a velocity bound is active.
  // The same pass lifts any sole corner of a free foot that ended below the floor.
  const int total = iterations + options_.projection_iterations;
  for (int it = 0; it < total; ++it) {
    const bool project = it >= iterations;
    dynamics::forward_kinematics(robot_, ws.data, q_);
    ws.h.setIdentity();
    ws.h *= project ? kProjectionDamping : (cold_start && 2 * it < iterations ? kColdStartDamping : options_.damping);
    ws.g.setZero();
    const auto add_point = [&](int body, const Vec3& point_body, const Vec3& target_m, double weight) {
      const Vec3 p = ws.data.position_m[body] + ws.data.rotation[body] * point_body;
      dynamics::point_jacobian(robot_, ws.data, body, p, ws.jacobian);
      const auto jl = ws.jacobian.topRows<3>();
      ws.h.noalias() += weight * jl.transpose() * jl;
      ws.g.noalias() += weight * jl.transpose() * (target_m - p);
    };
    const auto add_rotation = [&](int body, const Mat3& target_r, double weight) {
      // Uses ws.jacobian from the preceding add_point on the same body.
      const auto ja = ws.jacobian.bottomRows<3>();
      ws.h.noalias() += weight * ja.transpose() * ja;
      ws.g.noalias() += weight * ja.transpose() * rotation_log(target_r * ws.data.rotation[body].transpose());
    };
    // A pose target with separate weights on the horizontal (x, y, yaw) and the vertical
    // (z, roll, pitch) parts, world axes.
    const auto add_foot_pose = [&](int body, const FootPose2d& pose, double horizontal, double vertical) {
      const Vec3 p = ws.data.position_m[body];
      dynamics::point_jacobian(robot_, ws.data, body, p, ws.jacobian);
      const Eigen::Matrix<double, 6, 1> wdiag =
          (Eigen::Matrix<double, 6, 1>() << horizontal, horizontal, vertical, vertical, vertical, horizontal)
              .finished();
      Eigen::Matrix<double, 6, 1> e;
      e.head<3>() = pose.ankle_position_m - p;
      e.tail<3>() = rotation_log(yaw_rotation(pose.yaw_rad) * ws.data.rotation[body].transpose());
      ws.h.noalias() += ws.jacobian.transpose() * wdiag.asDiagonal() * ws.jacobian;
      ws.g.noalias() += ws.jacobian.transpose() * (wdiag.asDiagonal() * e);
    };
    int rows = 0;
    if (project) {
      for (int side = 0; side < 2 && options_.pin_stance_feet; ++side) {
        if (!locked_[side]) continue;
        // A foot that just landed keeps its place exactly but settles down and flat softly,
        // so a landing a little high or tilted never drags the other foot.
        const bool settling = locked_frames_[side] < kSettleFrames;
        add_foot_pose(kFootBody[side], stance[side], 1.0, settling ? kSettleWeight : 1.0);
        ++rows;
      }
    }
    // Keypoints.
    for (int k = 0; k < kNumKeypoints && !project; ++k) {
      if (!present[k] || position_weight_[k] <= 0.0) continue;
      const bool left_foot = k == kAnkleKp[0] || k == kToeKp[0] || k == kKpLeftHeel;
      const bool right_foot = k == kAnkleKp[1] || k == kToeKp[1] || k == kKpRightHeel;
      if ((left_foot || right_foot) && options_.pin_stance_feet) {
        const int side = left_foot ? 0 : 1;
        if (pins.pinned[side]) continue;
      }
      add_point(keypoints_[k].body, keypoints_[k].point_m, target.position_m[k], position_weight_[k]);
      if (k == kKpPelvis) add_rotation(0, target.base_rotation, w.pelvis_rotation);
    }
    // Stance feet: full pose pinned (free feet near a stance: blended in and out).
    for (int side = 0; side < 2 && options_.pin_stance_feet && !project; ++side) {
      for (const FootPose2d* pose : {static_cast<const FootPose2d*>(&stance[side]), &pins.release[side]}) {
        if (pose->blend <= 0.0 || (pins.pinned[side] && pose == &pins.release[side])) continue;
        const double b4 = pose->blend * pose->blend * pose->blend * pose->blend;
        add_point(kFootBody[side], Vec3::Zero(), pose->ankle_position_m, b4 * w.stance_position);
        add_rotation(kFootBody[side], yaw_rotation(pose->yaw_rad), b4 * w.stance_rotation);
      }
    }
    // Free feet near the floor turn flat (keeping the human heading), so a toe-down or
    // rolled human foot, which the robot's ±15° ankle roll often cannot copy, does not
    // drive a sole corner through the floor: weight rises as the ankle target descends.
    for (int side = 0; side < 2 && options_.ground_rows && !project; ++side) {
      if (options_.pin_stance_feet && pins.pinned[side]) continue;
      const Vec3& ankle = target.position_m[kAnkleKp[side]];
      const double proximity = std::clamp(1.0 - (ankle.z() - ankle_height_m_) / kFlatFootHeight_m, 0.0, 1.0);
      if (proximity <= 0.0) continue;
      double yaw = heading_of(target.base_rotation);
      if (present[kToeKp[side]]) {
        const Vec3 d = target.position_m[kToeKp[side]] - ankle;
        if (std::hypot(d.x(), d.y()) > 1e-6) yaw = std::atan2(d.y(), d.x());
      }
      const Vec3 p = ws.data.position_m[kFootBody[side]];
      dynamics::point_jacobian(robot_, ws.data, kFootBody[side], p, ws.jacobian);
      add_rotation(kFootBody[side], yaw_rotation(yaw), proximity * proximity * w.swing_flat);
    }
    // Sole corners of free feet stay above the ground (one-sided: only while below).
    for (int c = 0; c < model::kNumContactPoints && options_.ground_rows; ++c) {
      const int side = c / kCornersPerFoot;
      if (locked_[side]) continue;
      const Vec3 p = dynamics::frame_position(robot_, ws.data, c);
      if (p.z() >= 0.0) continue;
      dynamics::frame_jacobian(robot_, ws.data, c, ws.jacobian);
      const auto jz = ws.jacobian.row(2);
      const double weight = project ? 1.0 : w.ground;
      ws.h.noalias() += weight * jz.transpose() * jz;
      ws.g.noalias() += (weight * (kGroundClearance_m - p.z())) * jz.transpose();
      ++rows;
    }
    if (project && rows == 0) break;  // nothing to correct
    // Smoothness: pull the joints toward the previous frame (velocity) and toward the
    // previous frame's velocity continued (acceleration).
    if (smooth && !project) {
      for (int j = 0; j < model::kNumJoints; ++j) {
        const double predicted = q_prev[7 + j] + (q_prev[7 + j] - q_prev2_[7 + j]);
        ws.h(6 + j, 6 + j) += w.joint_smoothness + w.joint_acceleration;
        ws.g[6 + j] +=
            w.joint_smoothness * (q_prev[7 + j] - q_[7 + j]) + w.joint_acceleration * (predicted - q_[7 + j]);
      }
    }
    // Bounds.
    ws.lo.head<6>().setConstant(-INFINITY);
    ws.hi.head<6>().setConstant(INFINITY);
    for (int j = 0; j < model::kNumJoints; ++j) {
      const double qj = q_[7 + j];
      double lo = lim.position_min_rad[j] - qj, hi = lim.position_max_rad[j] - qj;
      if (velocity_bounds) {
        const double step = lim.velocity_rad_s[j] * dt_s_;
        lo = std::max(lo, q_prev[7 + j] - step - qj);
        hi = std::min(hi, q_prev[7 + j] + step - qj);
      }
      if (lo > 0.0) lo = 0.0;  // numerical safety: q is feasible, so 0 must be
      if (hi < 0.0) hi = 0.0;
      ws.lo[6 + j] = lo;
      ws.hi[6 + j] = hi;
    }
    solve_box_qp<kNv>(ws.h, ws.g, ws.lo, ws.hi, ws.dx);
    q_ = dynamics::integrate(q_, ws.dx, 1.0);
    // The joint part of integrate() is additive: land exactly on a bound that was hit.
    for (int j = 0; j < model::kNumJoints; ++j)
      q_[7 + j] = std::clamp(q_[7 + j], lim.position_min_rad[j], lim.position_max_rad[j]);
    if (ws.dx.norm() < options_.step_tolerance && !project) it = std::max(it, iterations - 1);
  }
}

double Retargeter::keypoint_cost(const TargetFrame& target, const std::array<bool, kNumKeypoints>& present) {
  Workspace& ws = *ws_;
  dynamics::forward_kinematics(robot_, ws.data, q_);
  double cost = 0.0;
  for (int k = 0; k < kNumKeypoints; ++k) {
    if (!present[k]) continue;
    const int b = keypoints_[k].body;
    const Vec3 p = ws.data.position_m[b] + ws.data.rotation[b] * keypoints_[k].point_m;
    cost += position_weight_[k] * (target.position_m[k] - p).squaredNorm();
  }
  return cost + options_.weights.pelvis_rotation *
                    rotation_log(target.base_rotation * ws.data.rotation[0].transpose()).squaredNorm();
}

FrameLimits Retargeter::step(const TargetFrame& target, const std::array<bool, kNumKeypoints>& present,
                             const FootPins& pins) {
  const model::JointLimits& lim = robot_.limits;
  bool velocity_bounds = options_.velocity_limits;
  if (!started_) {
    // Cold start by homotopy: from the zero pose (base on the target pelvis, knees and elbows
    // slightly bent, off the straight-limb singularity) the targets are blended from where
    // that pose puts the keypoints to the real ones in kColdStartSteps steps, each solved
    // warm. Jumping straight to the targets can land a foot in a wrong basin (rolled against
    // its hip yaw) that no later frame leaves.
    const Eigen::Quaterniond quat(target.base_rotation);
    q_.setZero();
    q_.head<3>() = target.position_m[kKpPelvis] - target.base_rotation * keypoints_[kKpPelvis].point_m;
    q_[3] = quat.x();
    q_[4] = quat.y();
    q_[5] = quat.z();
    q_[6] = quat.w();
    for (int j : {kLeftKnee, kRightKnee}) q_[7 + j] = kColdStartBend_rad;
    for (int j : {kLeftElbow, kRightElbow}) q_[7 + j] = -kColdStartBend_rad;
    Workspace& ws = *ws_;
    dynamics::forward_kinematics(robot_, ws.data, q_);
    TargetFrame from = target;
    for (int k = 0; k < kNumKeypoints; ++k) {
      const int b = keypoints_[k].body;
      from.position_m[k] = ws.data.position_m[b] + ws.data.rotation[b] * keypoints_[k].point_m;
    }
    const Eigen::Quaterniond r0(ws.data.rotation[0]);
    const int per_step = std::max(1, options_.first_frame_iterations / kColdStartSteps);
    for (int step = 1; step <= kColdStartSteps; ++step) {
      const double a = static_cast<double>(step) / kColdStartSteps;
      TargetFrame blended = target;
      for (int k = 0; k < kNumKeypoints; ++k)
        blended.position_m[k] = (1.0 - a) * from.position_m[k] + a * target.position_m[k];
      blended.base_rotation = r0.slerp(a, quat).toRotationMatrix();
      q_prev_ = q_;
      locked_ = {false, false};
      solve(blended, present, step == kColdStartSteps ? pins : FootPins{}, per_step, false, step < kColdStartSteps,
            false);
    }
    q_prev_ = q_;
    q_prev2_ = q_;
    velocity_bounds = false;
    started_ = true;
  } else {
    q_prev2_ = q_prev_;
    q_prev_ = q_;
    solve(target, present, pins, options_.iterations, velocity_bounds, false, true);
  }
  const ConfigVector& q_prev = q_prev_;
  FrameLimits out;
  for (int j = 0; j < model::kNumJoints; ++j) {
    const double qj = q_[7 + j];
    at_position_bound_[j] = qj <= lim.position_min_rad[j] + 1e-9 || qj >= lim.position_max_rad[j] - 1e-9;
    at_velocity_bound_[j] =
        velocity_bounds && std::abs(qj - q_prev[7 + j]) >= lim.velocity_rad_s[j] * dt_s_ * (1.0 - 1e-6);
    out.position_bounds_active += at_position_bound_[j];
    out.velocity_bounds_active += at_velocity_bound_[j];
  }
  return out;
}

std::vector<FootPins> plan_foot_pins(const HumanTargets& targets, const std::vector<ContactLabel>& labels,
                                     const model::Model& robot, double rate_hz, int* yaw_clamped_phases) {
  if (yaw_clamped_phases) *yaw_clamped_phases = 0;
  const std::size_t n = targets.frames.size();
  std::vector<FootPins> pins(n);
  const double ankle_h = robot_ankle_height_m(robot);
  for (int side = 0; side < 2; ++side) {
    const auto in_contact = [&](std::size_t i) {
      return i < labels.size() && (side == 0 ? left_in_contact(labels[i]) : right_in_contact(labels[i]));
    };
    for (std::size_t i = 0; i < n;) {
      if (!in_contact(i)) {
        ++i;
        continue;
      }
      std::size_t j = i;
      Vec3 sum = Vec3::Zero();
      double cx = 0.0, cy = 0.0, px = 0.0, py = 0.0;
      while (j < n && in_contact(j)) {
        const TargetFrame& f = targets.frames[j];
        sum += f.position_m[kAnkleKp[side]];
        px += f.base_rotation(0, 0);
        py += f.base_rotation(1, 0);
        // Heading of the foot: ankle→toe if the toe is known, else the pelvis heading.
        double yaw = heading_of(f.base_rotation);
        if (targets.present[kToeKp[side]]) {
          const Vec3 d = f.position_m[kToeKp[side]] - f.position_m[kAnkleKp[side]];
          if (std::hypot(d.x(), d.y()) > 1e-6) yaw = std::atan2(d.y(), d.x());
        }
        cx += std::cos(yaw);
        cy += std::sin(yaw);
        ++j;
      }
      const Vec3 mean = sum / static_cast<double>(j - i);
      // The robot turns a foot out only as far as its hip yaw allows (±45°, FACTS.md §2.2),
      // not into a dancer's 70–90° turnout: clamp the heading relative to the pelvis.
      const double pelvis_yaw = std::atan2(py, px);
      const int hip_yaw = side == 0 ? kLeftHipYaw : kRightHipYaw;
      const double relative = std::remainder(std::atan2(cy, cx) - pelvis_yaw, 2.0 * M_PI);
      const double clamped = std::clamp(relative, robot.limits.position_min_rad[hip_yaw] + kHipYawMargin_rad,
                                        robot.limits.position_max_rad[hip_yaw] - kHipYawMargin_rad);
      if (yaw_clamped_phases && clamped != relative) ++*yaw_clamped_phases;
      const double yaw = pelvis_yaw + clamped;
      const FootPose2d pose{Vec3(mean.x(), mean.y(), ankle_h), yaw, 1.0};
      for (std::size_t k = i; k < j; ++k) {
        pins[k].pinned[side] = true;
        pins[k].stance[side] = pose;
      }
      // Approach before touchdown and release after liftoff.
      const int window = std::max(1, static_cast<int>(std::lround(kPinBlend_s * rate_hz)));
      for (int d = 1; d <= window; ++d) {
        FootPose2d faded = pose;
        faded.blend = 1.0 - static_cast<double>(d) / (window + 1);
        const std::ptrdiff_t before = static_cast<std::ptrdiff_t>(i) - d,
                             after = static_cast<std::ptrdiff_t>(j) - 1 + d;
        if (before >= 0 && !pins[before].pinned[side]) pins[before].stance[side] = faded;
        if (after < static_cast<std::ptrdiff_t>(n) && !pins[after].pinned[side]) pins[after].release[side] = faded;
      }
      i = j;
    }
  }
  return pins;
}

void retarget_motion(const model::Model& robot, const HumanTargets& targets, const std::vector<ContactLabel>& labels,
                     const RetargetOptions& options, RetargetResult& out) {
  out = RetargetResult{};
  std::vector<ContactLabel> schedule = labels;
  schedule.resize(targets.frames.size(), ContactLabel::kFlight);
  out.report.schedule_phases = count_contact_phases(schedule);
  out.contacts.reserve(targets.frames.size());
  const std::vector<FootPins> pins = options.pin_stance_feet ? plan_foot_pins(targets, schedule, robot, targets.rate_hz,
                                                                              &out.report.stance_yaw_clamped_phases)
                                                             : std::vector<FootPins>(targets.frames.size());
  Retargeter solver(robot, options, targets.rate_hz);
  out.q.reserve(targets.frames.size());
  RetargetReport& r = out.report;
  for (std::size_t i = 0; i < targets.frames.size(); ++i) {
    const FrameLimits l = solver.step(targets.frames[i], targets.present, pins[i]);
    out.q.push_back(solver.q());
    out.contacts.push_back(options.pin_stance_feet ? solver.contact_label() : schedule[i]);
    r.position_bound_active_samples += l.position_bounds_active;
    r.velocity_bound_active_samples += l.velocity_bounds_active;
    for (int j = 0; j < model::kNumJoints; ++j) {
      r.position_bound_active_per_joint[j] += solver.at_position_bound()[j];
      r.velocity_bound_active_per_joint[j] += solver.at_velocity_bound()[j];
    }
  }
  evaluate_motion(robot, targets, out);
}

void evaluate_motion(const model::Model& robot, const HumanTargets& targets, RetargetResult& result) {
  RetargetReport& r = result.report;
  const std::size_t n = result.q.size();
  r.frames = static_cast<int>(n);
  r.duration_s = n > 0 ? static_cast<double>(n - 1) / targets.rate_hz : 0.0;
  r.contact_phases = count_contact_phases(result.contacts);
  const auto kps = robot_keypoints(robot);
  auto data = std::make_unique<dynamics::Data>();
  std::array<Vec3, model::kNumContactPoints> corners{}, prev_corners{};
  double err_sum = 0.0;
  long err_count = 0;
  r.keypoint_error_max_m = r.foot_slide_max_m_s = r.penetration_max_m = r.float_max_m = 0.0;
  r.joint_limit_violations = r.velocity_limit_violations = 0;
  const double dt = 1.0 / targets.rate_hz;
  // Tolerances: 1e-9 rad of round-off on the limits, 1e-6 relative on the velocity.
  for (std::size_t i = 0; i < n; ++i) {
    const ConfigVector& q = result.q[i];
    dynamics::forward_kinematics(robot, *data, q);
    for (int k = 0; k < kNumKeypoints; ++k) {
      if (!targets.present[k] || i >= targets.frames.size()) continue;
      const Vec3 p = data->position_m[kps[k].body] + data->rotation[kps[k].body] * kps[k].point_m;
      const double e = (p - targets.frames[i].position_m[k]).norm();
      err_sum += e;
      ++err_count;
      r.keypoint_error_max_m = std::max(r.keypoint_error_max_m, e);
    }
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      corners[c] = dynamics::frame_position(robot, *data, c);
      r.penetration_max_m = std::max(r.penetration_max_m, -corners[c].z());
    }
    for (int side = 0; side < 2; ++side) {
      const bool now = side == 0 ? left_in_contact(result.contacts[i]) : right_in_contact(result.contacts[i]);
      if (!now) continue;
      for (int c = side * kCornersPerFoot; c < (side + 1) * kCornersPerFoot; ++c)
        r.float_max_m = std::max(r.float_max_m, corners[c].z());
      const bool before =
          i > 0 && (side == 0 ? left_in_contact(result.contacts[i - 1]) : right_in_contact(result.contacts[i - 1]));
      if (!before) continue;
      for (int c = side * kCornersPerFoot; c < (side + 1) * kCornersPerFoot; ++c) {
        const Vec3 d = corners[c] - prev_corners[c];
        r.foot_slide_max_m_s = std::max(r.foot_slide_max_m_s, std::hypot(d.x(), d.y()) / dt);
      }
    }
    prev_corners = corners;
    for (int j = 0; j < model::kNumJoints; ++j) {
      const double qj = q[7 + j];
      if (qj < robot.limits.position_min_rad[j] - 1e-9 || qj > robot.limits.position_max_rad[j] + 1e-9)
        ++r.joint_limit_violations;
      if (i > 0 && std::abs(qj - result.q[i - 1][7 + j]) > robot.limits.velocity_rad_s[j] * dt * (1.0 + 1e-6))
        ++r.velocity_limit_violations;
    }
  }
  r.keypoint_error_mean_m = err_count > 0 ? err_sum / static_cast<double>(err_count) : 0.0;
  r.penetration_max_m = std::max(0.0, r.penetration_max_m);
}

}  // namespace kuavo::mocap
