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
  // Joint samples: Ruiwo replies come every 4 ms; 4 missed replies (16 ms,
  // ruiwo::kMaxConsecutiveMisses) make the drivers call a motor silent. 18 ms is
  // one tick past that, so frame loss alone does not trip it first.
  hal::TimeNs sensor_max_age_ns = 18'000'000;
  // MTi streams at 400 Hz (2.5 ms); 4 missed packets.
  hal::TimeNs imu_max_age_ns = 10'000'000;
  // MPC at 50 Hz: a plan's state is at most one period plus the iteration's latency old
  // when the next arrives. One lost or late iteration is bridged (plan_stale_ns below: the
  // motion's kinematic knots); a plan older than two periods plus 10 ms of latency means
  // two were lost: the planner stalled.
  hal::TimeNs plan_max_age_ns = 50'000'000;
  // Dance: the planner's result is replaced by the motion's kinematic knots (the stack's
  // fallback) once older than this: one planner period plus 10 ms of compute and hand-over
  // (the MPC iteration: p50 6.4 ms, BENCHMARKS.md). A single lost, late or refused plan is
  // so bridged without a fault; plan_max_age_ns above makes a stalled planner one.
  hal::TimeNs plan_stale_ns = 30'000'000;
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

  // --- Dance (firmware/dance.h) ---
  // The planning task's period: 50 Hz, the MPC's rate (ARCHITECTURE.md rates); must equal
  // the stack's plan period.
  hal::TimeNs planner_period_ns = 20'000'000;
  // Entering dance, the command cross-fades from the standing PD law to the WBC's over
  // this long: many drive PD time constants (~10 ms), short against the motion's features.
  hal::TimeNs dance_blend_ns = 200'000'000;
  // After the motion's last frame the reference holds it this long before finish.
  hal::TimeNs dance_settle_ns = 500'000'000;

  // --- Real time (rtos_shim) ---
  int fifo_priority = 80;
  int cpu = -1;  // -1: no pinning
  // The planning task: below the control task, so a long MPC iteration can never delay a
  // control tick on a shared core; on its own core when planner_cpu is set.
  int planner_fifo_priority = 70;
  int planner_cpu = -1;  // -1: no pinning
  // The CPUs' idle-exit latency bound while the firmware runs (rtos::RtConfig): 0 = no idle
  // state that takes time to leave. -1 leaves the system's setting.
  int cpu_dma_latency_us = 0;
};

// Checks ranges and consistency; false with a message naming the field.
bool validate_firmware_config(const FirmwareConfig& config, std::string& message);

}  // namespace kuavo::firmware
