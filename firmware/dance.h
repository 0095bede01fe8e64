// Dance mode: the online stack (controllers/stack) in the firmware, split over the two
// tasks the simulator also runs -- the 500 Hz control task (estimator -> reference -> WBC)
// and the 50 Hz planning task (centroidal MPC) -- with one LatestValue in each direction:
//
//   control task  --PlanRequest (epoch, estimate q v, its time)-->  planning task
//   control task  <--PlanMessage (epoch, ReferencePlan)------------  planning task
//
// Time: the stack runs in motion time, 0 at the cycle that entered dance (DanceControl::
// start_ns); the watchdog sees the plan's stamp back in firmware time.
//
// Hand-over from ready: stand-up takes the robot to the motion's first frame
// (dance_standing_pose, start-up), so on entering dance the stack starts (stack_begin_rt)
// where the robot already stands: the estimator is reset from the sensors, the first plan
// is the motion's own knots (kinematic, made on the control task) until the planner's first
// MPC plan arrives, and the command cross-fades from the standing controller's PD law to
// the WBC's over FirmwareConfig::dance_blend_ns (exact blend of the two torque laws, so the
// torque at any state moves continuously from one to the other).
//
// Estimator: fault 17 from estimator_diverged_rt (below).
//
// Planner trouble, in order (ages of the last plan the planner delivered, from the state it
// used): older than plan_stale_ns -> the control task replaces it once with the motion's
// kinematic knots (the stack's own fallback when an MPC iteration fails); older than
// plan_max_age_ns -> fault 16 (watchdog) -> damping. A plan with a non-finite value is
// dropped on arrival (counted) and so counts as not delivered. The WBC's own fallbacks
// (hold, stiff PD) and the safety filter stay behind that.
//
// After the motion's end the reference holds its last frame; dance_settle_ns later
// dance_done asks the mode machine for finish, where the same controller keeps running
// while the cycle fades its gains out (it keeps the robot up longer than a held command:
// held, the sagging robot pressed a joint past its stop, fault 21, in the firmware-in-the-
// loop dance). The robot sags as the gains fade and the controller's references may then
// run past a stop: in finish they are put on it whatever the excess (counted apart).
#pragma once

#include <cstdint>
#include <string>

#include "controllers/planner/motion_plan.h"
#include "controllers/planner/reference_plan.h"
#include "controllers/stack/online_stack.h"
#include "controllers/standing/standing_controller.h"
#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"
#include "firmware/control_cycle.h"
#include "rtos_shim/latest_value.h"

namespace kuavo::firmware {

// LatestValue copies its values in the real-time path and so wants nothrow special
// members; Eigen's fixed-size types do not allocate and cannot throw, but do not say so.
// The two messages below say it for them (a throw would terminate; none can happen).

// Control -> planner: the latest estimate. epoch 0: no dance running (the planner idles).
struct PlanRequest {
  std::uint32_t epoch = 0;
  std::uint64_t sequence = 0;  // one per control tick; the planner plans each request once
  hal::TimeNs t_state_ns = 0;  // motion time of the estimate
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  hal::AnkleMotorLimits ankle_motors;  // at the same sample, as the WBC bounds them

  PlanRequest() noexcept {}
  PlanRequest(const PlanRequest& o) noexcept { *this = o; }
  PlanRequest& operator=(const PlanRequest& o) noexcept {
    epoch = o.epoch, sequence = o.sequence, t_state_ns = o.t_state_ns, q = o.q, v = o.v;
    ankle_motors = o.ankle_motors;
    return *this;
  }
};

// Planner -> control: a plan for one epoch (plans of an earlier dance are dropped).
struct PlanMessage {
  std::uint32_t epoch = 0;
  planner::ReferencePlan plan{};

  PlanMessage() noexcept {}
  PlanMessage(const PlanMessage& o) noexcept { *this = o; }
  PlanMessage& operator=(const PlanMessage& o) noexcept {
    epoch = o.epoch, plan = o.plan;
    return *this;
  }
};

// The two hand-overs. One writer and one reader each: the control task writes `request`
// and reads `plan`; the planning task the reverse. Static storage (~25 KB).
struct DanceChannels {
  rtos::LatestValue<PlanRequest> request;
  rtos::LatestValue<PlanMessage> plan;
};

// The planning task's state. The MPC workspace is ~15 MB: static storage.
//
// Rehearsal: until the dance's first request (stand-up, ready), each planner period plans
// the motion's opening -- the robot at its first frame, at rest, motion time 0 -- from a
// cold start and throws the plan away. The dance's first MPC iteration then finds its
// ~15 MB workspace written 20 ms before, not seconds before: on a VM that write-protects
// guest memory left unwritten (dirty-page tracking; a page idle 1 s costs 12-15 us at its
// next write) the first iteration took 40-70 ms, past plan_max_age_ns, and the dance ended
// in fault 16 at its start. On the NUC the same keeps the caches and TLB warm. The dance's
// first request resets the workspace (a new epoch: stack_reset_planner_rt), so the dance
// plans as it would without rehearsals. Rehearsals feed no counter of the stack's
// (mpc_failures, ...).
struct DancePlanner {
  const model::Model* model = nullptr;
  const stack::StackConfig* config = nullptr;
  const planner::MotionPlan* motion = nullptr;
  stack::PlannerWorkspace ws;
  std::uint32_t epoch = 0;          // of the last request planned
  std::uint64_t last_sequence = 0;  // of the last request planned
  std::uint64_t plans = 0;
  bool rehearse = true;             // plan the opening while idle (above)
  std::uint64_t rehearsals = 0;
  std::uint64_t rehearsal_failures = 0;  // the MPC did not solve the opening
  planner::ReferencePlan rehearsal_plan{};
};

struct DanceCounters {
  std::uint64_t plans_taken = 0;     // planner plans that became active
  std::uint64_t plans_rejected = 0;  // non-finite plans dropped on arrival
  std::uint64_t plans_old_epoch = 0; // plans of an earlier dance, dropped
  std::uint64_t kinematic_fallbacks = 0;
  std::uint64_t wbc_not_ok_ticks = 0;
  std::uint64_t begin_failures = 0;  // stack_begin_rt refused the sensors
  std::uint64_t references_limited = 0;  // joint references put back on a stop (dance.cpp)
  std::uint64_t finish_references_limited = 0;  // the same in finish, where any excess is (gains fading)
  std::uint64_t torques_saturated = 0;   // joint torques clipped at the peak, as a drive does
  double max_torque_demand_x = 0.0;      // largest |tau_ff| / peak the WBC asked for (> 1 only)
};

// The control task's state. ~0.4 MB (the stack's control workspace): static storage.
struct DanceControl {
  drivers::AnkleMotors ankle_motors;  // mapped each tick for the WBC, handed to the MPC with each plan request
  hal::SerialLegDriveLimits serial_drives;  // copied into the WBC's workspace each tick
  dynamics::JointVector torque_cap_Nm = dynamics::JointVector::Constant(qp::kInfinity);  // likewise
  const model::Model* model = nullptr;
  stack::StackConfig config{};
  const planner::MotionPlan* motion = nullptr;
  DanceChannels* channels = nullptr;
  stack::ControlWorkspace stack;
  // Scratch of the control task's own kinematic plans (first plan, stale fallback).
  dynamics::Data data;
  planner::PlanWindow window;
  planner::ReferencePlan scratch_plan;
  // The first plan (the motion's knots from time 0), made once by dance_init: made in the
  // dance's first tick, the worst cycle of a whole dance, it cost that tick ~29 us.
  planner::ReferencePlan first_plan;
  hal::CommandFrame standing_command{};  // the cross-fade's other law
  hal::TimeNs blend_ns = 0, settle_ns = 0, stale_ns = 0;  // from FirmwareConfig
  hal::TimeNs duration_ns = 0;                            // the motion's
  bool running = false;
  bool finishing = false;             // the mode is finish (set by CycleController)
  std::uint32_t epoch = 0;            // of the current (or last) dance
  hal::TimeNs start_ns = 0;           // firmware time of motion time 0
  hal::TimeNs plan_stamp_ns = 0;      // firmware time of the last delivered plan's state
  bool on_kinematic_fallback = false; // the active plan is the control task's stale fallback
  std::uint64_t sequence = 0;
  wbc::WbcStatus last_wbc = wbc::WbcStatus::kOk;
  DanceCounters counters{};
  // Rehearsal of the dance's first tick (dance_rehearse_rt): before the first dance only.
  bool rehearse = true;
  bool danced = false;  // a dance has started since dance_init
  std::uint64_t rehearsals = 0;
  std::uint64_t rehearsal_failures = 0;  // the stack did not start, or its WBC did not solve
  hal::CommandFrame rehearsal_command{};  // discarded
};

// --- Start-up (not real-time) ---

// The online stack as the robot image runs it, for kuavo_fw and kuavo_fw_sim alike: the MPC
// planner, and the upper body planned for the moment its command acts -- the buses answer
// the previous tick's command, so the joint readings the tick runs on are one control
// period old (StackConfig::upper_body_delay_s). Measured in the firmware loop against
// `kuavo simulate` (770acda's motions, carpet, seeds 2-4), arms RMS: cmu_05_07 +20/+20/+20 %
// without, +13/+14/+14 % with it; perfume +15/+13/+14 → +10/+8/+9 %; cmu_05_20 +19/+19/+19
// → +11/+11/+11 %; the legs within 0.0009 rad of before. 4 ms (the Ruiwo bus's 250 Hz
// period) left cmu_05_07's arms at +15 %.
stack::StackConfig firmware_stack_config(const FirmwareConfig& fw_config);

// Binds the motion (finished and, if wanted, balance-filtered; read-only from here on) and
// the channels, prepares both workspaces. The config's planner is normally kMpc. false with
// a message if the stack's configuration or the motion is unusable.
bool dance_init(DanceControl& control, DancePlanner& planner, DanceChannels& channels, const model::Model& model,
                const stack::StackConfig& config, const FirmwareConfig& fw_config,
                const planner::MotionPlan& motion, const char*& error);

// Binds the ankle motors' torque limits, mapped through the leg transmissions at each tick's
// sampled ankle angles, into the WBC's QP (controllers/wbc/wbc.h) and the MPC's stance-leg
// torque barrier (drivers/transmission/ankle_motors.h). Start-up; without it the WBC limits
// joint torques only.
void dance_set_ankle_motors(DanceControl& control, const drivers::DriversConfig& drivers);
// Binds the CSP hip and knee drives' clamps, joint side, and their velocity feed-forward
// (the torque offset carries kd·v_ref) into the WBC's QP (hal/serial_drive_limits.h).
// Start-up; inactive unless all eight are CSP drives. Also caps each Ruiwo joint's planned
// torque at what its MIT frame carries (MotorConfig::torque_max_Nm, joint side).
void dance_set_serial_leg_drives(DanceControl& control, const drivers::DriversConfig& drivers);

// Start-up, before the drivers' validation: the CSP binding (firmware/README.md, leg binding).
// Every CiA 402 drive -- the legs' and the shoulder pitches' -- in CSP, holding the WBC's output
// gains, the law the dance commands (drivers::use_csp_leg_drives, use_csp_shoulder_drives).
// false + message if a gain is not representable.
bool dance_use_csp_drives(drivers::DriversConfig& drivers, std::string& message);

// Makes the standing controller stand at the motion's first frame: its joint pose, and
// its CoM target where that pose puts the CoM over the feet. Start-up; after firmware_init.
void dance_standing_pose(Firmware& fw, const planner::MotionPlan& motion);

// --- Control task (real-time) ---

// Before each firmware cycle: takes a newly delivered plan (checks it), falls back to the
// motion's knots if the plan has gone stale, and fills the inputs the dance owns: the plan
// age and estimator watchdogs and dance_done. Stops the dance once the mode left dance and
// finish (a fault, the e-stop): one cycle late, which only costs the planner one request.
void dance_before_cycle_rt(DanceControl& d, const Firmware& fw, hal::TimeNs now_ns, CycleInputs& in) noexcept;

// The dance controller's command for this tick (starts the stack on the first call of a
// dance). `standing` is the standing controller's state (the cross-fade's other law).
// false if the stack could not start: `out` is then left alone and the caller's cycle
// sends damping in its place (no fault is needed: nothing reached a motor).
bool dance_step_rt(DanceControl& d, control::StandingState& standing, const hal::SensorFrame& sensors,
                   hal::TimeNs now_ns, hal::CommandFrame& out) noexcept;

// Leaves the dance (mode left dance/finish): the planner idles from its next request on.
void dance_stop_rt(DanceControl& d) noexcept;

// The control task's rehearsal, the counterpart of the planner's (DancePlanner): in each
// stand-up and ready tick before the first dance, after the command has gone out, the
// dance's first tick runs on this tick's sensors -- the stack started at motion time 0 and
// one control tick (estimator, WBC QP from a cold start) -- and its command is discarded.
// The dance's first tick then finds the stack's memory written 2 ms before and its code
// and data in the caches. Why: on a VM host that write-protects guest memory left unwritten
// (firmware/README.md) that first tick took up to 1.5 ms, the whole dance's worst cycle, after
// the 2 s stand-up left the control state untouched; on the NUC the same is a cold WBC QP.
// The dance's first tick starts the stack afresh (stack_begin_rt resets the estimator, the
// WBC and the plan), so the dance runs to the bit as it would without rehearsals
// (Dance.ControlRehearsalsLeaveTheDanceUnchanged). Touches no counter of the dance's and no
// stage stamp (the timing run's per-stage figures stay the dance's).
void dance_rehearse_rt(DanceControl& d, Mode mode, const hal::SensorFrame& sensors) noexcept;

// Fault 17's input. The estimator reports kDiverged for a non-finite state (it re-seeds)
// and for trace(P) over its limit -- but the swing corners' ×1000 process noise adds
// ~1.8 m² per corner coordinate per tick, so the whole trace passes any limit in the first
// tick of every step. Diverged here: the re-seed, or the base block of P (position and
// velocity, the states the WBC uses) over the estimator's own trace limit.
[[nodiscard]] bool estimator_diverged_rt(const DanceControl& d) noexcept;

// The cross-fade: out = (1 - a)·standing + a·out as torque laws, joint by joint, so that
// tau(q, v) of the result is that blend of the two laws' torques at every state (kp, kd
// and tau_ff blend linearly, the references by their gains). A joint where either command
// is not kPdTorque keeps out's. a in [0, 1].
void blend_torque_laws_rt(const hal::CommandFrame& standing, double a, hal::CommandFrame& out) noexcept;

// The output stage's reference limit: a joint reference at most slack_rad past a stop is put
// on the stop (counted in `limited`); one further out is left for the safety filter (fault
// 31). Dance: 0.05 rad (dance.cpp says why); finish: any excess (infinite slack).
void limit_references_rt(const model::Model& m, double slack_rad, hal::CommandFrame& out,
                         std::uint64_t& limited) noexcept;

// Every finite field of a plan; a plan that fails is never used.
[[nodiscard]] bool reference_plan_finite(const planner::ReferencePlan& plan) noexcept;

// --- Planning task (real-time, lower priority) ---

// Takes the latest request; if it is new and a dance runs, plans into the channel's back
// slot and returns true (the caller then publishes: channels.plan.publish_rt(), at once on
// the robot, after the modelled latency in the lockstep tests). false: nothing to publish
// (idle: a rehearsal of the opening ran, see DancePlanner).
bool dance_plan_rt(DancePlanner& p, DanceChannels& channels) noexcept;

// The firmware's controller: standing in stand-up and ready, the dance in dance and in
// the finish after a dance. A template argument of firmware_cycle_rt (no virtual call).
struct CycleController {
  Firmware* fw = nullptr;
  DanceControl* dance = nullptr;  // nullptr: no motion loaded, standing only
  void operator()(const hal::SensorFrame& sensors, hal::CommandFrame& out) const noexcept;
};

}  // namespace kuavo::firmware
