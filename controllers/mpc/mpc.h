// Centroidal real-time-iteration MPC (issue 6; the paper's MPC; Leju's OCS2 setup, FACTS.md §4.2).
//
// Model: centroidal_model.h (x = [ṙ, h, base position, ZYX Euler, 26 joints], u = [8 sole-corner
// forces (world), 26 joint velocities]).
//
// Discretization: explicit Euler, x_{k+1} = x_k + dt_k·f(x_k, u_k), dt_k = cfg.dt_s (0.02 s),
// or up to tail_stride times it in the coarse tail (MpcConfig::tail_stride: by default 0.4 s
// of 20 ms stages, then 80 ms stages that end early at contact switches). At 20 ms the
// centroidal dynamics are slow (the fastest mode, the ~0.3 s pendulum, is 15 steps); Leju's
// RK2 at 15 ms buys little here and would double the linearization cost. Every stage term of
// the cost and the barriers is multiplied by its stage's dt_k (the integral, whatever the grid).
//
// One SQP iteration per call (real-time iteration, as Leju: 1 SQP iteration per MPC call):
// linearize about the previous solution shifted by the elapsed stages (or about the reference
// on a cold start), build the OCP QP in the increments (δx, δu), one solve, full step.
//
// Constraints (stage k, contact flags from reference knot k):
//   equalities (hard, in the QP):
//     - a foot with ≥ 3 corners in contact: foot twist = 0 (6 rows: point velocity of the sole
//       centre + angular velocity). Four 3-row corner constraints would be 12 rows of rank 6
//       and the OCP solver needs D full row rank (ocp_qp.h); 3 non-collinear fixed corners are
//       exactly "the foot does not move".
//     - 2 corners in contact (toe or heel phases): the velocity of their centroid = 0 and the
//       foot's angular velocity across the line through them = 0 (5 rows: it may roll about it).
//     - 1 corner in contact: its velocity = 0 (3 rows).
//     - each corner not in contact: force = 0, not as equality rows but by fixing those inputs:
//       δf = −f̄ exactly (B's 3 columns folded into b then zeroed, R_ii = 1, r_i = f̄_i: the
//       Riccati's pivot for each is an exact 1, so the solve returns δf = −f̄ bit for bit). As
//       rows they were 12 of a swing stage's 21 (and 30 of a flight stage's), doubling the
//       Riccati's ν block and the factor storage's capacity (kMaxEqualities 30 → 12).
//     - a foot with no corner in contact: normal-velocity rows (OCS2) on 3 of its 4 corners,
//       v_z = v_z,ref + k_swing (z_ref − z); the 4th follows by rigidity. x-y is soft only
//       (weight_swing_xy on the corners' x-y, and the leg joint cost), so the optimizer may
//       move the touchdown spot.
//   inequalities, as relaxed log-barrier penalties (OCS2; μ, δ from Leju) in the stage cost's
//   gradient and Gauss-Newton Hessian: friction pyramid |f_x|, |f_y| ≤ μ f_z (4 rows per stance
//   corner, the same pyramid as the WBC), joint position limits (model.limits).
// Why barriers and NG = 0: with only equalities each RTI is exactly one Riccati factorization
// and one solve (solve_ocp_qp's pure-LQ path): the cost per call is fixed and known. A hard
// inequality QP would need an interior point (~12 iterations here, ~70 ms) or an unbounded
// active set; one IPM step with warm start would be the same barrier step with less control.
//
// Cost (Leju's Q and R, FACTS.md §4.2, integrated: every stage term is multiplied by dt):
//   ½‖x − x_ref‖²_Q + ½‖u − u_ref‖²_R per stage, terminal ½‖x_T − x_ref‖²_{Q·dt·scale}.
//   x_ref from the plan knots (state_from_configuration of knot q, v); u_ref: the plan's joint
//   velocities, and the least-norm stance forces carrying m·g with no moment about the CoM
//   (the weight split over the stance corners, moment-balanced).
//
// Warm start: the previous solution shifted by round((stamp − previous stamp)/dt) knots, on the
// previous build's grid (in a coarse tail a stage may now start inside an old one: its state is
// interpolated along that stage, its input is that stage's); the new tail repeats the last
// state and takes the reference inputs. x̄₀ is set to the measurement, so δx₀ = 0. A cold start
// (first call, mpc_reset, a QP failure, a stamp jump backwards or beyond the horizon)
// linearizes about the reference.
//
// Using the plan (for the closed loop): plan.knots[i] describes stamp_ns + i·dt; interpolate
// with wbc::wbc_interpolate_reference between the two knots around "now". Base twist, point
// and CoM kinematics of the knots come from forward kinematics of the updated trajectory
// (the twist to first order from the linearization); accelerations are forward differences
// between knots. On any status other than kOk the plan has count 0: keep using the previous one
// (its knots cover 0.2 s) and let the WBC's staleness check take over after that.
#pragma once

#include <array>
#include <cstdint>

#include "controllers/hal/ankle_motor_limits.h"
#include "controllers/hal/types.h"
#include "controllers/mpc/centroidal_model.h"
#include "controllers/planner/plan_knot.h"
#include "controllers/qp/dense_qp.h"
#include "controllers/qp/ocp_solver.h"
#include "controllers/wbc/wbc_reference.h"

namespace kuavo::mpc {

inline constexpr int kMaxStages = 70;        // 1.4 s at 0.02 s
inline constexpr int kMaxEqualities = 12;    // both feet flat: 2 × 6 twist rows (a swing foot has 3)
                                             // (≥ 2 × (2 × 3 + 5) for two-corner contacts)
inline constexpr int kMpcPlanKnots = 10;     // knots handed to the WBC (0.2 s at dt 0.02)

struct MpcConfig {
  double horizon_s = 1.2;  // 0.6 … 1.4 s (the issue); Leju: 1.0 s
  double dt_s = 0.02;      // the reference window's knot spacing and the fine stages' length
  // Horizon grid: stages of dt_s up to fine_horizon_s, then stages of up to tail_stride · dt_s
  // that end early at a knot where a contact flag changes, so each stage's contacts hold over
  // all of it (every boundary is a knot of the dt_s reference window; the last stage ends at
  // horizon_s). 1 = uniform. The plan handed to the WBC (kMpcPlanKnots) lies in the fine part.
  // The offline trajectory optimization reads its trajectory stage by stage at dt_s and keeps 1.
  // Default 0.4 s × 4: 30 stages without switches in the tail (20 of 20 ms, 10 of 80 ms), one
  // more per switch. Against uniform it halves the iteration (BENCHMARKS.md) and plans the
  // same 0.2 s for the WBC (converged on a 0.2 m/s sideways push, CoM velocity within 0.5 % of
  // the push's response). The show campaign (4 × 100 seeds, carpet, the show set, 10 N·s
  // pushes) fell 11/400, the same 11 runs as uniform. A tail whose coarse stages took their
  // contacts from their first knot (lift-offs and touchdowns up to 60 ms off) fell 16/400.
  // 80 ms keeps the swing row's discrete loop stable: 1 − k·dt_k = −0.6 at k = 20/s
  // (mpc_validate_config).
  double fine_horizon_s = 0.4;
  int tail_stride = 4;
  double friction_coefficient = 0.5;  // Leju frictionConeSoftConstraint μ

  // State weights Q (diagonal). Leju's task.info Q, with its normalized momentum (v_com, L/m)
  // converted to ours: weight on h = weight on L/m divided by m².
  std::array<double, 3> weight_com_velocity{80.0, 80.0, 13.0};       // (m/s)⁻²
  std::array<double, 3> weight_angular_momentum_normalized{50.0, 50.0, 13.0};  // on h/m, (m²/s)⁻²
  std::array<double, 3> weight_base_position{500.0, 500.0, 2000.0};  // m⁻²
  std::array<double, 3> weight_base_euler{100.0, 2000.0, 800.0};     // yaw, pitch, roll, rad⁻²
  std::array<double, 6> weight_leg_joint{300.0, 300.0, 10.0, 10.0, 10.0, 10.0};  // per leg, rad⁻²
  // Leju weighs shoulder ×3 and elbow 200 and leaves the wrists out of its model; we keep them
  // in (their momentum matters in a dance) at the same weight.
  double weight_arm_joint = 200.0;  // rad⁻²
  // Q_T = scale · Q · dt: the terminal state weighs like 0.2 s of stages (Leju: terminal cost
  // off; its unused terminal P is 2–10× its Q on the base).
  double terminal_weight_scale = 10.0;

  // Input weights R (diagonal). Leju: R scaling 1e-3 × (forces 1, arm joint velocity 2000,
  // foot task-space velocity 5000 (m/s)⁻² mapped to the legs by JᵀRJ at the nominal stance).
  // The leg value is that mapping's diagonal rounded (lever arms ~0.4–0.8 m: 5·0.5² ≈ 1).
  // Forces: 1e-4, not Leju's 1e-3: with 1e-3 a 0.2 m/s sideways CoM disturbance is still at
  // 0.03 m/s and 19 of its 21 mm excursion at the end of the 1.2 s horizon (force deviations
  // cost more than the tracking error); with 1e-4 it is out by then (tests/mpc/mpc_test.cpp).
  double weight_force = 1e-4;               // N⁻²
  double weight_leg_joint_velocity = 1.0;   // (rad/s)⁻²
  double weight_arm_joint_velocity = 2.0;   // (rad/s)⁻²

  // Relaxed log barrier B(h) = −μ ln h (h > δ), quadratic extension below δ (OCS2).
  // Friction: Leju has μ = 0.1, δ = 5 N against its force weight 1e-3. We keep the ratio
  // μ / weight_force (the barrier's push on f_z, which otherwise lifts the robot at the end of
  // the horizon where nothing opposes it) and take δ = 1 N, so the relaxed penalty's curvature
  // μ/δ² is 100× the force weight: with δ = 5 N the 0.2 m/s push test left corners 13.7 N
  // outside the pyramid, with 1 N they stay inside (tests/mpc/mpc_test.cpp).
  double friction_barrier_mu = 0.01;
  double friction_barrier_delta_N = 1.0;
  // Joint limits are not in Leju's MPC. Ours: small enough that a reference 0.1 rad inside a
  // limit (the standing elbow) moves < 1 mrad against the arm weight, δ ≈ 1°.
  double joint_limit_barrier_mu = 0.01;
  double joint_limit_barrier_delta_rad = 0.02;

  // Leg joint torques of each stance foot: the moment of its corner forces about each of the
  // leg's six joint axes stays within this share of the joint's torque limit (relaxed
  // barrier, δ in N·m). The corners sit 0.1–0.15 m ahead of and behind the ankle, so the
  // friction pyramids and the support polygon allow a centre of pressure the ankles cannot
  // hold (perfume, with a 27 N·m ankle box: CoM 0.09 m ahead, both ankles saturated, fell at 14.8 s),
  // and a crouch or a turn on one foot loads the knee (130 N·m) and hip yaw (20 N·m) beyond
  // theirs (perfume's spin at 23–26 s: 230 and 116 N·m in the TO's result). Linear in the
  // forces with the leg geometry of the iterate (lagged: no state gradient), so convex; the
  // legs' own weight and inertia are left out (a few N·m at the hip). μ small enough that
  // standing (≈ 8 N·m per ankle) feels no pull (the barrier's gradient at rest, 2μτ/L², moved
  // the standing CoM 1.3 mm/s with μ = 0.1), δ small so that a violation costs as much as
  // with μ = 0.1, δ = 1. With MpcWorkspace::ankle_motor_limits active (the firmware, the sim) the
  // ankle pair's two motor torques are held to the same share of the motors' limits too: the
  // joint-space box on pitch and roll allows combinations the two motors cannot hold together
  // (pitch ≈ τ_A + τ_B, roll ≈ 0.46 (τ_A − τ_B)). 0 = off.
  // A lower share for the ankles while both feet stand, to keep a reserve for pushes, was
  // tried at 4035c5d and reverted. Danced on carpet (nominal plant, seed 1), perfume's motion
  // holds both ankle pitches at 23–25 N·m through its 12–18 s double support (its TO plans at
  // 0.9 of 27 N·m), and the show campaign's pushes there are falls the true state does not
  // save (seeds 29, 58, 75).
  // At 0.6 in the TO, perfume's check kept round 4 (was 6; steps 15/15, CoM path 47 %), but
  // the new motion, danced the same way, still held 19.5–21.6 N·m there and loads the right
  // ankle to 36–40 N·m at 21–23 s. Its show campaign fell 28/100 against 6/100: 29, 58, 75
  // still fell, and 20 of the 28 came in 21.9–25.0 s. At 0.6 in the online MPC instead, on
  // the current motion, 14 runs (its 6 falls and seeds 1–8) gave 8 falls against 6; none
  // was saved.
  double stance_leg_torque_share = 0.9;
  double leg_torque_barrier_mu = 0.01;
  double leg_torque_barrier_delta_Nm = 0.2;

  // Swing normal-velocity row gain: v_z = v_z,ref + k (z_ref − z). Leju positionErrorGain 20.
  double swing_position_gain_1_s = 20.0;
  // Soft x-y tracking of the swing corners, m⁻² per corner; 0 leaves the touchdown spot to the
  // leg joint cost alone. Leju: 500. In closed loop with the estimator (the built-in dance,
  // tests/loop/mpc_loop_test.cpp) 500 and 150 pin the feet so hard that the robot cannot step
  // out of trouble and falls (at 13.5 s on the floor, 13.9 s on carpet); 50 and 0 dance both
  // grounds to the end. 50 keeps the touchdown spot loosely tied to the plan. Loose enough to
  // cross the legs under a push (perfume's show campaign); a quadratic hinge keeping the swing
  // sole at least 0.10–0.15 m to its side of the stance sole, relative to where the reference
  // has it, was tried and made the show worse (perfume 35 and 32 falls in 60 against 22): the
  // real feet drift from the plan's by up to 0.18 m, so it pulled on ordinary swings.
  double weight_swing_xy = 50.0;

  // Stance feet: the sole centre's velocity row becomes v = k (foothold − position), which
  // holds a stance foot on its foothold instead of only at rest (Euler integration of the
  // rest condition lets it creep ~1 cm/s over a stance). 0 = rest only (the online MPC: the
  // measured foot is where it is); the offline optimization uses 10 s⁻¹.
  double stance_position_gain_1_s = 0.0;

  // The online MPC hands kMpcPlanKnots knots (0.2 s) to the WBC and needs a horizon of
  // 0.6–1.4 s. The offline trajectory optimization (tools/mocap/dynamic_retarget.h) reads the
  // trajectory itself and takes windows from 0.2 s: it sets this false.
  bool plan_output = true;

  // u_ref's forces: false, the least-norm stance forces carrying the weight with no moment
  // about the CoM; true, those carrying the reference's own centroidal wrench (m (r̈ + g) and
  // ḣ of the reference states), so the input cost stops pulling a dynamic reference toward
  // static forces. Those forces are the nearest within the friction pyramids (a small QP per
  // knot, solved again only when its wrench changes): an infeasible reference's own wrench
  // lies outside the cones. Offline only for now (`kuavo retarget --force-reference motion`):
  // with it the built-in dance's TO keeps 67 % of the geometric CoM path (61 % without) and
  // the oracle's torque violations fall 1069 → 388; see tools/mocap/dynamic_retarget.h.
  bool reference_forces_from_motion = false;
};

// nullptr if usable, else what is wrong. Load time.
const char* mpc_validate_config(const MpcConfig& config);
// Knots of the reference window a valid config reads: round(horizon_s / dt_s) + 1.
int mpc_window_knots(const MpcConfig& config);
// Stages of the horizon for a valid config: round(horizon_s / dt_s) with a uniform grid, fewer
// with a coarse tail (tail_stride > 1): then the count without contact switches in the tail;
// each knot of the tail where a contact flag changes may add one (MpcWorkspace::horizon).
int mpc_num_stages(const MpcConfig& config);

// Stable numbers (logs, fault records): never renumber or reuse.
enum class MpcStatus : std::uint8_t {
  kOk = 0,
  kNotInitialized = 1,  // mpc_init not called (or with an invalid config)
  kBadInput = 2,        // non-finite measured state
  kBadReference = 3,    // reference too short, wrong dt, or non-finite
  kQpFailed = 4,        // the QP solve failed (factorization); trajectory and warm start dropped
};
const char* to_string(MpcStatus s);

struct MpcPlan {  // a value type: copied through a triple buffer to the 500 Hz loop
  hal::TimeNs stamp_ns = 0;  // time of knot 0 (= the measured state's time)
  double dt_s = 0.02;
  int count = 0;
  std::array<wbc::WbcReference, kMpcPlanKnots> knots{};
  MpcStatus status = MpcStatus::kNotInitialized;
  int qp_iterations = 0;              // Riccati factorizations this call (1 when solved)
  double cost = 0.0;                  // ½Σ tracking cost (no barriers) of the updated trajectory
  // max |defect|, |equality row| at this call's linearization point (before its QP step). With a
  // shifted warm start this includes the newly guessed tail stage (up to ~1 while stepping);
  // repeated calls on a fixed state drive it to ~1e-15 (SQP convergence).
  double constraint_violation = 0.0;
};

using Ocp = qp::OcpQp<kNx, kNu, kMaxStages, kMaxEqualities, 0>;
using OcpWorkspace = qp::OcpWorkspace<kNx, kNu, kMaxStages, kMaxEqualities, 0>;
using OcpSolution = qp::OcpSolution<kNx, kNu, kMaxStages, kMaxEqualities, 0>;
// The reference forces carrying a wrench inside the friction pyramids (reference_forces_from_motion):
// the 8 corners' forces, 4 pyramid rows each.
using WrenchQp = qp::DenseQp<3 * kNumPoints, 0, 4 * kNumPoints>;
using WrenchQpWorkspace = qp::DenseQpWorkspace<3 * kNumPoints, 0, 4 * kNumPoints>;
using WrenchQpSolution = qp::DenseQpSolution<3 * kNumPoints, 0, 4 * kNumPoints>;

// Everything, ~15 MB: static storage only.
struct MpcWorkspace {
  bool initialized = false;
  int horizon = 0;  // T (stages)
  // The grid: stage k starts at reference window knot stage_knot[k] (stage_knot[T] = the
  // window's last) and lasts stage_dt_s[k]. With a coarse tail it follows the window's
  // contact switches, so each build sets it (and T); the previous build's grid is kept for
  // the warm start, with a copy of its trajectory when the grid moved (x_previous, u_previous).
  std::array<int, kMaxStages + 1> stage_knot{};
  std::array<double, kMaxStages> stage_dt_s{};
  int previous_horizon = 0;
  std::array<int, kMaxStages + 1> previous_stage_knot{};
  StateVector weight_state = StateVector::Zero();   // diag Q (not yet × dt)
  InputVector weight_input = InputVector::Zero();   // diag R
  Eigen::Matrix<double, kNumMpcJoints, 1> joint_min_rad, joint_max_rad;

  // Trajectory (linearization point / solution) and reference.
  std::array<StateVector, kMaxStages + 1> x{};
  std::array<InputVector, kMaxStages + 1> u{};
  std::array<StateVector, kMaxStages + 1> x_ref{};
  std::array<InputVector, kMaxStages + 1> u_ref{};
  std::array<HeadVector, kMaxStages + 1> head_rad{};
  std::array<StateVector, kMaxStages + 1> x_previous{};
  std::array<InputVector, kMaxStages + 1> u_previous{};
  // The reference in MPC coordinates is a function of its knot alone: the previous call's
  // window knots and their (pre-unwrap) states and inputs are kept, indexed by window knot
  // (a coarse tail reads other knots of the same window after a shift), and a knot met again
  // (same stamp, same values, as consecutive windows of one motion share all but their tail)
  // is not recomputed. reference_cached counts the valid entries.
  std::array<planner::PlanKnot, planner::kMaxWindowKnots> reference_knot{};
  std::array<StateVector, planner::kMaxWindowKnots> reference_state{};
  std::array<InputVector, planner::kMaxWindowKnots> reference_input{};
  int reference_cached = 0;
  // reference_forces_from_motion: the wrench each knot's u_ref forces were solved for (kept
  // with the knot, so a knot whose wrench is unchanged is not solved again) and the QP.
  std::array<Vec6, planner::kMaxWindowKnots> reference_wrench{};
  WrenchQp wrench_qp;
  WrenchQpWorkspace wrench_qp_workspace;
  WrenchQpSolution wrench_qp_solution;
  int reference_wrench_failures = 0;  // QPs that failed (their knot took the least-norm split)
  bool warm = false;
  hal::TimeNs last_stamp_ns = 0;

  // Base twist and its derivatives at the first knots (to map the QP step into the plan).
  std::array<Vec6, kMpcPlanKnots + 1> twist{};
  std::array<MotionRowsX, kMpcPlanKnots + 1> twist_dx{};
  std::array<MotionRowsU, kMpcPlanKnots + 1> twist_du{};

  // The ankle motors (controllers/hal/ankle_motor_limits.h), set by the binding before a step:
  // active, the stance ankles' motor torques join the leg-torque barrier. The map at the
  // sampled ankle angles serves the whole horizon (a stance ankle moves little in it).
  hal::AnkleMotorLimits ankle_motor_limits;

  CentroidalPoint point;
  dynamics::Data world_data;
  planner::PlanKnot scratch_knot;
  wbc::WbcReference scratch_reference;
  Ocp qp;
  std::array<bool, kMaxStages + 1> swing_block_written{};  // stage Q has the swing x-y block (not diagonal)
  OcpWorkspace qp_workspace;
  OcpSolution solution;
  qp::OcpSettings qp_settings;
  double constraint_violation = 0.0;  // of the last linearization
  qp::QpStatus qp_status = qp::QpStatus::kBadInput;
};

// Start-up, may be slow: weights, limits, an empty warm start. An invalid config leaves the
// workspace uninitialized (mpc_step_rt then returns kNotInitialized).
void mpc_init(const model::Model& model, const MpcConfig& config, MpcWorkspace& ws);
// Forget the warm start: the next step linearizes about the reference.
void mpc_reset(MpcWorkspace& ws);

// One real-time iteration. q, v: measured/estimated state (conventions.h), at
// reference.knots[0].stamp_ns. reference: the plan at dt = cfg.dt_s, count ≥
// mpc_window_knots(config). No allocation, no exceptions, no printing, bounded time.
MpcStatus mpc_step_rt(const model::Model& model, const MpcConfig& config, MpcWorkspace& ws,
                      const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                      const planner::PlanWindow& reference, MpcPlan& out);

// mpc_step_rt's three phases, exposed for the benchmark's timing split and the QP tests:
// (1) check the inputs, shift the warm start, linearize, fill ws.qp;
MpcStatus mpc_build_qp_rt(const model::Model& model, const MpcConfig& config, MpcWorkspace& ws,
                          const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                          const planner::PlanWindow& reference);
// (1') the same from the initial state in MPC coordinates (the offline trajectory
// optimization, tools/mocap/dynamic_retarget.h, chains its windows on the optimized state);
// mpc_build_qp_rt converts (q, v) and calls it.
MpcStatus mpc_build_qp_from_state_rt(const model::Model& model, const MpcConfig& config, MpcWorkspace& ws,
                                     const StateVector& x_initial, const planner::PlanWindow& reference);
// (2) solve ws.qp into ws.solution and apply the step to ws.x, ws.u;
MpcStatus mpc_solve_qp_rt(MpcWorkspace& ws);

// OCS2's relaxed log barrier B(h) = −μ ln h for h > δ, else the quadratic that matches value,
// slope and curvature at δ: B'(h) into d1, B''(h) into d2 (the MPC's joint-limit and friction
// terms; the offline TO's joint-velocity terms).
void relaxed_barrier(double h, double mu, double delta, double& d1, double& d2);
// (3) fill the plan from the updated trajectory (count 0 unless status is kOk).
void mpc_write_plan_rt(const model::Model& model, const MpcConfig& config, MpcWorkspace& ws,
                       const planner::PlanWindow& reference, MpcStatus status, MpcPlan& out);

}  // namespace kuavo::mpc
