// What the whole-body controller tracks at one 500 Hz tick. The MPC (50 Hz) fills
// one of these per knot; wbc_interpolate_reference() blends two knots linearly, so
// every continuous field is a plain vector (orientation as ZYX Euler angles, the
// MPC's own base-state coordinates, FACTS.md §4.2). Contact flags are discrete and
// come from the earlier knot.
#pragma once

#include <Eigen/Core>
#include <array>

#include "controllers/dynamics/data.h"
#include "controllers/hal/types.h"

namespace kuavo::wbc {

using dynamics::Vec3;
using dynamics::Vec6;
inline constexpr int kNumPoints = model::kNumContactPoints;
using PointVector = Eigen::Matrix<double, 3 * kNumPoints, 1>;  // [x y z] per contact point, world axes

struct WbcReference {
  hal::TimeNs stamp_ns = 0;  // the instant this reference describes; staleness is judged on it

  Vec3 base_euler_zyx_rad = Vec3::Zero();                // yaw, pitch, roll of base_link
  Vec3 base_angular_velocity_rad_s = Vec3::Zero();       // world axes
  Vec3 base_angular_acceleration_rad_s2 = Vec3::Zero();  // world axes, feed-forward

  Vec3 com_position_m = Vec3::Zero();
  Vec3 com_velocity_m_s = Vec3::Zero();
  // ḣ_G = [linear N; angular N·m about the CoM], world. The CoM feed-forward is ḣ_lin / m
  // (zero when standing still: ḣ_lin = Σf + m·g).
  Vec6 momentum_rate = Vec6::Zero();

  dynamics::JointVector joint_position_rad = dynamics::JointVector::Zero();
  dynamics::JointVector joint_velocity_rad_s = dynamics::JointVector::Zero();
  dynamics::JointVector joint_acceleration_rad_s2 = dynamics::JointVector::Zero();

  // Per contact point (frame ids 0..7): stance points are held at their position, swing
  // points follow it (swing trajectory from the planner).
  PointVector point_position_m = PointVector::Zero();
  PointVector point_velocity_m_s = PointVector::Zero();
  PointVector point_acceleration_m_s2 = PointVector::Zero();
  PointVector contact_force_N = PointVector::Zero();  // planned forces (MPC input), world
  std::array<bool, kNumPoints> in_contact{};
};

// out = (1 − alpha)·a + alpha·b for every continuous field (yaw blended along the short
// way); flags and stamp: a's flags, stamp blended. alpha is clamped to [0, 1]. Real-time safe.
void wbc_interpolate_reference(const WbcReference& a, const WbcReference& b, double alpha, WbcReference& out);

// Base rotation (base -> world) from ZYX Euler angles (yaw, pitch, roll).
dynamics::Mat3 rotation_from_euler_zyx(const Vec3& yaw_pitch_roll_rad);
// Inverse of the above; pitch in [−π/2, π/2].
Vec3 euler_zyx_from_rotation(const dynamics::Mat3& rotation);

}  // namespace kuavo::wbc
