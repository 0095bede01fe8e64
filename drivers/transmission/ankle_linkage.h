// The 4Pro ankle: two motors (A, B) on the shank turn cranks about y; rods from
// the crank ends to ball joints on the foot drive the virtual serial joints
// ankle pitch (y) then ankle roll (x). Geometry from Leju's Drake URDF
// (FACTS.md §2.4), all in the shank frame (leg_4 link) with the foot anchors in
// the foot frame (leg_6 link, origin at the ankle centre).
//
// joint -> motor (each crank on its own) is closed form; motor -> joint solves
// the closed chain with Newton (fixed iteration cap, warm start). Velocities
// map with the Jacobian J = d(motor)/d(joint), torques with its transpose
// (virtual work: tau_jointᵀ qd_joint = tau_motorᵀ qd_motor -> tau_joint = Jᵀ tau_motor).
// All functions are real-time safe (fixed-size Eigen, no heap).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>  // 2x2 inverse
#include <array>

#include "drivers/driver_error.h"

namespace kuavo::drivers {

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;

inline constexpr int kAnkleNewtonMaxIterations = 20;
inline constexpr double kAnkleNewtonTolerance_rad = 1e-12;

struct AnkleGeometry {
  Eigen::Vector3d ankle_centre_m;                // leg_5 origin in the shank frame
  std::array<Eigen::Vector3d, 2> crank_pivot_m;  // motor A, B axes (along y) in the shank frame
  std::array<Eigen::Vector3d, 2> crank_arm_m;    // crank end minus pivot at motor angle 0
  std::array<Eigen::Vector3d, 2> foot_anchor_m;  // rod end on the foot, foot frame
  std::array<double, 2> rod_length_m{};
  // Which of the two crank solutions is the assembled one (+1 / -1); set by make_*.
  std::array<int, 2> branch{1, 1};
};

// Left/right leg geometry. Rod lengths are taken from the zero pose so that
// motor angles 0 <-> joint angles 0 exactly (the published 0.256 / 0.193 m are
// rounded and would put a ~0.5 mrad offset into the zero); the branches are
// chosen to contain the zero pose.
AnkleGeometry make_left_ankle();
AnkleGeometry make_right_ankle();
// Finishes a custom geometry: rod lengths (if <= 0) and branches from the zero pose.
void finish_ankle_geometry(AnkleGeometry& g);

// joint (pitch, roll) -> motor (A, B) crank angles. false if a rod cannot reach.
bool ankle_motor_from_joint_rt(const AnkleGeometry& g, const Vec2& joint_rad, Vec2& motor_rad);

// J = d(motor)/d(joint) at the configuration (joint, motor consistent).
Mat2 ankle_jacobian_rt(const AnkleGeometry& g, const Vec2& joint_rad, const Vec2& motor_rad);

// motor -> joint by Newton from `joint_rad` (warm start: last cycle's value).
// kOk when converged; kTransmissionUnsolved (unreachable, singular or not
// converged in kAnkleNewtonMaxIterations) otherwise, joint unchanged.
DriverError ankle_joint_from_motor_rt(const AnkleGeometry& g, const Vec2& motor_rad, Vec2& joint_rad,
                                      int* iterations = nullptr);

inline Vec2 ankle_motor_velocity_rt(const Mat2& J, const Vec2& joint_rad_s) { return J * joint_rad_s; }
inline Vec2 ankle_joint_velocity_rt(const Mat2& J, const Vec2& motor_rad_s) {
  return J.inverse() * motor_rad_s;
}
inline Vec2 ankle_joint_torque_rt(const Mat2& J, const Vec2& motor_Nm) { return J.transpose() * motor_Nm; }
inline Vec2 ankle_motor_torque_rt(const Mat2& J, const Vec2& joint_Nm) {
  return J.transpose().inverse() * joint_Nm;
}

}  // namespace kuavo::drivers
