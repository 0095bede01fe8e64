// What perfect sensors report while the robot follows a plan knot exactly: encoders and
// the IMU (at the base origin, base axes) without noise, bias or quantization. For the
// stack's long allocation test and the tick benchmark, where the plan is the oracle.
#pragma once

#include <Eigen/Geometry>

#include "controllers/hal/types.h"
#include "controllers/planner/motion_plan.h"

namespace kuavo::sim {

// accel_world_m_s2: the base origin's acceleration (world axes); the IMU measures it
// minus gravity, in base axes.
inline void ideal_sensor_frame(const planner::PlanKnot& knot, const Eigen::Vector3d& accel_world_m_s2,
                               hal::TimeNs stamp_ns, hal::SensorFrame& frame) {
  for (int j = 0; j < model::kNumJoints; ++j) {
    frame.joints[j].position_rad = knot.q[7 + j];
    frame.joints[j].velocity_rad_s = knot.v[6 + j];
    frame.joints[j].torque_Nm = 0.0;
    frame.joints[j].stamp_ns = stamp_ns;
    frame.joints[j].valid = true;
  }
  const Eigen::Quaterniond o(knot.q[6], knot.q[3], knot.q[4], knot.q[5]);
  const Eigen::Vector3d f = o.conjugate() * (accel_world_m_s2 + Eigen::Vector3d(0.0, 0.0, model::kGravity_m_s2));
  frame.imu.orientation_xyzw = {o.x(), o.y(), o.z(), o.w()};
  frame.imu.angular_rate_rad_s = {knot.v[3], knot.v[4], knot.v[5]};
  frame.imu.acceleration_m_s2 = {f.x(), f.y(), f.z()};
  frame.imu.stamp_ns = stamp_ns;
  frame.imu.valid = true;
}

// The frame ideal sensors give at t_ns while the robot follows the plan exactly; knot gets
// the plan at t_ns (the oracle). The base acceleration is the central difference of the
// plan's base velocity over ±1 ms.
inline void ideal_sensor_frame_on_plan(const model::Model& model, dynamics::Data& data,
                                       const planner::MotionPlan& plan, hal::TimeNs t_ns, planner::PlanKnot& knot,
                                       hal::SensorFrame& frame) {
  constexpr hal::TimeNs h_ns = 1'000'000;
  auto world_velocity = [](const planner::PlanKnot& k) {
    return Eigen::Quaterniond(k.q[6], k.q[3], k.q[4], k.q[5]) * k.v.head<3>();
  };
  planner::motion_plan_sample_rt(model, data, plan, t_ns - h_ns, knot);
  const Eigen::Vector3d v_before = world_velocity(knot);
  planner::motion_plan_sample_rt(model, data, plan, t_ns + h_ns, knot);
  const Eigen::Vector3d accel = (world_velocity(knot) - v_before) / (2e-9 * h_ns);
  planner::motion_plan_sample_rt(model, data, plan, t_ns, knot);
  ideal_sensor_frame(knot, accel, t_ns, frame);
}

}  // namespace kuavo::sim
