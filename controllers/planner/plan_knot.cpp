#include "controllers/planner/plan_knot.h"

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::planner {

void plan_knot_from_state(const model::Model& model, dynamics::Data& data, const dynamics::ConfigVector& q,
                          const dynamics::VelocityVector& v, const ContactFlags& in_contact, hal::TimeNs stamp_ns,
                          PlanKnot& knot) {
  knot.stamp_ns = stamp_ns;
  knot.q = q;
  knot.v = v;
  knot.in_contact = in_contact;
  dynamics::forward_kinematics(model, data, q);
  dynamics::forward_velocities(model, data, v);
  for (int c = 0; c < kNumPoints; ++c) {
    knot.point_position_m.segment<3>(3 * c) = dynamics::frame_position(model, data, c);
    knot.point_velocity_m_s.segment<3>(3 * c) = dynamics::frame_velocity(model, data, c).head<3>();
  }
  // CoM and its velocity from the bodies' spatial inertias at the reference point (no CRBA).
  Vec3 first_moment = Vec3::Zero(), momentum = Vec3::Zero();
  double mass = 0.0;
  for (int b = 0; b < model::kNumBodies; ++b) {
    first_moment += data.inertia[b].first_moment;
    momentum += (data.inertia[b] * data.velocity[b]).head<3>();
    mass += data.inertia[b].mass;
  }
  knot.com_position_m = data.reference_point_m + first_moment / mass;
  knot.com_velocity_m_s = momentum / mass;
}

}  // namespace kuavo::planner
