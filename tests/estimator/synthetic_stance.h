// A kinematically exact synthetic robot for the estimator tests: the 8 sole
// corners stay fixed on the ground while the base moves; leg joint angles come
// from a Newton IK on all 24 corner coordinates, joint rates from the same
// Jacobian. IMU and encoders are noise-free unless a test adds noise.
#pragma once

#include <Eigen/Dense>
#include <array>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/hal/types.h"

namespace kuavo::test {

using CornerArray = std::array<Eigen::Vector3d, model::kNumContactPoints>;
using LegJacobian = Eigen::Matrix<double, 3 * model::kNumContactPoints, 2 * model::kLegJoints>;

// Knees bent, feet flat (hip + knee + ankle pitch = 0), lowest corner on z = 0.
inline dynamics::ConfigVector bent_stance(const model::Model& robot, dynamics::Data& data) {
  dynamics::ConfigVector q = dynamics::neutral_configuration(robot);
  for (int leg : {model::kLeftLegFirst, model::kRightLegFirst}) {
    q[7 + leg + 2] = -0.35;  // hip pitch
    q[7 + leg + 3] = 0.70;   // knee
    q[7 + leg + 4] = -0.35;  // ankle pitch
  }
  dynamics::forward_kinematics(robot, data, q);
  double lowest = 1e9;
  for (int i = 0; i < model::kNumContactPoints; ++i) lowest = std::min(lowest, dynamics::frame_position(robot, data, i).z());
  q[2] -= lowest;
  return q;
}

inline CornerArray corners(const model::Model& robot, dynamics::Data& data, const dynamics::ConfigVector& q) {
  dynamics::forward_kinematics(robot, data, q);
  CornerArray c;
  for (int i = 0; i < model::kNumContactPoints; ++i) c[i] = dynamics::frame_position(robot, data, i);
  return c;
}

// d(corner positions)/d(leg joints) at the current forward_kinematics.
inline void leg_jacobian(const model::Model& robot, const dynamics::Data& data, LegJacobian& j) {
  dynamics::FrameJacobian frame;
  for (int i = 0; i < model::kNumContactPoints; ++i) {
    dynamics::frame_jacobian(robot, data, i, frame);
    j.middleRows<3>(3 * i) = frame.block<3, 2 * model::kLegJoints>(0, 6);
  }
}

// Leg joints in q (base pose given) that put the corners on target. Returns the residual norm.
inline double solve_legs(const model::Model& robot, dynamics::Data& data, dynamics::ConfigVector& q,
                         const CornerArray& target) {
  LegJacobian j;
  Eigen::Matrix<double, 3 * model::kNumContactPoints, 1> r;
  for (int iter = 0; iter < 30; ++iter) {
    dynamics::forward_kinematics(robot, data, q);
    for (int i = 0; i < model::kNumContactPoints; ++i) r.segment<3>(3 * i) = dynamics::frame_position(robot, data, i) - target[i];
    if (r.norm() < 1e-13) break;
    leg_jacobian(robot, data, j);
    q.segment<2 * model::kLegJoints>(7) -= (j.transpose() * j).ldlt().solve(j.transpose() * r);
  }
  return r.norm();
}

// Leg joint rates that keep the corners still while the base translates at
// v_world (identity orientation, no rotation): J_leg q̇ = −v for every corner.
inline Eigen::Matrix<double, 2 * model::kLegJoints, 1> leg_rates(const model::Model& robot, dynamics::Data& data,
                                                               const dynamics::ConfigVector& q,
                                                               const Eigen::Vector3d& v_world_m_s) {
  dynamics::forward_kinematics(robot, data, q);
  LegJacobian j;
  leg_jacobian(robot, data, j);
  Eigen::Matrix<double, 3 * model::kNumContactPoints, 1> rhs;
  for (int i = 0; i < model::kNumContactPoints; ++i) rhs.segment<3>(3 * i) = -v_world_m_s;
  return (j.transpose() * j).ldlt().solve(j.transpose() * rhs);
}

// bent_stance with every corner exactly on z = 0: Leju's legs differ by about
// 0.1 mm in length, which the stance-height measurement would otherwise see.
inline dynamics::ConfigVector flat_stance(const model::Model& robot, dynamics::Data& data) {
  dynamics::ConfigVector q = bent_stance(robot, data);
  CornerArray target = corners(robot, data, q);
  for (Eigen::Vector3d& c : target) c.z() = 0.0;
  solve_legs(robot, data, q, target);
  return q;
}

// Left leg only: the left corners (0..3) on target, the right leg left as it is.
inline double solve_left_leg(const model::Model& robot, dynamics::Data& data, dynamics::ConfigVector& q,
                             const CornerArray& target) {
  LegJacobian j;
  Eigen::Matrix<double, 12, 1> r;
  for (int iter = 0; iter < 30; ++iter) {
    dynamics::forward_kinematics(robot, data, q);
    for (int i = 0; i < 4; ++i) r.segment<3>(3 * i) = dynamics::frame_position(robot, data, i) - target[i];
    if (r.norm() < 1e-13) break;
    leg_jacobian(robot, data, j);
    const Eigen::Matrix<double, 12, 6> jl = j.topLeftCorner<12, 6>();
    q.segment<6>(7) -= (jl.transpose() * jl).ldlt().solve(jl.transpose() * r);
  }
  return r.norm();
}

// Left-leg rates that keep the left corners still while the base translates at v_world.
inline Eigen::Matrix<double, 6, 1> left_leg_rates(const model::Model& robot, dynamics::Data& data,
                                                  const dynamics::ConfigVector& q, const Eigen::Vector3d& v_world_m_s) {
  dynamics::forward_kinematics(robot, data, q);
  LegJacobian j;
  leg_jacobian(robot, data, j);
  const Eigen::Matrix<double, 12, 6> jl = j.topLeftCorner<12, 6>();
  Eigen::Matrix<double, 12, 1> rhs;
  for (int i = 0; i < 4; ++i) rhs.segment<3>(3 * i) = -v_world_m_s;
  return (jl.transpose() * jl).ldlt().solve(jl.transpose() * rhs);
}

// Sensor frame for a robot with identity orientation and no rotation.
inline hal::SensorFrame frame_from(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                                   const Eigen::Vector3d& accel_world_m_s2, hal::TimeNs stamp_ns) {
  hal::SensorFrame f;
  for (int j = 0; j < model::kNumJoints; ++j) {
    f.joints[j].position_rad = q[7 + j];
    f.joints[j].velocity_rad_s = v[6 + j];
    f.joints[j].stamp_ns = stamp_ns;
    f.joints[j].valid = true;
  }
  f.imu.orientation_xyzw = {q[3], q[4], q[5], q[6]};
  f.imu.angular_rate_rad_s = {0.0, 0.0, 0.0};
  const Eigen::Vector3d specific = accel_world_m_s2 + model::kGravity_m_s2 * Eigen::Vector3d::UnitZ();
  f.imu.acceleration_m_s2 = {specific.x(), specific.y(), specific.z()};
  f.imu.stamp_ns = stamp_ns;
  f.imu.valid = true;
  return f;
}

}  // namespace kuavo::test
