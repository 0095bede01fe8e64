// Recovery step: a step the motion did not plan, taken when the robot's capture point leaves
// the support polygon while the motion keeps both feet down (issue 20).
//
// The online MPC adapts where a planned swing foot lands, but it never adds a step: in a
// long double support a push or a drift is caught by the ankles alone, and once the capture
// point ξ = c + ċ/ω (linear inverted pendulum, ω = √(g/h)) is outside the support polygon
// no centre of pressure inside it can bring the CoM to rest. 52 of 57 show-campaign falls
// (stop 34) came in double support, 48 of them in one of at least 1 s.
//
// What it does, once per planner call, on the window the MPC is about to track:
//   trigger  the measured ξ is more than trigger_outside_m outside the convex hull of the
//            soles on trigger_calls calls in a row, or within -creep_outside_m of its edge
//            (or beyond) on creep_calls calls in a row (not within settle_s of a reset), the
//            motion keeps both feet down from now until the step has landed plus quiet_s,
//            and no recovery swing is under way.
//   choose   each foot in turn as the swing foot: the centre of pressure is taken at the
//            point of the other (stance) sole nearest ξ, ξ is propagated to touchdown
//            (ξ_T = p + (ξ − p)e^{ωT}), and the swing sole's centre goes overshoot_m beyond
//            ξ_T, inside the reach box around the stance foot (its own axes: ahead/behind,
//            and beside it on the swing foot's side) and at most max_step_m from where the
//            motion has it. A candidate captures if ξ_T is step_capture_margin_m inside the
//            support it makes; the one with the larger margin is taken, and if neither
//            captures no step is taken (a sideways exit, or a wide stance whose single
//            support would throw ξ farther out: the ankles keep trying, as before).
//   rewrite  knots in [lift, land): the swing foot is out of contact, its corners move
//            to the new place on a smooth profile with a lift_height_m arc; from land on,
//            the foot stays displaced. The legs are re-solved on the sole corners
//            (leg_ik.h) and their velocities follow by differences of the displacement, so
//            the MPC's joint reference and its swing and stance rows agree.
//   return   the displacement is held until the motion itself lifts that foot: over the
//            motion's own swing it blends back to zero, and the foot lands where the
//            motion has it.
//
// Why a second trigger (stop 54): the soles' hull is not the region the ankles can hold. A
// loaded ankle's two motors (27 N·m each) give about 49 N·m of pitch through the linkage,
// which holds the centre of pressure at most 49 N·m / 340 N = 0.14 m ahead of the ankle,
// 3 cm short of the toe (0.171 m). So ξ can cross the hull's edge slowly and for good while
// the 1 cm trigger waits: in perfume's push-alone fall of seed 36 (pushed at 14.2 s) ξ went
// from 0.6 cm inside to 1.5 cm outside in 0.1 s; at 1.5 cm (14.60 s) the best step left ξ
// 1 mm inside, short of the 2 cm capture margin, and steps were declined until the fall;
// at 14.54 s (0.2 cm out, the creep trigger) it captured by 2.0 cm and the robot stood.
// In seed 15 the loaded ankle sat at its limit for 1.3 s with ξ 0–1 cm out; it steps
// sooner now but still falls (the step's weight transfer collapses). Lowering
// trigger_outside_m itself to -1 cm also stepped on single excursions the ankles catch
// (cmu_05_07 seed 44: 0.9 cm out once, a sideways step on 0.40 friction, fell; it stands
// without the step); 4 calls (0.08 s) in a row tell the two apart.
//
// Holdable soles (stop 65, ankle_pitch_capacity_Nm): the trigger's polygon is the part of
// each sole whose centre of pressure the ankle holds under that foot's share of the weight,
// not the sole. A lateral push in a double support loads one foot; that foot's ankle alone
// holds the centre of pressure P / F ahead of it (44 N·m / 540 N = 8 cm, the toe is at 17),
// so a CoM that stood 11 cm ahead of the ankles on two feet starts to fall forward while ξ
// is still 6 cm inside the soles. Perfume's show seed 29 (pushed to the left at 16.65 s):
// the right foot unloads (187 → 62 N by 17.2 s), the left ankle saturates at 38–42 N·m of
// pitch, and ξ crossed the toe line only at 17.08 s, too late for any step; with the holdable
// soles it triggers at 16.84 s. The step is still planned on the soles (plan_step): planning
// it from the centre of pressure the stance ankle holds under the whole weight (8 cm ahead of
// it) declined every step in two runs that step and dance without it (perfume 23 and 36) and
// saved none of the falls it was meant for. Loads by the lever rule (the CoM between the two
// ankles); P the ankle's pitch at the WBC's motor share: 0.9 × 49 N·m. Show campaign (the
// four motions of 2e6abcb × 100 seeds): 11/400 → 7/400; it saves perfume 27, 58, 64, 98 and
// cmu_05_07 71, and loses perfume 96 (pushed at 20.08 s, a step at once, fell at 20.74 s; it
// danced without a step before); 384 of the 400 logs are bit for bit the same, recovery steps
// are taken in 16 runs (5 before). Stop 65 kept it opt-in because the clips `kuavo retarget`
// wrote with it (its closed-loop check runs this stack) fell 31/400 against those 11. But those
// 11 were motions written before the MPC's coarse tail became the default (87bd2fa): the check
// of the pipeline as it stood (tail, trigger off) writes other motions too (perfume f9d2e95a,
// the same as with the trigger), and they fall 47/400 with it off (perfume 32, cmu_05_07 12,
// cmu_05_20 2, built-in 1). End to end, checked and danced with the trigger: 31/400 (perfume 24,
// cmu_05_07 5, cmu_05_20 1, built-in 1), with 12 show seeds in the check (24 since stop 67:
// 13/400, perfume 6; retarget_dynamic.h). On by default since stop 66; retarget_dynamic.h
// (verify_holdable_soles) has the check's side.
//
// Early touchdown (step timing, in a swing the motion plans): the MPC adapts where a swing
// foot lands but not when. Pushed towards the swing side in a long single support (cmu_05_20's
// first step, 0.7 s: three show-campaign falls in 60, each 1.0–1.4 s after a push at
// 1.8–2.7 s) the capture point runs past any landing within reach before the motion lands.
// When ξ at the motion's touchdown (centre of pressure at the stance sole's point nearest ξ)
// would lie early_trigger_m farther outside the support that touchdown makes than the
// motion's own ξ, and no landing within reach on the motion's clock would capture it, the
// foot lands early_lead_s from now instead, overshoot_m beyond ξ then (the reach box and
// max_step_m of a step), if that captures: the window's swing corners blend from the
// motion's to that landing, stand on it until the motion's touchdown, and the displacement
// is then held and returned like a step's. Not while the swing foot carries a displacement
// (its return swing: it lands where the motion has it). Both conditions matter: with the first alone
// (against a fixed margin) a show campaign on perfume fell in 58 of 60 runs, each from an
// early touchdown at 18.7 s (its own plan's ξ misses there; 4 cm of measured error grow 7×
// over the 0.56 s left, and the foot went 0.29 m back). And only in a swing of the motion
// that lasts early_min_swing_s: a long single support, which it was made for; in short ones
// (0.3 s) it threw the robot. The relative trigger still fires at perfume's 18.7 s under the
// show set's model errors (stop 67, motion f9d2e95a: 10 of 100 runs landed early, the four
// looked at all at 18.7 s; 7 fell at 19.2–21.0 s, six with no push in the 0.5 s before;
// `--early-touchdown off` danced 9, 53, 59, 65, 83, 96, 100 and fell in 44 and 70, late):
// the estimate's ξ 3–5 cm off the plan's, the landing 0.48 m from the foot just lifted
// (3.2 m/s over 0.15 s), the swing hips saturated and the stance knee threw the robot off the
// ground. Tried and not kept: a bound on the foot's mean speed, the landing moved later
// until the foot gets there. At 1 m/s it declines perfume's and keeps cmu_05_20's rescues
// (0.13–0.17 m in 0.15 s) but loses the step-in-place one below (16 N·s, 0.24 m in 0.15 s;
// recovery_step_loop_test); at 2 m/s perfume lands at 0.25 s and falls all the same. What
// separates them: the motion's own ξ at its touchdown, inside the support it makes in every
// rescue (margin +0.03…+0.08 m), 0.06–0.12 m outside in perfume's (a dynamic stride the next
// steps catch, which one early landing does not model): since stop 68 the early touchdown
// needs that margin to be at least early_plan_margin_min_m (0).
//
// Fast swing (stop 77, opt-in fast_swing_s, `kuavo simulate --recovery-fast-swing S`): a step
// that no swing_s landing captures is planned again with the shorter swing, which gives ξ less
// time to run (e^{ω(0.06 + 0.25)} = 2.9 against e^{ω(0.06 + 0.40)} = 4.8 at ω = 3.4 s⁻¹); a
// step the swing_s one captures is taken as before, so runs that never decline a step are bit
// for bit the same. Why: in the show campaign's cmu_05_07 falls the trigger comes and every
// step is declined (seed 36, pushed at 5.49 s: first trigger at 5.94 s, best margin −8 cm, the
// left foot 0.11 m short of the reach box's front; 57 declines until the fall at 6.56 s).
// Screens on the 14 show-campaign falls of cmu_05_07 and perfume (BENCHMARKS.md row 33, motions
// of 1c227c7): every step at 0.25 s (swing_s itself) saves cmu_05_07 47, 85 and perfume 94, 96,
// and loses perfume 58 and 64, which stepped and stood at 0.40 s (100 seeds each: cmu_05_07
// 7 → 5, perfume 7 → 7); 0.30 s saves none, 0.20 s five. As a fallback (this, at 0.25 s):
// cmu_05_07 5/100 (saves 47, 85; fast steps in 7 runs), perfume 58 and 64 dance, perfume's late
// falls (20.7–22.9 s) decline the 0.25 s step too. The whole show campaign (stop 78): 14/400
// against 16 on row 33's motions, but end to end (`kuavo retarget --verify-recovery-fast-swing
// 0.25`, the check dancing with it: cmu_05_07 keeps round 7 instead of 11, CoM path 27 % against
// 25 %) 16/400, as off (cmu_05_07 7/100). Off by default.
// Tried and not kept (stop 78): a last resort, after N triggers in a row where no step
// captures, the step whose ξ at touchdown lies least far outside the support it makes, taken
// if that is nearer than ξ with both feet kept down (a sideways exit never is). On the 16
// falls of row 33: N = 3 saved none (last-resort steps in 12 of them); N = 1 with the fast
// swing saved cmu_05_07 47, 75 and 85, the fast swing alone 47 and 85.
//
// Real-time: fixed-size state, no allocation; per call at most one leg solve per window
// knot that carries a displacement (≤ kMaxWindowKnots, ≤ 20 Gauss–Newton iterations each:
// 1.3 ms on the call that takes a step, 1.1 ms p50 on the one that lands a swing early, loaded),
// and only for the knots the previous call did not
// have (the window's tail: 33 µs p50 on the calls after it; mpc_bench). In a swing, the
// early touchdown's check reads the motion's frames back to the swing's lift-off.
#pragma once

#include <array>
#include <cstdint>

#include "controllers/planner/motion_plan.h"

namespace kuavo::planner {

// The holdable soles' pitch: the loaded ankle's two motors give ~49 N·m through the linkage;
// 0.9 of it, the WBC's ankle_motor_torque_share (wbc_config.h).
inline constexpr double kHoldableAnklePitch_Nm = 44.0;

struct RecoveryStepConfig {
  bool enabled = true;
  double trigger_outside_m = 0.01;  // ξ this far outside the support polygon …
  int trigger_calls = 2;            // … on this many planner calls in a row,
  // or ξ within -creep_outside_m of the edge, or beyond it, on creep_calls calls in a row (a
  // creep the ankles do not stop: see above). creep_outside_m <= trigger_outside_m.
  double creep_outside_m = -0.01;
  int creep_calls = 4;
  double lift_delay_s = 0.06;       // trigger → lift-off: the load moves to the stance foot
  double swing_s = 0.40;            // lift-off → touchdown (Leju's gait: 0.4–0.45 s a step)
  // A step no swing_s landing captures is planned again with this shorter swing, and taken if
  // that captures (0: off, the default; else in [0.1, swing_s]; "Fast swing" above).
  double fast_swing_s = 0.0;
  double lift_height_m = 0.05;      // swing apex above the motion's sole height
  double quiet_s = 0.20;            // the motion keeps both feet down this long after touchdown
  double overshoot_m = 0.04;        // sole centre beyond the predicted capture point
  // A recovery step is taken only if ξ at touchdown lies step_capture_margin_m inside the
  // support it makes (the stance sole and the swing sole at its landing); otherwise the ankles
  // keep trying. An early touchdown needs capture_margin_m.
  double capture_margin_m = 0.02;
  // 0.5 cm, not 2: a landing that holds ξ 0.4–1.5 cm inside is still a step the model says
  // catches it, and declining it waited for the fall (perfume's show seed 75). Show campaign:
  // 5/400 → 4/400 on row 33's motions, 5/400 end to end (BENCHMARKS.md; figures in 16bd318).
  double step_capture_margin_m = 0.005;
  double max_step_m = 0.30;         // displacement bound of one recovery step
  // Reach box of the swing sole's centre in the stance foot's axes (x ahead, y to the swing
  // side). Lateral minimum: the soles are 0.10 m wide, the standing feet 0.22 m apart.
  double reach_ahead_m = 0.30;
  double reach_behind_m = 0.30;
  double min_width_m = 0.16;
  double max_width_m = 0.40;
  double min_pendulum_height_m = 0.4;  // floor for h in ω = √(g/h)
  // No trigger this long after a reset: the estimator's velocity settles after start-up
  // (the show set's biased IMU on carpet: 0.58 m/s error at 26 ms, under 0.1 m/s by 0.1 s).
  double settle_s = 0.5;

  // Early touchdown (step timing): while the motion swings a foot, ξ propagated from the
  // measured state to the motion's touchdown (the centre of pressure at the stance sole's
  // point nearest ξ) lies early_trigger_m farther outside the support that touchdown makes
  // than the motion's own ξ (its first knot's, propagated alike; 0 if inside), no landing
  // within the reach box on the motion's clock captures it, on trigger_calls calls in a
  // row: the swing foot lands early_lead_s from now instead, overshoot_m beyond ξ at that
  // moment (reach box and max_step_m as for a step), if that captures by capture_margin_m
  // and gains at least early_min_gain_s on the motion. It stays there until the motion's
  // touchdown and then keeps the displacement like a step.
  bool early_touchdown = true;
  double early_trigger_m = 0.03;
  double early_lead_s = 0.15;
  double early_min_gain_s = 0.10;
  // … and only in a long swing: from the motion's lift-off of that foot to the window knot it
  // lands on (within one knot, 0.02 s, of the motion's touchdown) lasts at least this long.
  // A short swing lands soon on its own, and rewriting it just after lift-off to land 0.15 s
  // later elsewhere threw the robot: in the show campaigns (the motions of stop 51) every early
  // touchdown in a swing of 0.29–0.31 s fell (cmu_05_07 seeds 12, 21, 25, 53; cmu_05_20 seed 12:
  // the stance foot's force spiked to 1.2–1.6 kN, then both feet left the ground) and each of
  // those runs danced to the end with the motion's clock; the ones in cmu_05_20's 0.67 s first
  // swing (seeds 4, 56) stood, and fell without it. Leju's gait steps in 0.4–0.45 s.
  double early_min_swing_s = 0.5;
  // … and only where the motion's own ξ at its touchdown (as above) lies at least this far
  // inside the support that touchdown makes. A motion that plans ξ outside there (a dynamic
  // stride its next steps catch) is not one a single early landing models: with perfume's
  // f9d2e95a (stop 67) the trigger fired at 18.7 s, where the motion's own margin is −0.06 to
  // −0.12 m, landed the foot 0.48 m away and 7 of the 10 runs that did fell; every rescue
  // measured (cmu_05_20's first swing, seeds 4, 56, 100; recovery_step_loop_test) has +0.03
  // to +0.08 m.
  double early_plan_margin_min_m = 0.0;

  // Holdable soles (0: off, the soles' corners): the trigger takes each foot's sole only as far
  // from its ankle, ahead and behind, as this much pitch holds the foot's share of the weight
  // (see above; on by default, `kuavo simulate --holdable-soles off` for the soles).
  double ankle_pitch_capacity_Nm = kHoldableAnklePitch_Nm;
};

// The trigger on the holdable soles (the default) or on the soles' corners (`--holdable-soles
// off` of kuavo simulate, kuavo_fw, kuavo_fw_sim; `kuavo retarget --verify-holdable-soles off`).
inline void set_holdable_soles(RecoveryStepConfig& config, bool on) {
  config.ankle_pitch_capacity_Nm = on ? kHoldableAnklePitch_Nm : 0.0;
}

// nullptr if usable, else what is wrong. Load time.
const char* recovery_step_validate(const RecoveryStepConfig& config);

// One foot's displacement from the motion: d(t) = from + s(t)·(to − from) during the
// recovery swing [lift, land) (s smooth 0 → 1), `to` after it, and back to 0 over the
// motion's own next swing of that foot [return_lift, return_land) once it is known.
//
// An early touchdown (`early`) instead: from lift_ns (the trigger) the swing sole blends from
// the motion's towards `landing` (the motion's touchdown corners, window coordinates) moved by
// `to`, reaches it at early_land_ns and stands there until land_ns (the motion's touchdown);
// from then on it is displaced by `to` as after a step.
struct FootDisplacement {
  bool active = false;
  Eigen::Vector2d from = Eigen::Vector2d::Zero(), to = Eigen::Vector2d::Zero();
  hal::TimeNs lift_ns = 0, land_ns = 0;
  bool early = false;
  hal::TimeNs early_land_ns = 0;
  std::array<Vec3, kCornersPerFoot> landing{Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  bool return_known = false;
  hal::TimeNs return_lift_ns = 0, return_land_ns = 0;
};

// What the displacements do to one knot, per foot: the sole's horizontal shift, the height
// its swing arc adds, and whether it is out of contact for a recovery swing.
struct KnotRewrite {
  std::array<Eigen::Vector2d, 2> d{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  std::array<double, 2> lift{};
  std::array<bool, 2> swing{};
  // An early touchdown's blend towards its landing (0 none … 1 down). Its landing corners and
  // time are not in the key: they stay fixed while a displacement lives, and a new one never
  // starts on the call after another on the same foot with the same `to`.
  std::array<double, 2> early{};
  bool operator==(const KnotRewrite& o) const {
    return d == o.d && lift == o.lift && swing == o.swing && early == o.early;
  }
};

struct RecoveryStepState {
  int outside_calls = 0;
  int creep_calls = 0;  // consecutive calls with ξ beyond creep_outside_m
  bool started = false;
  hal::TimeNs start_ns = 0;                // the first call after the reset
  std::array<FootDisplacement, 2> foot{};  // [left, right]
  std::uint64_t steps = 0;                 // recovery steps taken since the reset
  std::uint64_t fast_steps = 0;            // … of them with RecoveryStepConfig::fast_swing_s
  std::uint64_t declined = 0;              // triggers where no step (or early touchdown) would have captured
  std::uint64_t early_touchdowns = 0;      // swings landed before the motion's touchdown
  int early_calls = 0;                     // consecutive swing calls meeting the early trigger
  double last_outside_m = 0.0;             // ξ's distance outside the support at the last call (< 0 inside)
  dynamics::Data data;                     // scratch
  std::array<dynamics::ConfigVector, kMaxWindowKnots> q{};  // scratch: re-solved knots
  std::array<Eigen::Matrix<double, 12, 1>, kMaxWindowKnots> leg_delta{};  // scratch: re-solved − motion legs
  std::array<bool, kMaxWindowKnots> changed{};
  std::array<int, kMaxWindowKnots> hit{};  // scratch: the cache entry knot k reused, or −1

  // The previous call's rewritten knots, by window index: consecutive windows share all but
  // their tail, so a knot met again (same stamp, same motion sample, same displacement)
  // takes its re-solved legs, and, when its neighbours are met again too, the whole
  // rewritten knot, bit for bit (the rewrite of a held step: 1.4 ms for 61 knots).
  struct CachedKnot {
    hal::TimeNs stamp_ns = 0;
    dynamics::ConfigVector motion_q = dynamics::ConfigVector::Zero();
    dynamics::VelocityVector motion_v = dynamics::VelocityVector::Zero();
    KnotRewrite rewrite;
    dynamics::ConfigVector q = dynamics::ConfigVector::Zero();  // re-solved
    PlanKnot out;                                                 // rewritten
  };
  std::array<CachedKnot, kMaxWindowKnots> cache{};
  std::array<bool, kMaxWindowKnots> cache_valid{};
  int cache_count = 0;
};

void recovery_step_reset(RecoveryStepState& state);

// measured: the measured state at window.knots[0] as a knot (plan_knot_measured). motion:
// what the window was sampled from (the motion's next swings of a displaced foot),
// motion_lag_ns behind the knots' stamps (liftoff_hold.h). plan_offset: what the plan anchor
// (plan_anchor.h) will add to the window's horizontal positions after this call; a new
// step's landing, chosen on the measured state, has it taken off so that it lands where
// chosen. Rewrites window in place. Real-time safe.
void recovery_step_rt(const model::Model& model, const RecoveryStepConfig& config, RecoveryStepState& state,
                      const MotionPlan& motion, const PlanKnot& measured, PlanWindow& window,
                      hal::TimeNs motion_lag_ns = 0,
                      const Eigen::Vector2d& plan_offset = Eigen::Vector2d::Zero());

}  // namespace kuavo::planner
