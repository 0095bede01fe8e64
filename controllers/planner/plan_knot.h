// The kinematic plan: what the robot should do, before dynamics. One PlanKnot is
// one instant of the desired whole-body motion (the retargeted dance, a gait, or a
// held pose) together with its contact schedule and the sole-corner targets derived
// from it. The MPC reads a window of knots at its stage times; without the MPC the
// WBC can track knots directly (wbc_reference_from_knot).
//
// Knots are plain fixed-size values: a PlanWindow (~70 knots) lives in static
// storage, never on a real-time stack.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>

#include "controllers/dynamics/data.h"
#include "controllers/hal/types.h"
#include "controllers/model/model.h"

namespace kuavo::planner {

using dynamics::Vec3;
inline constexpr int kNumPoints = model::kNumContactPoints;
using PointVector = Eigen::Matrix<double, 3 * kNumPoints, 1>;  // [x y z] per sole corner, world
using ContactFlags = std::array<bool, kNumPoints>;              // frame order 0..7

struct PlanKnot {
  hal::TimeNs stamp_ns = 0;
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();    // conventions.h
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();  // conventions.h (base twist in base axes)
  ContactFlags in_contact{};
  // Sole corners: stance = where the corner is planted (fixed over the stance phase);
  // swing = the swing trajectory (lift-off to touchdown, apex height from the plan).
  PointVector point_position_m = PointVector::Zero();
  PointVector point_velocity_m_s = PointVector::Zero();
  Vec3 com_position_m = Vec3::Zero();
  Vec3 com_velocity_m_s = Vec3::Zero();
};

// The linear inverted pendulum's capture point of a knot's CoM over soles at height sole_z:
// ξ = c + ċ/ω (horizontal), ω = √(g/h), h = c_z − sole_z but at least min_height_m.
struct CapturePoint {
  Eigen::Vector2d xi = Eigen::Vector2d::Zero();
  double omega = 0.0;
};
inline CapturePoint capture_point(const PlanKnot& knot, double sole_z, double min_height_m) {
  const double h = std::max(knot.com_position_m.z() - sole_z, min_height_m);
  CapturePoint out;
  out.omega = std::sqrt(model::kGravity_m_s2 / h);
  out.xi = knot.com_position_m.head<2>() + knot.com_velocity_m_s.head<2>() / out.omega;
  return out;
}

// 1.4 s (the longest MPC horizon) at 50 Hz, plus the terminal knot, plus slack for a
// 0.01 s step at 0.6 s.
inline constexpr int kMaxWindowKnots = 72;

struct PlanWindow {
  int count = 0;             // knots[0 .. count) are valid
  double dt_s = 0.02;        // knots[i].stamp_ns = knots[0].stamp_ns + i·dt
  std::array<PlanKnot, kMaxWindowKnots> knots{};
};

}  // namespace kuavo::planner

namespace kuavo::planner {

// Fills knot.q, knot.v, knot.in_contact and the derived fields (sole corners, CoM and
// their velocities) from kinematics of (q, v). data is scratch. Real-time safe.
void plan_knot_from_state(const model::Model& model, dynamics::Data& data, const dynamics::ConfigVector& q,
                          const dynamics::VelocityVector& v, const ContactFlags& in_contact, hal::TimeNs stamp_ns,
                          PlanKnot& knot);

// The measured state as a knot: kinematics of (q, v) at stamp_ns with every sole corner
// flagged in contact. The planner computes it once per call (stack_plan_rt) and the recovery
// step, the plan anchor and the lift-off hold read its corners and CoM. Real-time safe.
inline void plan_knot_measured(const model::Model& model, dynamics::Data& data, const dynamics::ConfigVector& q,
                               const dynamics::VelocityVector& v, hal::TimeNs stamp_ns, PlanKnot& knot) {
  ContactFlags all{};
  all.fill(true);
  plan_knot_from_state(model, data, q, v, all, stamp_ns, knot);
}

}  // namespace kuavo::planner
