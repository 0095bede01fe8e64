#include "controllers/planner/motion_plan.h"

#include <algorithm>
#include <cmath>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::planner {
namespace {

using dynamics::ConfigVector;
using dynamics::VelocityVector;

Eigen::Quaterniond orientation(const ConfigVector& q) { return Eigen::Quaterniond(q[6], q[3], q[4], q[5]); }

// Velocity (conventions.h) that carries qa to qb in dt_s: base twist in the axes of the
// midpoint orientation, joints by difference.
VelocityVector difference(const ConfigVector& qa, const ConfigVector& qb, double dt_s) {
  VelocityVector v;
  const Eigen::Quaterniond ra = orientation(qa), rb = orientation(qb);
  const Eigen::Quaterniond mid = ra.slerp(0.5, rb);
  v.head<3>() = mid.conjugate() * (qb.head<3>() - qa.head<3>()) / dt_s;
  const Eigen::AngleAxisd delta(ra.conjugate() * rb);  // rotation vector in qa's axes
  v.segment<3>(3) = (mid.conjugate() * ra) * (delta.angle() * delta.axis()) / dt_s;
  v.tail<model::kNumJoints>() = (qb.tail<model::kNumJoints>() - qa.tail<model::kNumJoints>()) / dt_s;
  return v;
}

// Time since the motion's start, in frames.
double frames_at(const MotionPlan& plan, hal::TimeNs t_ns) {
  return static_cast<double>(t_ns - plan.start_ns) * 1e-9 * plan.rate_hz;
}

}  // namespace

const char* motion_plan_finish(const MotionPlan& plan) {
  if (!(plan.rate_hz >= 1.0 && plan.rate_hz <= 10000.0)) return "motion rate outside 1..10000 Hz";
  if (plan.frame_count < 2) return "a motion needs at least two frames";
  if (plan.frame_count > kMaxMotionFrames) return "motion longer than kMaxMotionFrames";
  for (int i = 0; i < plan.frame_count; ++i) {
    if (!plan.q[i].allFinite()) return "motion frame with a non-finite value";
    if (std::abs(plan.q[i].segment<4>(3).norm() - 1.0) > 1e-6) return "motion frame whose base quaternion is not unit";
  }
  return nullptr;
}

VelocityVector motion_plan_velocity(const MotionPlan& plan, int i) {
  if (i <= 0 || i >= plan.frame_count - 1) return VelocityVector::Zero();
  return difference(plan.q[i - 1], plan.q[i + 1], 2.0 * (1.0 / plan.rate_hz));
}

double motion_plan_duration_s(const MotionPlan& plan) {
  return plan.frame_count > 0 ? static_cast<double>(plan.frame_count - 1) / plan.rate_hz : 0.0;
}

int motion_plan_frame_at(const MotionPlan& plan, hal::TimeNs t_ns) {
  const int last = std::max(plan.frame_count - 1, 0);
  const double s = frames_at(plan, t_ns);
  if (!(s > 0.0)) return 0;
  return s >= static_cast<double>(last) ? last : static_cast<int>(s);
}

hal::TimeNs motion_plan_frame_time(const MotionPlan& plan, int i) {
  return plan.start_ns + static_cast<hal::TimeNs>(std::llround(static_cast<double>(i) / plan.rate_hz * 1e9));
}

void motion_plan_sample_rt(const model::Model& model, dynamics::Data& data, const MotionPlan& plan, hal::TimeNs t_ns,
                           PlanKnot& knot) {
  const int last = std::max(plan.frame_count - 1, 0);
  const double s = frames_at(plan, t_ns);
  const int i = motion_plan_frame_at(plan, t_ns);
  ConfigVector q;
  VelocityVector v;
  if (s > 0.0 && i < last) {
    const double a = s - static_cast<double>(i);
    const ConfigVector& q0 = plan.q[i];
    const ConfigVector& q1 = plan.q[i + 1];
    q = (1.0 - a) * q0 + a * q1;
    q.segment<4>(3) = orientation(q0).slerp(a, orientation(q1)).coeffs();
    v = (1.0 - a) * motion_plan_velocity(plan, i) + a * motion_plan_velocity(plan, i + 1);
  } else {  // before the start or after the end: that frame, at rest
    q = plan.q[i];
    v.setZero();
  }
  ContactFlags flags{};
  for (int c = 0; c < kNumPoints; ++c) flags[c] = plan.foot_contact[i][c < kCornersPerFoot ? kLeftFoot : kRightFoot];
  plan_knot_from_state(model, data, q, v, flags, t_ns, knot);
}

void motion_plan_window_rt(const model::Model& model, dynamics::Data& data, const MotionPlan& plan, hal::TimeNs t0_ns,
                           double dt_s, int count, PlanWindow& window) {
  window.count = std::clamp(count, 0, kMaxWindowKnots);
  window.dt_s = dt_s;
  for (int k = 0; k < window.count; ++k) {
    const hal::TimeNs t = t0_ns + static_cast<hal::TimeNs>(std::llround(k * dt_s * 1e9));
    motion_plan_sample_rt(model, data, plan, t, window.knots[k]);
  }
}

}  // namespace kuavo::planner
