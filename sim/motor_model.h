// The drive's own control law, as the real drives run it (motor-side PD plus
// feed-forward, FACTS.md §4.3), with the torque saturating at the joint's peak
// trip limit. Evaluated continuously inside the plant integration.
//
// The ankle pairs (drive_torques with the ankle motors): on the 4Pro two motors drive ankle
// pitch and roll through the parallel linkage (FACTS.md §2.4), and each motor clamps its own
// torque. The law still runs in joint space (the hal::JointCommand, as the firmware's CST
// binding evaluates it); the pair's torques are mapped to the motors at the present ankle
// angles, each motor clipped at its peak, and mapped back: pitch and roll share the two
// clamps (about 54 N·m of pitch alone, 24.5 of roll alone near the zero pose).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "drivers/transmission/ankle_motors.h"

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

using JointValues = std::array<double, model::kNumJoints>;

// Every drive's torque at joint positions q and velocities v: each joint clipped at its peak,
// or, with `ankle_motors` (nullptr: none), each ankle pair clipped per motor instead (a pair
// the linkage cannot solve at q clips at the joints' peaks). Returns the drives that clipped.
inline int drive_torques(const hal::CommandFrame& c, const model::Model& model, const JointValues& q,
                         const JointValues& v, const drivers::AnkleMotors* ankle_motors, JointValues& tau) {
  std::array<bool, model::kNumJoints> saturated{};
  for (int j = 0; j < model::kNumJoints; ++j) {
    tau[j] = drive_torque(c.joints[j], q[j], v[j], model.limits.peak_torque_Nm[j], &saturated[j]);
  }
  int motors_clipped = 0;
  for (int leg = 0; ankle_motors != nullptr && leg < 2; ++leg) {
    const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + 4;  // pitch, then roll
    constexpr double kUnclipped = std::numeric_limits<double>::infinity();
    Eigen::Vector2d pair(drive_torque(c.joints[j], q[j], v[j], kUnclipped, nullptr),
                         drive_torque(c.joints[j + 1], q[j + 1], v[j + 1], kUnclipped, nullptr));
    const int motors = drivers::clip_ankle_torques_rt(*ankle_motors, leg, Eigen::Vector2d(q[j], q[j + 1]), pair);
    if (motors < 0) continue;  // unsolvable: the joints' own clips stand
    motors_clipped += motors;
    tau[j] = pair[0];
    tau[j + 1] = pair[1];
    saturated[j] = saturated[j + 1] = false;
  }
  return motors_clipped + static_cast<int>(std::count(saturated.begin(), saturated.end(), true));
}

}  // namespace kuavo::sim
