#include "controllers/wbc/wbc_config.h"

#include <cmath>

namespace kuavo::wbc {

const char* wbc_validate_config(const WbcConfig& c) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  auto non_negative = [](double x) { return std::isfinite(x) && x >= 0.0; };
  if (!positive(c.dt_s)) return "dt_s must be > 0";
  if (!positive(c.friction_coefficient)) return "friction_coefficient must be > 0";
  if (!positive(c.max_normal_force_N)) return "max_normal_force_N must be > 0";
  for (double w : {c.weight_stance_point, c.weight_swing_point, c.weight_base_angular, c.weight_com, c.weight_arm,
                   c.weight_head}) {
    if (!non_negative(w)) return "task weights must be finite and >= 0";
  }
  // These two keep the Hessian positive definite whatever the other weights are.
  if (!positive(c.weight_contact_force)) return "weight_contact_force must be > 0";
  if (!positive(c.weight_acceleration_regularization)) return "weight_acceleration_regularization must be > 0";
  if (!positive(c.max_joint_acceleration_rad_s2)) return "max_joint_acceleration_rad_s2 must be > 0";
  if (!positive(c.joint_limit_lookahead_s)) return "joint_limit_lookahead_s must be > 0";
  if (!(c.ankle_motor_torque_share > 0.0 && c.ankle_motor_torque_share <= 1.0)) {
    return "ankle_motor_torque_share must be in (0, 1]";
  }
  if (c.hold_ticks < 0) return "hold_ticks must be >= 0";
  if (c.max_reference_age_ns <= 0) return "max_reference_age_ns must be > 0";
  if (c.qp_max_iterations < 1) return "qp_max_iterations must be >= 1";
  return nullptr;
}

const char* to_string(WbcStatus s) {
  switch (s) {
    case WbcStatus::kOk: return "ok";
    case WbcStatus::kHoldingLastCommand: return "holding_last_command";
    case WbcStatus::kFallbackPd: return "fallback_pd";
    case WbcStatus::kDamping: return "damping";
  }
  return "unknown";
}

const char* to_string(WbcFailure f) {
  switch (f) {
    case WbcFailure::kNone: return "none";
    case WbcFailure::kQpFailed: return "qp_failed";
    case WbcFailure::kReferenceStale: return "reference_stale";
    case WbcFailure::kReferenceInvalid: return "reference_invalid";
    case WbcFailure::kSolutionInvalid: return "solution_invalid";
    case WbcFailure::kStateInvalid: return "state_invalid";
  }
  return "unknown";
}

}  // namespace kuavo::wbc
