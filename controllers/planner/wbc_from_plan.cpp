#include "controllers/planner/wbc_from_plan.h"

namespace kuavo::planner {
namespace {

dynamics::Mat3 rotation(const dynamics::ConfigVector& q) {
  return Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix();
}

}  // namespace

void wbc_reference_from_knots(const model::Model& model, const PlanKnot& knot, const PlanKnot& next, double dt_s,
                              wbc::WbcReference& out) {
  const double inv_dt = dt_s > 0.0 ? 1.0 / dt_s : 0.0;
  const dynamics::Mat3 r = rotation(knot.q);
  out.stamp_ns = knot.stamp_ns;
  out.base_euler_zyx_rad = wbc::euler_zyx_from_rotation(r);
  out.base_angular_velocity_rad_s = r * knot.v.segment<3>(3);
  out.base_angular_acceleration_rad_s2 = (rotation(next.q) * next.v.segment<3>(3) - out.base_angular_velocity_rad_s) * inv_dt;
  out.com_position_m = knot.com_position_m;
  out.com_velocity_m_s = knot.com_velocity_m_s;
  const Vec3 com_acceleration = (next.com_velocity_m_s - knot.com_velocity_m_s) * inv_dt;
  out.momentum_rate.head<3>() = model.total_mass_kg * com_acceleration;
  out.momentum_rate.tail<3>().setZero();
  out.joint_position_rad = knot.q.tail<model::kNumJoints>();
  out.joint_velocity_rad_s = knot.v.tail<model::kNumJoints>();
  out.joint_acceleration_rad_s2 = (next.v.tail<model::kNumJoints>() - knot.v.tail<model::kNumJoints>()) * inv_dt;
  out.point_position_m = knot.point_position_m;
  out.point_velocity_m_s = knot.point_velocity_m_s;
  out.point_acceleration_m_s2 = (next.point_velocity_m_s - knot.point_velocity_m_s) * inv_dt;
  out.in_contact = knot.in_contact;
  int stance = 0;
  for (bool c : knot.in_contact) stance += c ? 1 : 0;
  out.contact_force_N.setZero();
  const double weight_N = model.total_mass_kg * (model::kGravity_m_s2 + com_acceleration.z());
  for (int c = 0; c < kNumPoints; ++c) {
    if (knot.in_contact[c] && weight_N > 0.0) out.contact_force_N[3 * c + 2] = weight_N / stance;
  }
  // Stance corners are held still: no planned motion.
  for (int c = 0; c < kNumPoints; ++c) {
    if (!knot.in_contact[c]) continue;
    out.point_velocity_m_s.segment<3>(3 * c).setZero();
    out.point_acceleration_m_s2.segment<3>(3 * c).setZero();
  }
}

}  // namespace kuavo::planner
