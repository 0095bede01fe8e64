// Standing balance: the first controller, which proves the loop end to end.
// Joint PD around a bent-knee standing pose (executed by the drives) plus a
// feed-forward torque τ = g_joints − J_cᵀ f: gravity from our RNEA, and the
// weight carried by the 8 sole corners with a chosen centre of pressure. The
// centre of pressure follows a capture-point law, p = ξ + k_ξ(ξ − c_ref) with
// ξ = c + ċ/ω, which is what pushes a disturbed robot back over its feet. CoM and
// its velocity relative to the feet come from leg kinematics, the IMU
// orientation and its gyro (the base's linear velocity cancels in the difference).
#pragma once

#include <cstdint>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/hal/types.h"

namespace kuavo::control {

struct StandingConfig {
  double base_height_m = 0.78;  // Leju's standing height (reference.info standBaseState)
  // Per joint group PD gains the drives run [Nm/rad, Nm·s/rad].
  double leg_kp[6] = {400.0, 300.0, 400.0, 400.0, 150.0, 150.0};
  double leg_kd[6] = {6.0, 4.0, 6.0, 6.0, 3.0, 3.0};
  double arm_kp = 60.0, arm_kd = 2.0;
  double head_kp = 10.0, head_kd = 1.0;  // FACTS.md §4.3 head PD
  // Capture-point gain (dimensionless, > 0) and the margin kept between the
  // commanded centre of pressure and the sole edges.
  double capture_gain = 1.5;
  double cop_margin_m = 0.015;
  // First-order low-pass on the CoM velocity (Leju filters the gyro at 20 Hz).
  double velocity_filter_hz = 20.0;
  double dt_s = 0.002;
};

struct StandingState {
  dynamics::JointVector pose_rad = dynamics::JointVector::Zero();  // the standing joint pose
  dynamics::Data data;                                             // workspace
  dynamics::FrameJacobian jacobian = dynamics::FrameJacobian::Zero();
  Eigen::Matrix<double, 3 * model::kNumContactPoints, model::kNv> contact_jacobian =
      Eigen::Matrix<double, 3 * model::kNumContactPoints, model::kNv>::Zero();
  Eigen::Matrix<double, 3 * model::kNumContactPoints, 1> contact_force_N =
      Eigen::Matrix<double, 3 * model::kNumContactPoints, 1>::Zero();
  StandingConfig config{};
  Eigen::Vector2d com_ref_m = Eigen::Vector2d::Zero();         // CoM target, relative to the feet centre
  Eigen::Vector2d com_velocity_m_s = Eigen::Vector2d::Zero();  // filtered, relative to the feet
  Eigen::Vector2d cop_m = Eigen::Vector2d::Zero();             // commanded, relative to the feet centre
  bool filter_started = false;
};

// Joint angles of the standing pose for a base height: knees bent, feet flat and
// ankle_behind_hip_m behind the hips, arms hanging with a slight elbow bend.
dynamics::JointVector standing_pose(const model::Model& model, double base_height_m, double ankle_behind_hip_m);

// The standing pose whose centre of mass sits over the middle of the feet (the
// most margin against pushes both ways), found by adjusting the feet fore-aft.
// Start-up only; uses data as scratch.
dynamics::JointVector centred_standing_pose(const model::Model& model, dynamics::Data& data, double base_height_m);

// Lowers or raises the base so the lowest sole corner touches z = 0.
void place_on_ground(const model::Model& model, dynamics::Data& data, dynamics::ConfigVector& q);

void standing_init(const model::Model& model, const StandingConfig& config, StandingState& state);

// One 500 Hz control step. Real-time safe: no allocation, no I/O.
void standing_step_rt(const model::Model& model, StandingState& state, const hal::SensorFrame& sensors,
                      hal::CommandFrame& command);

}  // namespace kuavo::control
