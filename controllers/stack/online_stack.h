// The online stack as two step functions, identical in the firmware and the simulator
// (only the binding that fills SensorFrame and consumes CommandFrame differs):
//
//   control task, 500 Hz:  sensors → estimator → reference at now (from the active plan)
//                          → WBC → joint commands            stack_control_tick_rt
//   planning task, 50 Hz:  latest estimate + motion → a ReferencePlan
//                          (kinematic: the motion itself; MPC: one real-time iteration)
//                                                             stack_plan_rt
//   hand-over:             the plan becomes active when it arrives  stack_apply_plan_rt
//
// The two tasks own separate workspaces (ControlWorkspace, PlannerWorkspace), so on the
// robot they can run on two threads with a LatestValue in each direction; in the
// simulator the lockstep scheduler calls them in virtual time. Both workspaces are large
// (~0.3 MB and more): static storage or one start-up allocation, never a stack.
#pragma once

#include <cstdint>

#include "controllers/estimator/estimator.h"
#include "controllers/mpc/mpc.h"
#include "controllers/planner/liftoff_hold.h"
#include "controllers/planner/plan_anchor.h"
#include "controllers/planner/recovery_step.h"
#include "controllers/planner/reference_plan.h"
#include "controllers/stack/lean_trim.h"
#include "controllers/wbc/wbc.h"

namespace kuavo::stack {

// Stable numbers.
enum class PlannerKind : std::uint8_t {
  kKinematic = 0,  // the WBC tracks the motion as is (no dynamics in the plan)
  kMpc = 1,        // centroidal RTI-MPC
};
const char* to_string(PlannerKind k);
bool parse_planner(const char* text, PlannerKind& out);  // "kinematic" | "mpc"

struct StackConfig {
  PlannerKind planner = PlannerKind::kKinematic;
  double plan_period_s = 0.02;  // 50 Hz; also the spacing of the plan's knots
  // The estimator treats a planned touchdown as contact only after this long: a foot that
  // lands late (soft ground, a robot behind its plan) would otherwise count as fixed while
  // it still moves, and leg odometry would carry its motion into the base estimate.
  double estimator_touchdown_delay_s = 0.03;
  // Opt-in (0: off). A foot the WBC loaded with less than this much normal force on the last
  // tick (the sum over its corners of the QP's answer) is not a stance foot for the estimator,
  // though the plan holds it down: the controller has let go of it, and an unloaded sole drags,
  // tips onto an edge or lifts, so its corners are not fixed points for leg odometry. Only
  // while the other foot carries at least this much, and only after a tick the QP solved.
  // Measured (perfume's motion of 2e6abcb, carpet, show set, seed 27, pushed 10 N·s at 6.37 s,
  // sensors ideal, so that only the filter errs): after the push the WBC unloads the right
  // foot (15-50 N), which drags at up to 0.6 m/s for 0.7 s under stance flags; the contact
  // gate (contact_velocity_gate_m_s) takes its corners out only past 0.3 m/s, and the base
  // velocity estimate runs 0.03-0.06 m/s off for 1.5 s (position 5.2 cm off), and the run
  // falls at 8.28 s (with the true state it dances to the end). With 50 N: the error stays
  // within 0.003 m/s, the position within 4 mm, and the run dances to the end. Not yet the default:
  // its show campaign (and the retargets whose closed-loop check runs this stack) are to come.
  double estimator_unloaded_foot_N = 0.0;
  // Opt-in: the estimate's base tilt trimmed until the WBC's horizontal forces are the ones
  // the CoM obeys (lean_trim.h), for the IMU's tilt error and the model's CoM error; learned
  // in every quiet phase (kAlways) or in the motion's opening stand only (kOpening). Off:
  // neither has yet shown fewer falls in the show campaign end to end (lean_trim.h).
  LeanTrimConfig lean_trim{};
  // A newly applied plan takes over from the previous one linearly over this long (the WBC
  // reference is the blend of both plans at the tick's time; contact flags are the new
  // plan's). 0: switch at once. Measured (stack_bench, the built-in dance with the MPC):
  // consecutive plans disagree, and at a switch the WBC QP's warm start is off by most of its
  // working set; 0.02 s cuts the ticks over 100 µs of computation ~10× and the worst by a
  // quarter, and the demo's closed-loop results are unchanged (dance floor legs 0.029 vs
  // 0.028 rad, carpet 0.049 vs 0.050, horizon 0.6 s falls at 24.94 s either way). The
  // default since the firmware's finish puts references past a stop on it (dance.h): the
  // blend had left one 0.052 rad past at the end of the firmware-in-the-loop dance.
  double plan_blend_s = 0.02;
  // The binding's delay from the joints' sample to the command acting on them: the arm and
  // head joints (the WBC's joint tasks) are planned for that moment -- their measured
  // angles predicted forward (q + q̇·d) and their reference advanced (q_ref + q̇_ref·d +
  // ½q̈_ref·d², q̇_ref + q̈_ref·d) before the WBC. 0 in `kuavo simulate` (sensors sampled at
  // the tick, the command applied at once); the firmware's buses answer the previous tick's
  // command, so its joint readings are one tick old (firmware_stack_config, 2 ms). Measured
  // (cmu_05_07's motion, carpet, seed 2, arms RMS against the motion): `kuavo simulate`
  // 0.01222 rad; with --latency-ticks 1 / 2, 0.0134 / 0.0152, and 0.01231 / 0.01241 with d =
  // 2 / 4 ms; the firmware loop 0.01461, and 0.01385 with d = 2 ms. The legs are left out:
  // the WBC drives them through the contact, swing and CoM tasks, and predicting them too
  // made the firmware loop's legs worse (0.0577 against 0.0555 rad).
  double upper_body_delay_s = 0.0;
  wbc::WbcConfig wbc{};
  mpc::MpcConfig mpc{};
  // MPC planner only: a step the motion did not plan when the capture point leaves the
  // support in double support, and an earlier touchdown of a planned swing that would not
  // catch it (recovery_step.h).
  planner::RecoveryStepConfig recovery{};
  // MPC planner only: a planned lift-off waits while the capture point is not over the
  // foot that will stand (liftoff_hold.h).
  planner::LiftoffHoldConfig liftoff_hold{};
  // MPC planner only: the window shifted to where the stance foot measures (plan_anchor.h).
  planner::PlanAnchorConfig anchor{};
  // MPC planner only: the planner (the MPC, the recovery step, the lift-off hold, the anchor)
  // plans with the robot whose sole corners are this much closer to each sole's centre, in x
  // and y (model::inset_sole_corners); the WBC keeps the whole soles (it fits its corners to
  // the plan's swing corners in least squares: the same foot centre and heading). Meant as a
  // reserve for what the model gets wrong: a plan whose centre of pressure runs along a sole's
  // edge leaves the WBC nothing. cmu_05_07's single supports at 2.3–4.8 s run it 0.4–1.4 cm
  // inside the outer edge on the nominal robot, and with the show set's model errors seeds 25,
  // 52, 64 and 100 fall there (25 and 64 before their push); the show set without its link-CoM
  // errors (±1 cm a link) saves 25, 52 and 64 and moves 100's fall from 3.8 to 4.8 s (without
  // the ground tilt, the steps, the encoder offsets or the inertia errors, all four still fall).
  // Measured at 0.01 m, show campaign (BENCHMARKS.md): on the motions of 51eb55c 14/400 as off
  // (saves built-in 39, cmu_05_07 52 and 85, perfume 94; loses perfume 51, 64, 70, 89); end to
  // end, each motion retargeted with it on (the check runs this stack), 16/400 against 14/400
  // (built-in 0, perfume 7, cmu_05_07 7, cmu_05_20 2). Off (0), `kuavo simulate
  // --planner-sole-inset M`, campaign key "planner_sole_inset_m".
  double planner_sole_inset_m = 0.0;
  estimator::EstimatorConfig estimator = dance_estimator_config();

  // Leju's IMU low-pass corners (gyro 20 Hz, accelerometer 12 Hz) lag a dancing robot:
  // on the built-in dance in simulation (ideal sensors, first 14 s) the base-velocity
  // error is 0.079 m/s RMS with them and 0.037 m/s with 100 Hz / 50 Hz, and the robot
  // only stays up with the latter. The other noise values stay Leju's (FACTS.md §6).
  static estimator::EstimatorConfig dance_estimator_config() {
    estimator::EstimatorConfig c;
    c.gyro_cutoff_hz = 100.0;
    c.accel_cutoff_hz = 50.0;
    return c;
  }
};
// nullptr if usable, else what is wrong. Load time.
const char* stack_validate_config(const StackConfig& config);

// Stage stamps for the firmware's timing command (firmware/timing.h). The controllers read no
// clock: the caller hands one in (rtos_shim's); nullptr (the default) stamps nothing.
using StageClock = std::int64_t (*)() noexcept;
struct StageStamps {
  std::int64_t start_ns = 0, estimator_done_ns = 0, wbc_done_ns = 0;  // of the last tick
};

struct ControlWorkspace {
  StageClock stage_clock = nullptr;
  StageStamps stamps{};
  estimator::EstimatorState estimator;
  estimator::EstimateOutput estimate;
  wbc::WbcWorkspace wbc;
  planner::ReferencePlan active;  // the plan the ticks follow
  planner::ReferencePlan previous;  // the plan it took over from (config.plan_blend_s)
  wbc::WbcReference previous_reference;  // previous at this tick's time, while blending
  hal::TimeNs blend_start_ns = 0;
  bool blend_pending = false;  // a plan was applied; the blend starts at the next tick
  bool blending = false;
  wbc::WbcReference reference;    // this tick's, interpolated (upper body advanced by config.upper_body_delay_s)
  dynamics::ConfigVector predicted_q = dynamics::ConfigVector::Zero();  // with a delay: the state the WBC ran on
  std::array<double, model::kNumContactPoints> planned_contact_s{};  // how long each corner has been planned in contact
  estimator::ContactFlags estimator_contact{};
  std::uint64_t estimator_unloaded_foot_ticks = 0;  // foot-ticks config.estimator_unloaded_foot_N took out
  LeanTrimState lean_trim;  // config.lean_trim's observer and trim (applied to estimate.q)
  hal::TimeNs last_tick_ns = 0;
  bool started = false;
  std::uint64_t ticks = 0, plans_applied = 0;
};

struct PlannerWorkspace {
  planner::PlanWindow window;
  dynamics::Data data;
  planner::PlanKnot measured;  // the measured state's kinematics, this call's (plan_knot_measured)
  mpc::MpcWorkspace mpc;  // ~15 MB
  mpc::MpcPlan mpc_plan;
  mpc::MpcStatus last_mpc_status = mpc::MpcStatus::kNotInitialized;
  // MPC iterations that failed; each one hands the WBC the kinematic plan instead (the
  // robot keeps going on the motion, the failure is counted and the MPC restarts cold).
  std::uint64_t mpc_failures = 0;
  // Joint positions of MPC knots put on their joint's stop (knots × joints). The MPC keeps
  // joint limits by a relaxed barrier (mpc.h), so its prediction may pass a stop in a fast
  // motion (perfume's kick: the swing ankle's knots > 0.05 rad past, which the firmware
  // refuses as garbage); the plan handed to the WBC holds the hard limits.
  std::uint64_t plan_positions_on_a_stop = 0;
  planner::RecoveryStepState recovery;  // its count: recovery.steps
  planner::LiftoffHoldState liftoff;    // lift-offs held, the motion's lag
  planner::PlanAnchorState anchor;      // the plan's offset to the measured stance foot
  // The model the planner plans with (StackConfig::planner_sole_inset_m), set by stack_prepare;
  // until then stack_plan_rt plans with the model it is given.
  model::Model planning_model;
  bool planning_model_set = false;
};

// The estimator's contact flags less an unloaded foot (StackConfig::estimator_unloaded_foot_N):
// a foot whose corners' normal forces in `force_N` (the WBC's last answer, 3 per corner,
// world z last) sum below threshold_N, while the other foot's reach it, leaves the flags.
// Returns the number of feet taken out (0 or 1). threshold_N <= 0: nothing changes.
int estimator_drop_unloaded_foot_rt(const wbc::ForceVector& force_N, double threshold_N,
                                    estimator::ContactFlags& contact);

// The state the control tick runs on: the estimator's, or (simulation only, for
// comparisons) the simulator's truth.
struct StateOverride {
  const dynamics::ConfigVector* q = nullptr;
  const dynamics::VelocityVector* v = nullptr;
};

// Start-up (not real-time): validates, resets the estimator from the standing robot at
// the motion's first frame, makes the first plan and activates it. false if the sensors
// are unusable or the config is bad.
bool stack_start(const model::Model& model, const StackConfig& config, ControlWorkspace& control,
                 PlannerWorkspace& planner_ws, const planner::MotionPlan& motion, const hal::SensorFrame& sensors,
                 hal::TimeNs now_ns);

// stack_start in two halves, for a binding whose tasks run on two threads and that starts
// the motion at a moment it does not choose (the firmware entering dance mode):
//
//   stack_prepare   start-up, before real time: validates, initialises the estimator, the
//                   WBC and (MPC) the planner workspace. false if the config is bad.
//   stack_begin_rt  the control task, at the motion's time 0 (`now_ns`, in the stack's
//                   time base): resets the estimator from the standing robot (base xy from
//                   the motion's first frame), clears the WBC's fallback state and activates
//                   `first`, a plan the caller made without the planner workspace (the
//                   kinematic planner does). The planner task forgets its warm start itself
//                   (mpc_reset) before its first plan of the new run. Allocation-free;
//                   false if the sensors are unusable (nothing started).
//
// stack_start is stack_prepare + the first plan (from the motion's first frame at rest)
// + stack_begin_rt, in one thread.
bool stack_prepare(const model::Model& model, const StackConfig& config, ControlWorkspace& control,
                   PlannerWorkspace& planner_ws);
bool stack_begin_rt(const model::Model& model, const StackConfig& config, ControlWorkspace& control,
                    const planner::MotionPlan& motion, const planner::ReferencePlan& first,
                    const hal::SensorFrame& sensors, hal::TimeNs now_ns);

// 500 Hz. now_ns: this tick's sensor time. Real-time safe.
wbc::WbcStatus stack_control_tick_rt(const model::Model& model, const StackConfig& config, ControlWorkspace& ws,
                                     const hal::SensorFrame& sensors, hal::TimeNs now_ns, const StateOverride& state,
                                     hal::CommandFrame& command);

// 50 Hz. (q, v): the state at t_state_ns (the control task's estimate when the planner
// released). Kinematic: the motion's knots. MPC: one real-time iteration on the motion
// sampled at the MPC's stage times; on failure the kinematic knots (counted in
// ws.mpc_failures). Real-time safe.
void stack_plan_rt(const model::Model& model, const StackConfig& config, PlannerWorkspace& ws,
                   const planner::MotionPlan& motion, const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                   hal::TimeNs t_state_ns, planner::ReferencePlan& out);

// The planning task before its first plan of a new run: forgets the MPC's warm start
// (nothing for the kinematic planner). Real-time safe.
void stack_reset_planner_rt(const StackConfig& config, PlannerWorkspace& ws);

// Makes plan the active one (real-time safe); the next ticks blend into it from the
// previous one over config.plan_blend_s.
void stack_apply_plan_rt(ControlWorkspace& ws, const planner::ReferencePlan& plan);

}  // namespace kuavo::stack
