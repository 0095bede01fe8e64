#include "controllers/wbc/wbc_reference.h"

#include <algorithm>
#include <cmath>

namespace kuavo::wbc {

dynamics::Mat3 rotation_from_euler_zyx(const Vec3& ypr) {
  return (Eigen::AngleAxisd(ypr[0], Vec3::UnitZ()) * Eigen::AngleAxisd(ypr[1], Vec3::UnitY()) *
          Eigen::AngleAxisd(ypr[2], Vec3::UnitX()))
      .toRotationMatrix();
}

Vec3 euler_zyx_from_rotation(const dynamics::Mat3& r) {
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  return Vec3(std::atan2(r(1, 0), r(0, 0)), pitch, std::atan2(r(2, 1), r(2, 2)));
}

void wbc_interpolate_reference(const WbcReference& a, const WbcReference& b, double alpha, WbcReference& out) {
  constexpr double kPi = 3.14159265358979323846;
  const double s = std::clamp(alpha, 0.0, 1.0);
  auto lerp = [s](const auto& x, const auto& y) { return (1.0 - s) * x + s * y; };
  out.stamp_ns = a.stamp_ns + static_cast<hal::TimeNs>(std::llround(s * static_cast<double>(b.stamp_ns - a.stamp_ns)));
  Vec3 euler_b = b.base_euler_zyx_rad;
  // Yaw wraps at ±π: blend along the shorter arc.
  euler_b[0] = a.base_euler_zyx_rad[0] + std::remainder(euler_b[0] - a.base_euler_zyx_rad[0], 2.0 * kPi);
  out.base_euler_zyx_rad = lerp(a.base_euler_zyx_rad, euler_b);
  out.base_angular_velocity_rad_s = lerp(a.base_angular_velocity_rad_s, b.base_angular_velocity_rad_s);
  out.base_angular_acceleration_rad_s2 = lerp(a.base_angular_acceleration_rad_s2, b.base_angular_acceleration_rad_s2);
  out.com_position_m = lerp(a.com_position_m, b.com_position_m);
  out.com_velocity_m_s = lerp(a.com_velocity_m_s, b.com_velocity_m_s);
  out.momentum_rate = lerp(a.momentum_rate, b.momentum_rate);
  out.joint_position_rad = lerp(a.joint_position_rad, b.joint_position_rad);
  out.joint_velocity_rad_s = lerp(a.joint_velocity_rad_s, b.joint_velocity_rad_s);
  out.joint_acceleration_rad_s2 = lerp(a.joint_acceleration_rad_s2, b.joint_acceleration_rad_s2);
  out.point_position_m = lerp(a.point_position_m, b.point_position_m);
  out.point_velocity_m_s = lerp(a.point_velocity_m_s, b.point_velocity_m_s);
  out.point_acceleration_m_s2 = lerp(a.point_acceleration_m_s2, b.point_acceleration_m_s2);
  out.contact_force_N = lerp(a.contact_force_N, b.contact_force_N);
  out.in_contact = a.in_contact;
}

}  // namespace kuavo::wbc
