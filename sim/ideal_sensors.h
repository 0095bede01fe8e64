// What perfect sensors report while the robot follows a plan knot exactly: encoders and
// the IMU (at the base origin, base axes) without noise, bias or quantization. For the
// stack's long allocation test and the tick benchmark, where the plan is the oracle.
#pragma once

#include <Eigen/Geometry>

#include "controllers/hal/types.h"
#include "controllers/planner/plan_knot.h"

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

}  // namespace kuavo::sim
