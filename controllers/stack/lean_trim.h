// Lean trim: the estimated base tilt corrected so that the CoM the controller believes in is
// the one the ground pushes on (issue 20; opt-in).
//
// Three errors put the robot's true CoM beside the one the controller plans with, and the
// controller cannot see any of them in its state: the IMU's roll/pitch error (the MTi's
// 0.2°, 1σ, is 2.6 mm of CoM at 0.75 m), the links' mass and CoM errors (the show set's
// ±6 % / ±1 cm per link) and the joints' encoder offsets. Holding its believed CoM over the
// plan, the robot stands with the true one off it (cmu_05_07's motion, show set, seed 100,
// no push: roll −0.71° against 0.00° on ideal sensors) and has that much less centre-of-
// pressure range on one side. What they all leave behind is visible: the WBC plans
// horizontal contact forces that should accelerate the CoM and it does not move as they
// say. (Stephens, "State estimation for force-controlled humanoid balance using simple
// models in the presence of modeling error", ICRA 2011, estimates a CoM offset from the
// same mismatch; here it is fed back as a tilt.)
//
// Per control tick, horizontal world axes, m the model's mass:
//   residual  a generalized-momentum observer (De Luca's collision residual) on the CoM's
//             linear momentum P = m·ċ of the believed state:
//               I += dt·(F_wbc + r),   r = K·(P − P₀ − I)
//             F_wbc: the horizontal sum of the WBC's contact forces of the previous tick (what
//             the controller asked the ground for over the interval). r follows the force
//             the CoM obeys but the WBC did not plan, with time constant 1/K.
//   offset    read as a CoM offset through the inverted pendulum: δ = r·h / (m·g) (h the
//             CoM's height over the lowest sole corner): the true CoM is δ from the believed.
//   trim      integrated towards it: θ_pitch += dt/τ · δ_x/h, θ_roll −= dt/τ · δ_y/h, within
//             ±max_rad (the ticks it is held there are counted). Applied to the estimate's
//             base orientation, R ← R_trim(θ)·R, before the WBC and the planner read it: the
//             believed feet move −h·θ under the base, so the believed CoM moves over them
//             by δ. As the trim converges the WBC's forces stop fighting it and r → 0.
//   gate      the trim only integrates while the WBC's QP answered, the feet carry at least
//             min_load_share of the weight, |r| ≤ residual_gate_N and the CoM stands over
//             0.2 m above the lowest sole corner: a push (10 N·s over 0.1 s is 100 N), a
//             foot leaving the ground or a robot on the floor is not an offset. And only in
//             quasi-static phases: the WBC's horizontal force at most quasi_static_force_N
//             and the CoM slower than quasi_static_speed_m_s, both for quasi_static_hold_s
//             (the observer's transient, 1/K, has passed): in a dance's fast phases the
//             WBC's forces and the plant part for more reasons than an offset.
//
// Off by default (`kuavo simulate --lean-trim opening|always`, campaign key "lean_trim").
// Measured on Simbody; the campaigns on carpet, the `show` set, one 10 N·s push; kAlways
// (`always`, formerly `on`: the trim of every quasi-static phase) on the motions of 2e6abcb:
//  - standing, ideal sensors (LeanTrimLoop): an injected IMU tilt of (0.6°, −0.8°) is trimmed
//    to (−0.56°, +0.75°) in 10 s, the CoM over the feet 14.2 → 1.0 mm off the truth; every
//    link's CoM 1.5 cm off in the plant: 20.4 → 11.1 mm only (the residual reaches zero with
//    half of it left; not explained yet).
//  - the 11 falls of the 400-run show campaign (each run to ~2 s past its fall): it saves the
//    5 that noise-free sensors save (built-in 39, cmu_05_07 71 and 100, cmu_05_20 77,
//    perfume 64), and perfume 27 too with estimator_unloaded_foot_N = 50.
//  - but the whole campaign with both on falls 15/400 against 11/400 without: of its 10
//    new falls, 6 fall with the trim alone (cmu_05_07 41, 42, cmu_05_20 25, 39, perfume 23,
//    96). In a dance the residual is not only an offset (the WBC's forces and the plant part
//    in every fast phase): the trim wanders to a median 0.32° (max 0.96°) by the end of a
//    run, more than the MTi's error it is for.
//  - with the quasi-static gate (033879f), the trim alone: 12/400 (built-in 0, perfume 7,
//    cmu_05_07 3, cmu_05_20 2) against 11/400 off. It saves 5 (built-in 39, cmu_05_07 100,
//    cmu_05_20 77, perfume 64, 98) and makes 6 (cmu_05_07 27, 42, cmu_05_20 39, perfume 9,
//    23, 96); the trim still ends a median 0.30° (max 0.72°) from zero. The CoM over the
//    feet at the end, seeds 1-10 of the four motions (39 runs up in both): median 5.4 →
//    3.3 mm (max 10.1 → 7.4), closer in 31. Bounded at 0.03° the same runs fall as off
//    (13 screened): the new falls are the trim's. They come at the motions' thin places:
//    all three cmu_05_07 ones in its last 0.6 s (seed 42's log: its last step lands with
//    the lateral capture point at the sole's outer edge, the robot stays on that foot, its
//    ankle pitch at 49-52 N·m, the motors' share, and tips forward).
//  - kOpening (learned in the motion's opening stand only, τ 0.5 s, dead band 3 N; host G),
//    on the motions of 51eb55c, whose campaign falls 14/400 without a trim (built-in 1,
//    perfume 3, cmu_05_07 9, cmu_05_20 1): 11/400 (0, 5, 5, 1). It saves built-in 39,
//    cmu_05_07 25, 64, 85, 100 (the link-CoM family: the robot stood its opening with its
//    true CoM 1-2.5 cm off the motion's) and perfume 75; it makes perfume 5, 66 and 89.
//    Without the dead band (learning until 1.8 s): 15/400 (0, 9, 5, 1); its trims leaned
//    +0.16° in roll on average over every motion's seeds, the joints' Coulomb friction
//    (residual_deadband_N).
//  - kOpening end to end (each clip retargeted with it on, so the check runs it): built-in
//    unchanged (7d0f0110); cmu_05_07 (round 7, 8/11 steps) 6/100 against 9; cmu_05_20
//    (round 8, 4 of the check's seeds given up, 3/7 steps, CoM path 14 %) 14/100 against 1.
//    So it stays off. Of six of those cmu_05_20 falls, three fall with the trim off too (the
//    checked motion is frailer); the trim drops the others with pitch trims of −0.13° to
//    −0.35°. Its source is joint friction again: on that motion's opening (51eb55c, seeds
//    1–4, the band on) the MTi alone trims 0.00–0.04°, Coulomb friction alone −0.06° to
//    −0.23°. The friction residual depends on the pose, and a band wide enough for every pose
//    swallows the offsets the trim is for: the lever is the friction itself (compensated,
//    or stiction broken by a dither while the trim learns).
// Real-time: fixed-size state, no allocation, no kinematics of its own (it reads what the
// WBC's tick computed: the CoM, the momentum matrix, the sole corners, the forces).
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "controllers/dynamics/data.h"
#include "controllers/planner/plan_knot.h"
#include "controllers/wbc/wbc.h"

namespace kuavo::stack {

// When the trim learns. kAlways: in every quasi-static phase of the run (what the figures
// above measured, with time_constant_s). kOpening: only in the motion's opening double
// support, until the plan first lifts a sole corner, with opening_time_constant_s; the trim
// then holds through the dance. The errors it is for are constant over a show (a link's CoM,
// the IMU's mounting, an encoder's zero), and the opening stand is the phase in which the
// residual holds least else (joint friction aside: residual_deadband_N); in the dance's fast
// phases it holds much else (the campaign figures above), and a trim learned there wanders.
enum class LeanTrimLearn { kAlways, kOpening };

struct LeanTrimConfig {
  bool enabled = false;
  LeanTrimLearn learn = LeanTrimLearn::kAlways;
  double observer_gain_1_s = 10.0;  // K: the residual follows within 0.1 s
  double time_constant_s = 3.0;     // τ: the trim takes the offset over this long (kAlways)
  // τ while learning in the opening (kOpening): a motion opens with 0.8 s of standing and a
  // 1 s blend into the dance's first pose, so the trim must learn within about a second.
  double opening_time_constant_s = 0.5;
  double max_rad = 0.035;           // 2°: beyond any IMU or model error the show set draws
  double residual_gate_N = 40.0;    // a 1 cm offset is 7 N; a 10 N·s push 100 N
  // The trim learns r·(1 − d/|r|), nothing while |r| ≤ d. Joint Coulomb friction holds a
  // standing robot a little off where the WBC steers it, and the residual reads that as an
  // offset: measured (the built-in dance's opening, carpet, seeds 1–8, kOpening, d = 0),
  // with the show set's coulomb_rel_peak alone in the plant the trim learned a mean 0.28°
  // more roll and 0.21° more pitch than with no errors at all (2.6 / 2.0 N of residual), on
  // a plant whose CoM is the model's. d = 3 N passes over that, and leaves 3 N of any larger
  // residual unlearned (3/7 of a 1 cm offset). The figures of kAlways above were measured
  // with d = 0.
  double residual_deadband_N = 3.0;
  double min_load_share = 0.5;      // of m·g on the soles
  // Quasi-static gate: the trim integrates only after the WBC's horizontal force and the CoM's
  // speed have both stayed small for quasi_static_hold_s (a dance's fast phases are not an offset).
  double quasi_static_force_N = 20.0;     // 0.36 m/s² of CoM acceleration at 55 kg
  double quasi_static_speed_m_s = 0.1;
  double quasi_static_hold_s = 0.3;
};
// nullptr if usable, else what is wrong.
const char* lean_trim_validate(const LeanTrimConfig& config);

struct LeanTrimState {
  Eigen::Vector2d theta_rad = Eigen::Vector2d::Zero();  // (roll, pitch) applied, world axes
  Eigen::Vector2d residual_N = Eigen::Vector2d::Zero();
  Eigen::Vector2d integral_Ns = Eigen::Vector2d::Zero();
  Eigen::Vector2d momentum0_Ns = Eigen::Vector2d::Zero();
  Eigen::Vector2d last_force_N = Eigen::Vector2d::Zero();  // the previous tick's WBC answer
  bool primed = false;
  bool opening_over = false;           // the plan has lifted a sole corner since the reset
  double quiet_s = 0.0;                // how long the quasi-static gate has held
  std::uint64_t integrated_ticks = 0;  // ticks the gate let the trim move
  std::uint64_t saturated_ticks = 0;   // ticks the trim sat at ±max_rad
};

void lean_trim_reset(LeanTrimState& state);

// The trim on a configuration's base orientation (q[3:7]), in place. Off: nothing.
void lean_trim_apply_rt(const LeanTrimConfig& config, const LeanTrimState& state, dynamics::ConfigVector& q);

// The tick's planned contacts: the first corner the plan lifts ends the opening (kOpening
// stops learning from then on; the trim holds). Off: nothing.
void lean_trim_note_plan_rt(const LeanTrimConfig& config, LeanTrimState& state, const planner::ContactFlags& planned);

// After the WBC's tick on the trimmed state: the residual, the gate and the trim's step.
// wbc_ok: the tick's QP answered (its forces are a plan); data, points: what the tick
// computed (dynamics terms at q, sole corners); v: the state's velocity. Off: nothing.
void lean_trim_update_rt(const LeanTrimConfig& config, LeanTrimState& state, const dynamics::Data& data,
                         const wbc::ForceVector& point_position_m, const wbc::ForceVector& force_N,
                         const dynamics::VelocityVector& v, bool wbc_ok, double gravity_m_s2, double dt_s);

}  // namespace kuavo::stack
