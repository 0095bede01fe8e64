// The online stack (controllers/stack) following a motion in the simulator: Simbody
// plant (or MuJoCo's: run.engine), seeded sensors, the 500 Hz control task and the 50 Hz planning task in lockstep
// virtual time, the planner's latency modelled. Writes a CSV row per control tick and
// returns the summary figures. Deterministic: same inputs and binary → the same
// log bytes (compute-time figures in the summary are wall-clock measurements and vary).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "controllers/planner/motion_plan.h"
#include "controllers/stack/online_stack.h"
#include "sim/closed_loop.h"
#include "sim/perturbation.h"
#include "sim/sensor_model.h"

namespace kuavo::sim {

struct MotionRunConfig {
  MotionRunConfig() { run.duration_s = 0.0; }
  RunConfig run;                   // ground, push, seed, log, command latency, integrator;
                                   // run.duration_s ≤ 0: the motion's length plus settle_s
  stack::StackConfig stack;
  double settle_s = 1.0;
  // Planner latency: its result is applied this long after the state it used (rounded up
  // to control ticks). Fixed by default so the run is reproducible; measured_plan_latency
  // uses each iteration's measured compute time instead (then the log varies run to run).
  double plan_latency_s = 0.004;
  bool measured_plan_latency = false;
  bool use_truth_state = false;    // comparison runs: the WBC on the simulator's truth
  bool ideal_sensors = false;      // diagnostics: no noise, bias or quantization (SensorNoise zeroed)
  // Tests: a fixed IMU tilt error (roll, pitch) [rad] on top of the sensor model's own.
  Eigen::Vector2d imu_tilt_rad = Eigen::Vector2d::Zero();
  // Model mismatch (sim/perturbation.h): the plant and the sensors get the drawn errors,
  // the controller keeps `model`. Inactive (the default): the unperturbed run, bit for bit.
  PlantPerturbation perturbation;
  // Called with the simulated time every kProgressPeriod_s of it (a CLI's progress line);
  // empty: never. It only observes: the run and its log do not depend on it.
  std::function<void(double sim_time_s)> on_progress;
  static constexpr double kProgressPeriod_s = 0.5;
};

// The centre of pressure of the ground's normal forces and its margin to the support
// polygon (the loaded feet's sole corners), from the plant's truth. Undefined (defined
// false) while the feet carry little load.
struct Balance {
  bool defined = false;
  Eigen::Vector2d cop = Eigen::Vector2d::Zero();
  double margin_m = 0.0;
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();  // the polygon's bounding box
};
Balance balance_of(const PlantTruth& t);

struct Percentiles {
  double p50 = 0.0, p99 = 0.0, max = 0.0;
};
Percentiles percentiles(std::vector<double> samples);

// Stepping phases (MotionSummary::steps).
inline constexpr double kUnloaded_N = 5.0, kLoaded_N = 100.0, kMinStance_s = 0.05;

struct MotionSummary {
  RunSummary run;
  std::string planner;
  double motion_duration_s = 0.0;
  double tracking_rms_legs_rad = 0.0;  // joint angle vs the motion, over the run
  double tracking_rms_arms_rad = 0.0;
  double com_err_m_max = 0.0;          // ‖CoM − planned CoM‖
  // What was danced, before a fall (issue 18's "the dance is kept"): the path length (3D, as
  // mocap::motion_metrics) of the plant's CoM and of the motion's planned CoM over the same ticks, and the stepping
  // phases (lift-offs: a foot's load below kUnloaded_N after it carried over kLoaded_N for
  // kMinStance_s at least; a shorter touch is a bump before the lift, not a stance).
  double com_path_m = 0.0, com_path_plan_m = 0.0;
  int steps = 0;
  double zmp_margin_m_min = 0.0;       // centre of pressure to the support polygon's edge
  double zmp_at_edge_s = 0.0;          // time the centre of pressure spent within 1 mm of the edge (a foot rolling)
  double torque_ratio_max = 0.0;       // max over joints and ticks before a fall of |τ_joint| / peak torque
                                       // (PlantTruth::joint_torque_Nm; the ankle slots per motor against
                                       // its clamp; 1: the drive saturates)
  std::string perturbation_json;       // the set, seed and drawn figures; empty when inactive
  Percentiles mpc_ms;                  // planner iteration compute time
  Percentiles wbc_us;                  // control tick (estimator + reference + WBC) compute time
  Percentiles wbc_qp_iterations;       // the WBC QP's iterations per tick (warm-start guess size
                                       // + drops + adds): the tick's work, free of the machine's noise
  std::uint64_t deadline_misses = 0;   // ticks over 2 ms plus planner iterations over their period
  std::uint64_t wbc_not_ok_ticks = 0;  // ticks whose WBC status was not kOk
  std::uint64_t plans_applied = 0, plans_skipped = 0;
  std::uint64_t mpc_failures = 0;      // MPC iterations replaced by the kinematic plan
  std::uint64_t plan_positions_on_a_stop = 0;  // MPC knot joint positions put on a stop
  std::uint64_t recovery_steps = 0;            // steps the motion did not plan (recovery_step.h)
  // planner calls whose capture point had left the support (the step's trigger) where no
  // step within the reach box (nor, in a swing, an early touchdown) would have captured:
  // none taken (recovery_step.h, "choose")
  std::uint64_t recovery_declined = 0;
  std::uint64_t recovery_early_touchdowns = 0;  // swings landed early (recovery_step.h)
  // Lift-offs the planner held (liftoff_hold.h), those let go at the hold's limit, and how
  // far the motion's clock fell behind (most, and at the end of the run) [s].
  std::uint64_t liftoff_holds = 0, liftoff_released = 0;
  double motion_lag_s_max = 0.0, motion_lag_s_end = 0.0;
  // The plan anchor (plan_anchor.h): targets taken, planner calls that refused one (beyond its bound), and
  // the largest offset applied [m].
  std::uint64_t anchor_reanchors = 0, anchor_refused = 0;
  double anchor_offset_m_max = 0.0;
  double estimator_velocity_rms_m_s = 0.0;  // base velocity (world) vs truth
  double estimator_position_drift_m = 0.0;  // final horizontal base position error
  double estimator_position_err_m_max = 0.0;
  std::uint64_t estimator_gated_corner_ticks = 0;  // EstimatorState::gated_corner_ticks at the end
  std::uint64_t estimator_unloaded_foot_ticks = 0;  // ControlWorkspace::estimator_unloaded_foot_ticks at the end
  // The state the controller ran on against the truth: the tilt of its base (the angle between
  // the two base z axes; with the lean trim, the trimmed one), RMS over the run before a fall,
  // and, on the last tick, the horizontal distance between its CoM over the mean of the sole
  // corners and the plant's (the model's CoM errors and the tilt together) [m].
  double estimator_tilt_err_deg_rms = 0.0;
  double com_over_feet_err_m_end = 0.0;
  // StackConfig::planner_sole_inset_m of an MPC run, in the summary only when above 0.
  double planner_sole_inset_m = 0.0;
  // The estimator's stance sink (EstimatorConfig::stance_sink_m, `--surface-sink`), in the
  // summary only when above 0.
  double stance_sink_m = 0.0;
  // The recovery step's fast swing (RecoveryStepConfig::fast_swing_s) of an MPC run with the
  // step on, and the steps that took it; in the summary only when it is on.
  double recovery_fast_swing_s = 0.0;
  std::uint64_t recovery_fast_steps = 0;
  // The lean trim (controllers/stack/lean_trim.h), in the summary only when it is on.
  bool lean_trim = false;
  bool lean_trim_opening = false;  // learned in the opening stand only (LeanTrimLearn::kOpening)
  double lean_trim_roll_deg = 0.0, lean_trim_pitch_deg = 0.0;  // at the end
  std::uint64_t lean_trim_integrated_ticks = 0, lean_trim_saturated_ticks = 0;
};

// The planning task's counters (MPC fallbacks, knots put on a stop, recovery steps taken and
// declined) into a summary: `kuavo simulate` and `kuavo_fw_sim` read the same workspace, so one
// copy keeps their summaries from drifting apart (kuavo_fw_sim once left recovery_steps at 0).
void copy_planner_counters(const stack::PlannerWorkspace& ws, MotionSummary& out);

// The state the controller ran on against the plant's truth (MotionSummary's figures, shared
// with kuavo_fw_sim): the angle between the believed and the true base z axes [deg], and the
// horizontal distance between the controller's CoM over the mean of its sole corners (the WBC
// tick's) and the plant's [m].
double tilt_error_deg(const dynamics::ConfigVector& believed_q, const dynamics::ConfigVector& true_q);
double com_over_feet_error_m(const wbc::WbcWorkspace& wbc, const PlantTruth& truth);

// Decimated traces for the report's plots (every `stride` control ticks).
struct MotionTrace {
  int stride = 5;
  std::vector<double> time_s;
  std::vector<std::array<double, 3>> com, com_ref;
  std::vector<std::array<double, 2>> zmp;
  std::vector<double> zmp_margin_m;
  std::vector<std::array<double, model::kNumJoints>> q, q_ref;
  std::vector<std::array<double, 2>> support_lo, support_hi;  // support polygon's bounding box
  std::vector<std::array<double, 3>> base_velocity, base_velocity_est;
  std::vector<std::array<double, 2>> foot_force_z_N;  // [left, right] normal load from the ground
  std::vector<std::array<double, 4>> foot_xy_m;       // [left x, y, right x, y]: sole centres
};

MotionSummary run_motion(const model::Model& model, const planner::MotionPlan& motion, const MotionRunConfig& config,
                         MotionTrace* trace = nullptr);

std::string motion_summary_json(const MotionSummary& s);

}  // namespace kuavo::sim
