// The joints' mechanical end stops: a stiff one-sided spring-damper beyond each joint's
// position limit (model.limits), evaluated inside the plant integration like the drives.
// Without them the simulated robot bent joints past where the real one's hard stops end
// them: perfume's left ankle pitch reached 0.045 rad past its -0.87 rad stop in a kick, the
// reference followed it, and the firmware (which refuses a reference > 0.05 rad past a stop)
// faulted where `kuavo simulate` danced on.
#pragma once

#include <algorithm>

namespace kuavo::sim {

// Engineering values (no data sheet gives the stops' compliance): 2000 N·m/rad lets a
// 100 N·m push in 0.05 rad, the output stage's tolerance for a reference past a stop; the
// damping takes the bounce out of a light link (the foot about its ankle: 0.002 kg·m²)
// without holding a heavy one (the leg about its hip, ~1 kg·m²) against the stop.
inline constexpr double kJointStopStiffness_Nm_per_rad = 2000.0;
inline constexpr double kJointStopDamping_Nm_s_per_rad = 5.0;

// Torque of the stop on a joint at q [rad] moving at v [rad/s], limits [lower, upper]:
// 0 inside, pushing back beyond; the damping only brakes motion into the stop and never pulls
// the joint back into it (the total never points outwards).
inline double joint_stop_torque(double q_rad, double v_rad_s, double lower_rad, double upper_rad) {
  if (q_rad > upper_rad) {
    const double tau = -kJointStopStiffness_Nm_per_rad * (q_rad - upper_rad) -
                       kJointStopDamping_Nm_s_per_rad * std::max(v_rad_s, 0.0);
    return std::min(tau, 0.0);
  }
  if (q_rad < lower_rad) {
    const double tau = kJointStopStiffness_Nm_per_rad * (lower_rad - q_rad) -
                       kJointStopDamping_Nm_s_per_rad * std::min(v_rad_s, 0.0);
    return std::max(tau, 0.0);
  }
  return 0.0;
}

}  // namespace kuavo::sim
