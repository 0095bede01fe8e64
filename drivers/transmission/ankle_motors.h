// The ankle pairs in motor space, one map for every binding. On the 4Pro two motors (A, B)
// drive ankle pitch and roll through the parallel linkage (FACTS.md §2.4) and each clamps
// its own torque, which bounds pitch and roll jointly (about 54 N·m of pitch alone, 24.5 of
// roll alone near the zero pose) as no joint-space box can. The firmware builds this from
// its drivers configuration and the simulator from the default one (its plants clip the
// same two motors); each tick maps it at the sampled ankle angles into the
// hal::AnkleMotorLimits the WBC and the MPC bound the motors with. Real-time safe.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "controllers/hal/ankle_motor_limits.h"
#include "controllers/hal/types.h"
#include "drivers/transmission/leg_transmission.h"

namespace kuavo::drivers {

struct DriversConfig;  // drivers/config/drivers_config.h

struct AnkleMotors {
  bool active = false;
  std::array<LegTransmission, 2> legs{};
  std::array<Eigen::Vector2d, 2> limit_Nm{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};  // per motor (A, B)
  // The binding's velocity feed-forward per motor (CSP: the drive's kd), hal::AnkleMotorLimits.
  std::array<Eigen::Vector2d, 2> velocity_gain_Nm_s_per_rad{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  std::uint64_t unmapped_ticks = 0;  // ticks an ankle could not be mapped (joint-space limits only)
};

// Each ankle slot's drive clamp (and, CSP, its kd) from the drivers configuration; inactive
// when a slot has no drive (not a CiA 402 ankle).
AnkleMotors ankle_motors_from_config(const DriversConfig& drivers);

// One leg's ankle motor torques (A, B) for the joint torques `tau` (pitch, roll) at the joint
// angles `q`: the linkage's J⁻ᵀ, then each motor's linear transmission. false (motor
// unchanged) when the linkage cannot be solved at q.
bool ankle_motor_torques_rt(const AnkleMotors& a, int leg, const Eigen::Vector2d& q, const Eigen::Vector2d& tau,
                            Eigen::Vector2d& motor) noexcept;

// Fills `out` at the ankle angles (pitch, roll) of each leg: joint_to_motor's columns are
// the motor torques of the two unit joint torques. false, and `out` inactive (joint-space
// limits only), when a leg's linkage cannot be solved there.
bool map_ankle_motors_rt(const AnkleMotors& a, const std::array<Eigen::Vector2d, 2>& ankle_rad,
                         hal::AnkleMotorLimits& out) noexcept;
// The same at the sampled ankle angles; a leg with an invalid sample leaves `out` inactive
// too. Each tick `out` is inactive is counted in a.unmapped_ticks.
void map_ankle_motors_rt(AnkleMotors& a, const hal::SensorFrame& sensors, hal::AnkleMotorLimits& out) noexcept;

// What one leg's ankle pair delivers of the joint torques `tau` (pitch, roll) at the joint
// angles `q`: mapped to the motors, each clipped at its limit as its drive does, mapped back
// (unchanged when no motor clips). Returns the number of motors that clipped (0..2), or -1
// (tau unchanged) when the linkage cannot be solved at q.
int clip_ankle_torques_rt(const AnkleMotors& a, int leg, const Eigen::Vector2d& q, Eigen::Vector2d& tau) noexcept;

}  // namespace kuavo::drivers
