// Whole-body controller settings: task weights and gains (FACTS.md §4.3, Leju's
// task.info, where not stated otherwise), output PD gains, fallback policy.
// Plain values with defaults; wbc_validate_config() checks them once, at load.
#pragma once

#include <array>
#include <cstdint>

#include "controllers/hal/types.h"

namespace kuavo::wbc {

struct WbcConfig {
  double dt_s = 0.002;                // 500 Hz tick
  double friction_coefficient = 0.5;  // frictionConeTask μ
  double max_normal_force_N = 1500.0; // ~3× body weight per point: bounds the fz variables

  // Task weights (stance values of Leju's weighted WBC).
  double weight_stance_point = 1000.0;  // stance points do not move
  double weight_swing_point = 100.0;
  double weight_base_angular = 10.0;
  // Leju: 10 (= base angular). Above base angular, the QP may pitch the torso to move the CoM
  // (hip strategy) once the 27 Nm ankles saturate: the 10 N·s forward push on the floor is
  // survived with 100 and not with 10 (tests/wbc/wbc_standing_sim_test.cpp).
  double weight_com = 100.0;
  double weight_arm = 9.0;
  double weight_head = 9.0;  // Leju runs the head apart; we keep it in the dynamics with the arm weight
  // Leju weighs force tracking 1 against CoM 10, which works because its MPC forces already
  // carry the balance feedback. Per N² against per (m/s²)², 1 would drown the CoM PD here
  // (1 m/s² of CoM is 55 N); 1e-3 keeps the planned forces as the tie-breaker among contacts.
  double weight_contact_force = 1e-3;
  double weight_acceleration_regularization = 1e-4;  // keeps H positive definite at singular poses

  // Task PD gains.
  double stance_kp = 24.0, stance_kd = 10.0;  // Leju's sim values
  double swing_kp_z = 150.0, swing_kd_z = 50.0, swing_kp_xy = 120.0, swing_kd_xy = 50.0;
  std::array<double, 3> base_angular_kp{120.0, 120.0, 50.0};  // roll, pitch, yaw (yaw frame)
  std::array<double, 3> base_angular_kd{20.0, 20.0, 10.0};
  // x, y, z in the yaw frame. Leju: x-y kp (20.72, 10.0), kd (5.93, 5.48), z as here. Its
  // MPC closes the balance loop at 50 Hz on top; the WBC alone (standing reference, no MPC)
  // drifts sideways with those gains and light leg PD (measured in tests/wbc: falls after
  // ~8 s), and holds the CoM within 0.2 mm with these.
  std::array<double, 3> com_kp{40.0, 40.0, 44.32};
  std::array<double, 3> com_kd{12.0, 12.0, 10.26};
  double arm_kp = 150.0, arm_kd = 10.2;
  double head_kp = 150.0, head_kd = 10.2;

  // Joint-acceleration bounds: |q̈| ≤ max, and no joint may cross its position limit within
  // the lookahead at the commanded acceleration (q + v·h + ½·a·h² inside the limits).
  double max_joint_acceleration_rad_s2 = 500.0;  // Leju treats > 2000 as a broken solution
  double joint_limit_lookahead_s = 0.05;

  // Share of each ankle motor's limit (AnkleMotorLimits, when the binding sets it) the QP may
  // plan; the rest is left to the drive's own feedback on top (CSP: kp·(target − q) −
  // kd·(q̇ − J v_ref)). The built-in dance in the firmware loop, floor / carpet, seed 1: at
  // 1.0 the ankle drives sat at their limit in 41 307 / 10 987 force evaluations, legs RMS
  // 0.0232 / 0.0475 rad; at 0.9 in 506 / 115, 0.0225 / 0.0457; at 0.8 in 2 333 / 0,
  // 0.0228 / 0.0424. With the ankles per motor in `kuavo simulate` too (56aadf6), 1.0 saved
  // 6 then 3 runs and lost none of the show campaign on the same motions; but re-retargeted
  // with it (the closed-loop check runs this WBC) cmu_05_07's motion fell in 7 more, and in
  // the firmware loop on floor and carpet (fault 18, seed 1), where the motions written at
  // 0.9 dance: 0.9 stays.
  double ankle_motor_torque_share = 0.9;

  // Output PD run by the drives around (q_ref, v_ref): light, the torque does the work.
  std::array<double, 6> leg_kp{60.0, 60.0, 60.0, 60.0, 30.0, 30.0};
  std::array<double, 6> leg_kd{3.0, 3.0, 3.0, 3.0, 1.5, 1.5};
  double arm_pd_kp = 30.0, arm_pd_kd = 2.0;  // ruiwo arm PTM gains (FACTS.md §4.3)
  double head_pd_kp = 10.0, head_pd_kd = 1.0;

  // Fallback: hold the last good command this long, then the gravity-compensated stiff PD.
  int hold_ticks = 10;  // 20 ms: under one MPC period
  hal::TimeNs max_reference_age_ns = 100'000'000;  // 5 MPC periods
  std::array<double, 6> fallback_leg_kp{400.0, 300.0, 400.0, 400.0, 150.0, 150.0};  // standing controller
  std::array<double, 6> fallback_leg_kd{6.0, 4.0, 6.0, 6.0, 3.0, 3.0};
  double fallback_arm_kp = 60.0, fallback_arm_kd = 2.0;
  double damping_kd = 2.0;  // the state itself is unusable: damping only

  int qp_max_iterations = 100;
};

// Returns nullptr if usable, else what is wrong. Load time only.
const char* wbc_validate_config(const WbcConfig& config);

// What the tick did. Stable numbers (logs, fault records): never renumber or reuse.
enum class WbcStatus : std::uint8_t {
  kOk = 0,                  // QP solved; command from its (q̈, f, τ)
  kHoldingLastCommand = 1,  // this tick failed; the last good command is repeated (≤ hold_ticks)
  kFallbackPd = 2,          // failures outlasted the hold: gravity-compensated stiff PD on a held pose
  kDamping = 3,             // the estimated state is not finite: damping mode only
};

// Why the tick was not kOk. Stable numbers.
enum class WbcFailure : std::uint8_t {
  kNone = 0,
  kQpFailed = 1,          // status other than solved (see WbcDiagnostics::qp_status)
  kReferenceStale = 2,    // older than max_reference_age_ns
  kReferenceInvalid = 3,  // non-finite values
  kSolutionInvalid = 4,   // solved but non-finite or beyond the acceleration bound
  kStateInvalid = 5,
};

const char* to_string(WbcStatus s);
const char* to_string(WbcFailure f);

}  // namespace kuavo::wbc
