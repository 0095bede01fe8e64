// The drive's own control law, as the real drives run it (motor-side PD plus
// feed-forward, FACTS.md §4.3), with the torque saturating at the joint's peak
// trip limit. Evaluated continuously inside the plant integration.
#pragma once

#include <algorithm>
#include <cmath>

#include "controllers/hal/types.h"

namespace kuavo::sim {

// Returns the torque the drive applies; sets *saturated when it had to clip.
inline double drive_torque(const hal::JointCommand& c, double q_rad, double v_rad_s, double peak_torque_Nm,
                           bool* saturated) {
  double tau = 0.0;
  switch (c.mode) {
    case hal::JointMode::kDisabled:
      tau = 0.0;
      break;
    case hal::JointMode::kDamping:
      tau = -c.kd_Nm_s_per_rad * v_rad_s;
      break;
    case hal::JointMode::kPdTorque:
      tau = c.torque_ff_Nm + c.kp_Nm_per_rad * (c.position_ref_rad - q_rad) +
            c.kd_Nm_s_per_rad * (c.velocity_ref_rad_s - v_rad_s);
      break;
  }
  if (!std::isfinite(tau)) tau = 0.0;  // a drive never outputs NaN; the firmware stops it earlier
  const double clipped = std::clamp(tau, -peak_torque_Nm, peak_torque_Nm);
  if (saturated != nullptr) *saturated = clipped != tau;
  return clipped;
}

}  // namespace kuavo::sim
