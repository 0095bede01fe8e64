// Weighted whole-body controller (the paper's WBC, Leju's WeightedWbc, FACTS.md §4.3), one
// dense QP per 500 Hz tick:
//
//   variables x = [q̈ (34: base twist rate in base axes, 28 joints); f (8 points × 3, world)]
//   torques eliminated: τ = M_j q̈ + b_j − J_jᵀ f is recovered afterwards (rows 6.. of the EoM)
//   equalities:   the 6 floating-base rows  M_b q̈ + b_b = J_bᵀ f
//   inequalities: friction pyramid, 4 rows per stance point (|f_x|, |f_y| ≤ μ f_z);
//                 ankle motor limits: each ankle pair's two motor commands, J⁻ᵀ (τ_pitch, τ_roll)
//                 through the linkage plus the drives' damping on the velocity error, within
//                 ankle_motor_torque_share of the motors' limits, 4 rows (off: ±∞) -- a joint-space
//                 box does not bound what the linkage asks of each motor (roll = 0.46 (τ_A − τ_B));
//                 serial leg drives: hip roll/yaw/pitch and knee torques at the drive's sample,
//                 τ + kv·(v_ref − v), within the drives' clamps, 8 rows (off: ±∞;
//                 hal/serial_drive_limits.h)
//                 torque limits |τ| ≤ min(model.limits.torque_Nm, the binding's cap), 28 rows (last)
//   bounds:       0 ≤ f_z ≤ max_normal_force_N on stance points, f = 0 on swing points;
//                 joint q̈ within the joint-limit-aware window
//   cost:         Σ weights · task errors² (stance points still, swing points tracking, base
//                 angular, CoM PD + ḣ feed-forward, arm and head joints, planned forces)
//
// The head stays in the dynamics (its 2 joints cost nothing in a 58-variable QP and keep M
// exact) and is driven by a joint task like the arms.
//
// Per-tick call sequence (firmware and sim alike):
//   static WbcWorkspace ws;  wbc_init(model, config, ws);     // once
//   each tick: reference = interpolate the MPC knots at now;   // wbc_interpolate_reference
//              status = wbc_step_rt(model, config, ws, q, v, reference, now_ns, command);
//   command goes to the drives (kPdTorque: τ = τ_ff + kp (q_ref − q) + kd (v_ref − v)).
#pragma once

#include "controllers/dynamics/rigid_body.h"
#include "controllers/hal/ankle_motor_limits.h"
#include "controllers/hal/serial_drive_limits.h"
#include "controllers/qp/dense_qp_solver.h"
#include "controllers/wbc/wbc_config.h"
#include "controllers/wbc/wbc_reference.h"

namespace kuavo::wbc {

inline constexpr int kNumAccelerations = model::kNv;               // 34
inline constexpr int kNumForces = 3 * kNumPoints;                  // 24
inline constexpr int kNumVars = kNumAccelerations + kNumForces;    // 58
inline constexpr int kNumEqualities = 6;                           // floating base
inline constexpr int kFrictionRowsPerPoint = 4;
inline constexpr int kNumFrictionRows = kFrictionRowsPerPoint * kNumPoints;  // rows [0, 32)
inline constexpr int kNumAnkleMotorRows = 4;  // [left A, left B, right A, right B], rows [32, 36)
inline constexpr int kNumSerialDriveRows = 2 * hal::kSerialLegJoints;  // left, right, rows [36, 44)
inline constexpr int kNumInequalities =
    kNumFrictionRows + kNumAnkleMotorRows + kNumSerialDriveRows + model::kNumJoints;  // torque rows last

using Qp = qp::DenseQp<kNumVars, kNumEqualities, kNumInequalities>;
using QpWorkspace = qp::DenseQpWorkspace<kNumVars, kNumEqualities, kNumInequalities>;
using QpSolution = qp::DenseQpSolution<kNumVars, kNumEqualities, kNumInequalities>;
using ContactJacobian = Eigen::Matrix<double, kNumForces, model::kNv>;  // linear rows per point
using ForceVector = Eigen::Matrix<double, kNumForces, 1>;

// What the last tick computed (the QP's answer when status is kOk).
struct WbcDiagnostics {
  WbcStatus status = WbcStatus::kFallbackPd;
  WbcFailure failure = WbcFailure::kNone;
  qp::QpStatus qp_status = qp::QpStatus::kBadInput;
  int qp_iterations = 0;
  int failed_ticks = 0;  // consecutive ticks without a good QP solution
  dynamics::VelocityVector acceleration = dynamics::VelocityVector::Zero();  // q̈
  ForceVector contact_force_N = ForceVector::Zero();
  dynamics::JointVector torque_Nm = dynamics::JointVector::Zero();
};

// The ankle pairs in motor space (controllers/hal/ankle_motor_limits.h), set by the binding
// before each tick. Inactive: no rows.
using AnkleMotorLimits = hal::AnkleMotorLimits;
using SerialLegDriveLimits = hal::SerialLegDriveLimits;

// ~190 KB with the QP: static storage only.
struct WbcWorkspace {
  AnkleMotorLimits ankle_motor_limits;
  SerialLegDriveLimits serial_drive_limits;  // set by the binding, like ankle_motor_limits
  // Per joint, the largest feed-forward torque the binding can send, joint side (the Ruiwo arm
  // motors' MIT torque field spans ±50 N·m, under the model's 60 N·m shoulder limits): the
  // torque rows bound τ by the smaller of it and the model's limit. +∞: no cap (the simulator).
  dynamics::JointVector torque_cap_Nm = dynamics::JointVector::Constant(qp::kInfinity);
  dynamics::Data data;
  dynamics::FrameJacobian frame_jacobian = dynamics::FrameJacobian::Zero();
  ContactJacobian contact_jacobian = ContactJacobian::Zero();
  ForceVector contact_bias = ForceVector::Zero();  // J̇v per point
  ForceVector point_position_m = ForceVector::Zero();
  ForceVector point_velocity_m_s = ForceVector::Zero();
  // Weighted task rows on q̈ for the points and the CoM (sqrt(w)·J), and their targets.
  Eigen::Matrix<double, kNumForces + 3, model::kNv> task_rows = Eigen::Matrix<double, kNumForces + 3, model::kNv>::Zero();
  Eigen::Matrix<double, kNumForces + 3, 1> task_targets = Eigen::Matrix<double, kNumForces + 3, 1>::Zero();
  Qp qp;
  QpWorkspace qp_workspace;
  QpSolution solution;
  qp::DenseQpSettings qp_settings;

  hal::CommandFrame last_good_command;
  bool have_last_good = false;
  dynamics::JointVector hold_position_rad = dynamics::JointVector::Zero();  // fallback PD target
  bool hold_position_latched = false;
  WbcDiagnostics diagnostics;
};

// Resets the workspace and writes the fixed parts of the QP (friction rows). Start-up only.
void wbc_init(const model::Model& model, const WbcConfig& config, WbcWorkspace& ws);

// One tick. q, v: estimated state (conventions.h). now_ns: this tick's time (sensor stamp).
// Writes all 28 joint commands and returns ws.diagnostics.status. Real-time safe: no
// allocation, no exceptions, bounded time.
WbcStatus wbc_step_rt(const model::Model& model, const WbcConfig& config, WbcWorkspace& ws,
                      const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                      const WbcReference& reference, hal::TimeNs now_ns, hal::CommandFrame& command);

// A reference that holds the given state still: base orientation, CoM, joints and contact
// points where they are, all points in contact, zero rates, planned forces the least-norm
// set carrying the weight. For
// standing and for tests. Uses ws.data as scratch (not real-time: call before the loop).
void wbc_reference_hold_state(const model::Model& model, WbcWorkspace& ws, const dynamics::ConfigVector& q,
                              hal::TimeNs stamp_ns, WbcReference& out);

}  // namespace kuavo::wbc
