// Worst-case timing on the robot (`kuavo_fw --timing MOTION`): a whole dance's control ticks
// and MPC iterations through the firmware's task bodies (control_task.h), under the real-time
// set-up (mlockall, SCHED_FIFO, CPU affinity), each tick optionally after evicting the caches.
// The sensors are simulated from the motion itself: the joints as the motion moves them fed
// to the drivers' bus emulators over socketpairs (emulated_buses.h; so the drivers encode
// and decode every frame), the IMU from the motion's base. Ticks run back to back on
// virtual time stamps (2 ms apart); every stage is timed on rtos_shim's clock:
//   drivers    receive + send (robot_io.h)
//   estimator  reference + state estimator (the stack's tick up to the WBC)
//   wbc        the whole-body QP and its command
//   output     the rest of the cycle: watchdogs, modes, dance output stage, ramp, filter
//   cycle      the whole control task (the sum)
//   mpc        one planning-task iteration (its own CPU on the robot; run in turn here)
// A cycle misses its deadline beyond the control period, an MPC iteration beyond the
// planner period; the control task's overruns (a release missed) count as misses too, except
// with evict_caches, whose 64 MB write is part of the body.
// After the dance, the machine's own floor (rtos_shim/stall_probe.h): the control task's
// CPU and priority spin half of each control period for stall_probe_s, and the longest time
// the CPU was taken away from them is reported beside the stages (not a deadline: the
// machine's, which no controller change moves).
#pragma once

#include <cstdint>
#include <string>

#include "controllers/planner/motion_plan.h"
#include "drivers/config/drivers_config.h"
#include "firmware/control_task.h"
#include "rtos_shim/rt_setup.h"
#include "rtos_shim/stall_probe.h"

namespace kuavo::firmware {

struct TimingConfig {
  bool evict_caches = false;  // write kEvictBytes before each control tick
  std::uint64_t seed = 1;     // the emulators' generators (no fault is injected)
  rtos::RtConfig rt{};        // the control task's real-time set-up (the loop's thread)
  double stall_probe_s = 10.0;  // after the dance; 0: none
};

// Larger than the NUC's i9-13900H last-level cache (24 MB) and this machine's.
inline constexpr std::size_t kEvictBytes = 64u << 20;

struct StageFigures {
  double p50_us = 0.0, p99_us = 0.0, p9999_us = 0.0, max_us = 0.0;
  std::uint64_t samples = 0, deadline_misses = 0;
  // Motion time of the slowest sample [s] (−1: none, or the MPC's): the same time run after
  // run points at the work that tick does, a different one at the machine.
  double max_at_s = -1.0;
};

struct TimingReport {
  StageFigures drivers, estimator, wbc, output, cycle, mpc;
  std::uint64_t dance_ticks = 0;
  // rtos_shim's loop counters: control-task cycles that ended past the next release (body
  // plus wake latency; with evict_caches the eviction is in the body) and the worst wake latency.
  std::uint64_t control_overruns = 0, planner_overruns = 0;
  std::uint64_t rehearsals = 0, rehearsal_failures = 0;  // the planner's, before the dance (dance.h)
  std::uint64_t control_rehearsals = 0, control_rehearsal_failures = 0;  // the control task's (dance.h)
  // Control-task release times dropped to recover from its overruns (each one a tick the
  // dance did not run: the stack follows the clock, not a tick count).
  std::uint64_t control_skipped_periods = 0;
  double max_wake_latency_us = 0.0;
  // The stall probe after the dance: what the machine took from a spinning thread on the
  // control task's CPU and priority, and that thread's worst wake latency.
  rtos::StallStats machine{};
  double machine_wake_latency_us = 0.0;
  bool danced_to_end = false;  // the dance ran to its finish without a fault
  Fault fault = Fault::kNone;
  bool realtime = false;       // the real-time set-up fully applied
  std::string realtime_status; // what failed, if anything
  std::string error;           // set if the run could not be set up
};

// Runs the dance (already loaded and checked: motion::load_motion) through static firmware
// state the caller owns (kuavo_fw's). Start-up allocates; the timed loop does not.
bool run_timing(const model::Model& model, const drivers::DriversConfig& drivers, const FirmwareConfig& fw_config,
                const planner::MotionPlan& motion, const TimingConfig& config, Firmware& firmware, DanceControl& dance,
                DancePlanner& planner, DanceChannels& channels, RobotIo& io, TimingReport& report);

// The report as a table (one line per stage) for the operator.
std::string timing_table(const TimingReport& r, hal::TimeNs control_period_ns, hal::TimeNs planner_period_ns);

}  // namespace kuavo::firmware
