// The firmware's own settings (rates, watchdog thresholds, safe-mode gains):
// a plain struct with defaults, validated once at start-up. The drivers'
// settings (buses, motors, transmissions) come from drivers/config.
#pragma once

#include <string>

#include "controllers/hal/types.h"

namespace kuavo::firmware {

struct FirmwareConfig {
  // Control tick: 500 Hz, the WBC rate (FACTS.md §4.1; ARCHITECTURE.md rates).
  hal::TimeNs control_period_ns = 2'000'000;
  // Ruiwo buses are served every 2nd tick: 250 Hz keeps them under 70 % load
  // (drivers/README.md, default bus plan).
  int ruiwo_divider = 2;

  // --- Watchdogs (all must trip inside the 20 ms budget of issue 7) ---
  // Joint samples: Ruiwo replies come every 4 ms; 3 missed replies (12 ms,
  // ruiwo::kMaxConsecutiveMisses) make the drivers call a motor silent. 14 ms is
  // one tick past that, so frame loss alone (3 in a row ~1e-6 at 1 %) does not trip it.
  hal::TimeNs sensor_max_age_ns = 14'000'000;
  // MTi streams at 400 Hz (2.5 ms); 4 missed packets.
  hal::TimeNs imu_max_age_ns = 10'000'000;
  // MPC at 50 Hz applies after at most one period (lockstep default delay): a
  // result older than two periods means the planner stalled.
  hal::TimeNs plan_max_age_ns = 40'000'000;
  // Issue 7 / sim fall criterion: 45 degrees of torso tilt.
  double max_tilt_rad = 0.7853981633974483;
  // Self-check: every sample valid and fresh; drives boot in ~0.1 s
  // (drivers/README.md), so 3 s is generous.
  hal::TimeNs self_check_timeout_ns = 3'000'000'000;

  // --- Safety filter ---
  // Largest PD gains accepted: 2.5x the stiffest standing gain (leg kp 400,
  // kd 6; controllers/standing), Ruiwo's wire maximum kd is 50.
  double kp_max_Nm_per_rad = 1000.0;
  double kd_max_Nm_s_per_rad = 50.0;

  // --- Modes ---
  // Damping: tau = -kd v. 3 Nm·s/rad is the ankle's standing kd (the weakest
  // joint group): it slows a fall without fighting the operator.
  double damping_kd_Nm_s_per_rad = 3.0;
  hal::TimeNs stand_up_duration_ns = 2'000'000'000;  // gains ramp 0 -> 1
  hal::TimeNs finish_duration_ns = 1'000'000'000;    // gains ramp 1 -> 0

  // --- Real time (rtos_shim) ---
  int fifo_priority = 80;
  int cpu = -1;  // -1: no pinning
};

// Checks ranges and consistency; false with a message naming the field.
bool validate_firmware_config(const FirmwareConfig& config, std::string& message);

}  // namespace kuavo::firmware
