// One firmware-in-the-loop run, as kuavo_fw_sim makes it: the robot hangs on its gantry
// while the firmware boots, self-checks and stands up (to the motion's first frame), is
// released in ready, stands 0.2 s, is asked to dance (as an operator would), dances, is
// taken back on the gantry as the firmware enters finish (which fades every gain to
// damping: no free-standing robot survives that), finishes, and is in damping 0.5 s later
// -- or a fault latches (damping) or it falls, and the run ends 0.5 s after. Without a
// motion it stands for stand_s.
//
// The CSV log (one row per 2 ms tick) holds only virtual-time quantities: same
// configuration and seed, same bytes (its sha256 is in the summary). The summary carries
// `kuavo simulate`'s figures for the dance plus the firmware's own, and, with a fault drill
// armed mid-dance (fault_drill.h), when it was armed, the fault that latched and how long
// the command took to reach damping.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/sitl/fault_drill.h"
#include "firmware/sitl/firmware_loop.h"
#include "sim/motion_loop.h"

namespace kuavo::firmware::sitl {

struct SitlConfig {
  LoopConfig loop{};
  std::string log_path;       // empty: no file (the hash is still computed)
  double stand_s = 5.0;       // without a motion
  hal::TimeNs plan_latency_ns = 4'000'000;  // the planning task's result, applied this much later
  hal::TimeNs settle_ns = 200'000'000;      // standing in ready off the gantry before the dance
  AllocationCounter count_allocations = nullptr;
  // A fault drill (fault_drill.h), armed at the first tick in dance mode at least
  // inject.at_s after the cycle that entered dance; off unless `inject_fault`.
  bool inject_fault = false;
  Injection inject{};
  // false: the recovery step's trigger on the soles, not the image's holdable soles
  // (planner::set_holdable_soles; kuavo_fw_sim --holdable-soles off).
  bool holdable_soles = true;
  // > 0: the recovery step's fast swing as a fallback (planner::RecoveryStepConfig::fast_swing_s;
  // kuavo_fw_sim --recovery-fast-swing S); 0: off, the image's default.
  double recovery_fast_swing_s = 0.0;
  // The stage surface's sink under the standing robot (estimator::EstimatorConfig::stance_sink_m;
  // kuavo_fw_sim --surface-sink M); 0: a hard floor, the image's default.
  double surface_sink_m = 0.0;
};

// What the drill did: when it was armed, the first fault latched from then on, and the
// virtual time from the tick it was armed before to the first tick whose command is damping
// on every joint (0: that same tick).
struct InjectionReport {
  Injection requested{};
  bool armed = false;
  std::string target, error;  // what was hit; why arming failed (empty: it did not)
  double armed_at_s = -1.0;   // virtual time of the run
  Fault fault = Fault::kNone;
  double latency_to_damping_ms = -1.0;  // -1: no damping after the injection
  // Reply frames the emulators did not send from then on (lost, or a silent device's).
  std::uint64_t frames_lost = 0;
};

struct BusFigures {
  std::string interface;
  double planned_load = 0.0;        // fraction of the bus time (drivers/bus/bus_plan.h)
  double frames_per_s = 0.0;        // frames the emulator received and sent, over the run
};

struct SitlSummary {
  sim::MotionSummary motion;        // kuavo simulate's keys (tracking over the dance mode)
  bool danced_to_end = false;       // finish came from the motion's end, then damping, no fault
  std::string final_mode;
  std::vector<Fault> faults;        // latched, in order (one per clear; a run has no clears)
  double fault_at_s = -1.0;
  double dance_started_at_s = -1.0;  // virtual time of the motion's time 0 (-1: no dance)
  DanceCounters dance{};            // the output stage: references on a stop, torques clipped
  std::uint64_t rehearsals = 0, rehearsal_failures = 0;  // the planner's, before the dance (dance.h)
  std::uint64_t control_rehearsals = 0, control_rehearsal_failures = 0;  // the control task's (dance.h)
  std::array<std::uint64_t, 6> leg_torque_clamps{};  // drivers' clamps per leg slot (both legs)
  std::uint64_t refused_commands = 0, csp_holds = 0, drive_loop_saturations = 0;
  std::uint64_t ruiwo_clamp_events = 0;
  std::uint64_t binding_failures = 0;
  WireCheck wire{};
  std::size_t allocations_control = 0, allocations_planner = 0;  // while dancing
  bool allocations_counted = false;
  std::vector<BusFigures> buses;
  std::string legs;
  bool injected = false;  // config.inject_fault: `injection` holds the report
  InjectionReport injection{};
};

SitlSummary run_firmware_sim(const model::Model& model, const planner::MotionPlan* motion, const SitlConfig& config);

std::string sitl_summary_json(const SitlSummary& s);

}  // namespace kuavo::firmware::sitl
