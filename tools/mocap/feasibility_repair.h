// Automatic feasibility repair: a geometric retargeting result → a reference the robot can
// dance, before the dynamic retargeting (dynamic_retarget.h) optimizes it.
//
// What a human dance holds that this robot cannot do as captured, and what each becomes:
//  - flight (hops, leaps, jetés: neither foot on the floor) → the foot that left last stays
//    down until the other lands (a leap becomes a step, a hop a double-support bounce: the
//    pelvis keeps its vertical motion within the acceleration the planted feet can carry,
//    max_vertical_acceleration_m_s2; so does a fast drop into a crouch);
//  - swings shorter than the leg can lift and place a foot (min_swing_s) and double-support
//    phases shorter than a weight transfer (min_double_support_s) → re-timed: touch-down or
//    lift-off delayed by the missing time; the schedule is re-read from the human at every
//    frame, so the delay does not accumulate (a step the robot cannot fit is skipped and
//    reported);
//  - strides longer than the legs, feet crossing or colliding → the touchdown placed at the
//    nearest reachable spot relative to the stance foot (stride shortened / widened);
//  - pivots and pirouettes on one foot (the human stance foot turns, a planted robot foot
//    cannot) and turns faster than the hip yaw allows → the foot keeps its touchdown heading,
//    the relative heading of the next touchdown is limited to the hip-yaw range, so the turn
//    is carried out by the following steps (stepping turns);
//  - arm and head accelerations beyond what their joints' torques give → smoothed;
//  - a stance foot the legs cannot lay flat on its foothold at the human's pelvis pose (a
//    torso leaning or twisted beyond the hip and ankle ranges) → the pelvis moves towards
//    standing over its feet there (stance_reach);
//  - a double support held with the CoM far ahead of (or behind) the ankles, where the ankle
//    motors hold the weight with little reserve left (a human's centre of pressure sits on
//    the ball of the foot; this robot's two ankle motors hold ~49 N·m of pitch, the centre
//    of pressure 9 cm ahead of the ankle under its whole weight) → the pelvis moves back
//    over the feet by what the CoM's 1 s average stands beyond the standing pose's (opt-in:
//    max_stance_lean_m, stance_lean);
//  - a motion that does not start standing → a lead-in: the robot stands in double support
//    on the dance's first footholds, then blends into the dance's first pose; a tail that
//    ends in double support, standing: a step that lands in it is set down square beside
//    the other foot (square_tail_step).
// The geometric stage's upper body, head, pelvis height and orientation (yaw kept within the
// hip-yaw range of the stance feet) are kept; legs are re-solved by inverse kinematics to the
// repaired feet: stance feet flat at their footholds, swing feet from lift-off to touchdown
// foothold, raised to at least a swing arc, following the human's foot otherwise (kicks and
// leg gestures stay). Every repair is listed with its time range, kind and reason.
//
// Overrides (a text file, like the contact overrides): lines
//   start_s end_s forbid KIND     (KIND: flight, retime, stride, turn, upper, pelvis, bounce, travel,
//                                  attenuate, reach, lean, or all)
//   start_s end_s force double    (both feet down over the range: a hold or a bounce)
//   start_s end_s force square    (both feet down, side by side at the standing width, the pelvis
//                                  over them: a hold with the widest support)
//   start_s end_s calm steps      (shorter strides and slower travel: RepairConfig::calm_*)
// times in the dance's own clock (the geometric motion's, before the lead-in). A forbidden
// flight repair leaves the flight in the schedule: the dynamic stage then refuses the motion
// with a message naming the time (the robot cannot fly). Offline; allocates.
#pragma once

#include <string>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/contact_label.h"

namespace kuavo::mocap {

struct RepairConfig {
  // Shortest swing the robot lifts and places a foot in, and shortest weight transfer. The
  // built-in dance steps with 0.4 s swings and 0.1 s double support, Leju's gait with
  // 0.4–0.6 s swings; 0.3 s is the fastest step the online stack has been shown to track.
  double min_swing_s = 0.30;
  double min_double_support_s = 0.10;
  double lead_in_s = 0.8;   // standing still on the first footholds
  double blend_in_s = 1.0;  // standing pose → the dance's first pose
  double tail_s = 1.0;      // both feet down after the dance, blending to standing
  // A step that lands in the tail (the human's last, still in the air when the clip ends) is
  // set down beside the other foot, square, at the standing width and heading, so the motion
  // ends standing as it starts (false: where the human's would land, within the limits below).
  bool square_tail_step = true;
  // Swing foot: apex of the minimum arc [m] (the built-in dance: 0.06), highest foot the
  // reference keeps from the human [m] (a kick above the knee is out of the leg's reach).
  double swing_lift_m = 0.06;
  double max_foot_height_m = 0.35;
  // Reachable touchdown relative to the stance foot, in its heading frame [m] (centre to
  // centre of the soles). Leg length 0.71 m, hip width 0.174 m (FACTS.md): a 0.4 m stride
  // keeps the knees bent at the standing height; feet nearer than 0.15 m laterally collide
  // (sole width 0.095 m plus the ankle linkages).
  double max_step_forward_m = 0.40;
  double max_step_backward_m = 0.30;
  double min_step_width_m = 0.15;
  double max_step_width_m = 0.45;
  // Relative heading of the two feet (hip yaw leg_l2/r2 range −0.87…0.79 rad, FACTS.md). The
  // built-in dance turns with 45° between the feet and dances that in simulation; 0.55 rad
  // (32°) made the repair lag its turn by up to 139° there (hands 1.3 m off the human's, and
  // a fall at 25 s while it caught up).
  double max_relative_yaw_rad = 0.80;
  // A human stance foot turning more than this counts as a pivot [rad].
  double pivot_yaw_rad = 0.35;
  // Base orientation kept within this of the level pose [rad]. The 4Pro has no waist: the
  // base's tilt is the whole torso's lean. Show campaign (carpet, the show set, one 10 N·s
  // push): the built-in dance, 1 fall in 100 runs, leans at most 6°; perfume 12° (9 / 30);
  // cmu_05_07 and cmu_05_20 leaned up to 25° and 23° under the former bound, 0.45 rad (26°),
  // and fell in 38 / 60 and 33 / 60 runs (seeds 1–60), most at the same moments. At 0.30 rad
  // (17°): 28 / 60 and 20 / 60, perfume the same 9 / 30, and the dynamic stage kept more of
  // both CMU dances (CoM path 2.06 → 2.69 m and 1.76 → 2.18 m; 3 and 1 more steps): the
  // closed-loop check passed cmu_05_20 at its round 7, where no round passed before. At
  // 0.20 rad (11°) the check's rounds went another way: 19 / 30 and 27 / 30 (seeds 1–30).
  double max_base_tilt_rad = 0.30;
  // Arm and head joints: the acceleration a joint's torque limit gives its own inertia at the
  // standing pose, times this share (the rest is left for gravity and the body's motion), is
  // the most the reference asks of it; 0 turns the limit off. A human arm's snap (the built-
  // in dance's punches, ~300 rad/s², which the RNEA prices at 146 N·m on a 60 N·m shoulder)
  // is smoothed over the frames around it.
  double upper_torque_share = 0.5;
  // Least knee bend of a stance leg [rad]: a human dancer stands on nearly straight legs
  // (perfume: stance knees at 0.11–0.18 rad, scaled pelvis height kept), where the leg's
  // Jacobian loses the vertical direction and the controllers lose the base height; the
  // robot then fell at 14.6 s with both ankles saturated. The built-in dance, which the
  // online stack dances on floor and carpet, keeps its stance knees at a median of 0.56 rad
  // (10th percentile 0.40). The pelvis is lowered (smoothly) where a stance leg would be
  // straighter: 0.5 rad costs at most 2.5 cm of pelvis height. 0 turns it off.
  double min_stance_knee_rad = 0.5;
  // Deepest knee bend of a stance leg [rad]: the pelvis is raised where a crouch would fold a
  // stance knee further. perfume's deepest stance knee (1.43 rad after the repair) is danced;
  // cmu_05_07's crouch at 7.5 s (pelvis at 0.51 m, knee 1.97 rad) asked 414 N·m of a hip
  // pitch (limit 72) in the TO's result and fell. 0 turns it off.
  double max_stance_knee_rad = 1.45;
  // Fastest travel [m/s]: a foot's touchdown lies at most this × the time since its previous
  // touchdown from its previous foothold. The built-in dance, danced on floor and carpet,
  // travels at most 0.46 m/s (base, 0.5 s average); perfume and cmu_05_07 fell while
  // travelling at 0.6–0.75 m/s with the stance knee and hip pitch at their torque limits
  // (130 and 72 N·m) and the robot running ahead of its plan. The dance travels a shorter
  // path; later steps make up the lag (each within the limit); a lag left at the end stays
  // (the stride repair's relative placement carries it). 0 turns it off.
  double max_travel_speed_m_s = 0.45;
  // Largest vertical acceleration of the pelvis, up or down [m/s²]. With the feet planted the
  // body cannot drop faster than g (the floor does not pull) and the legs cannot push
  // arbitrarily hard: at half of g the feet carry between 0.5 and 1.5 × the weight, leaving
  // the friction cones and the ankles their load. A hop kept as a double-support bounce
  // (cmu_05_07 at 5.5–7.7 s: the pelvis dropped 0.21 m in 0.35 s and rose again) had the TO's
  // feet carrying 19 N of the 540 N weight and asked 414 N·m of a hip pitch (limit 72) at the
  // top. 0 turns it off.
  double max_vertical_acceleration_m_s2 = 0.5 * 9.81;
  // Calm steps, where an override asks for them ("START END calm steps"; the closed-loop check
  // of `kuavo retarget` adds them where the online stack fell twice): touchdowns within these
  // of the stance foot and travel no faster than this. cmu_05_20 and cmu_05_07 with them
  // everywhere (and the closed-loop check) danced to the end on the floor, where with the
  // limits above they fell at 9.2–9.8 s and 11.8–12.2 s; everywhere they would also shorten
  // the built-in dance's travel, which it dances as it is.
  double calm_step_forward_m = 0.30;
  double calm_step_backward_m = 0.20;
  double calm_step_width_m = 0.35;
  double calm_travel_speed_m_s = 0.35;
  // Stance lean: in double support the CoM's 1 s average (stance_lean_window_s, over frames
  // of which at least half are double support) is read against the segment between the two
  // feet's standing centres of pressure (each ankle plus the standing pose's own CoM-ahead-of-
  // ankles, 4.2 cm), along the feet's heading; beyond stance_lean_band_m the pelvis moves back
  // (or ahead) by the rest, at most max_stance_lean_m, over the pelvis-to-CoM ratio of the
  // standing pose (the legs' mass moves less), smoothed over ±0.25 s, legs re-solved (a frame
  // whose legs do not reach keeps its pose, and the report counts it). A human's centre of
  // pressure sits on the ball of the foot; this robot's ankle holds 49 N·m of pitch through
  // its two motors, the centre of pressure 9 cm ahead of the ankle under the whole weight,
  // and the TO's leg-torque barrier holds each ankle within 24.3 N·m. The three clips'
  // double supports stood (TO output, `--verify 0`) with the centre of pressure mostly 6–8 cm
  // ahead of the ankle, the built-in dance's 2–4 cm; perfume's hold at 19.9–23.2 s with the
  // CoM 11.9 cm beyond the standing pose's and an ankle at up to 48 N·m (the frames' RNEA),
  // danced at 24–31 N·m a foot and, in show runs that fell there (5 of its 7 falls), 43–47
  // N·m on one foot.
  // Measured at 5 cm (built-in / perfume / cmu_05_07 / cmu_05_20), off → on:
  //  - `--verify 0`: oracle torque violations 1068/633/626/580 → 1076/505/613/538, max
  //    |τ|/limit 2.15/2.37/3.54/2.74 → 2.15/2.08/3.17/2.37, CoM path kept 61/55/59/34 % →
  //    61/55/58/33 %; perfume's hold (20.2–23.0 s): its larger ankle pitch 20–48 → 22–33 N·m;
  //  - the whole check: kept round 0/8/11/8 → 0/7/7/8, seeds given up 0/0/6/3 → 0/1/3/1,
  //    steps 41/12/8/6 → 41/15/8/6 (of 41/15/11/7), CoM path kept 61/37/25/21 → 61/44/26/18 %;
  //  - but the show campaign (carpet, `show` set, a 10 N·s push, seeds 1–100) fell 21/400
  //    (1/11/7/2) against 16/400 (1/7/7/1): perfume's falls stay at its hold's end (22.2–24.3 s,
  //    9 of 11), where the pelvis comes forward again into the spin's first steps.
  // So 0 (off) by default; `kuavo retarget --stance-lean M` turns it on.
  double max_stance_lean_m = 0.0;
  double stance_lean_band_m = 0.01;
  double stance_lean_window_s = 1.0;
};

enum class RepairKind : int {
  kLeadIn = 0,       // standing start and blend into the first pose
  kFlight = 1,       // flight phase → support (step or bounce)
  kRetime = 2,       // swing or double support lengthened (touchdown/lift-off delayed)
  kStepSkipped = 3,  // a human step too short to fit: the foot stayed down
  kStride = 4,       // touchdown moved to a reachable spot (stride shortened, width fixed)
  kTurn = 5,         // pivot / fast turn: heading limited, turn carried by the next steps
  kTilt = 6,         // base tilt limited
  kTail = 7,         // both feet brought down at the end
  kForcedDouble = 8, // override: both feet down
  kUpperBodySpeed = 9,  // arm/head accelerations beyond their torques: smoothed
  kPelvisHeight = 10,   // pelvis lowered / raised so the stance knees stay within their bend range
  kTravel = 11,         // a step shortened so the dance travels no faster than the robot can
  kAttenuate = 12,      // the TO's result still over a leg's torque limits: gestures scaled down
  kBounce = 13,         // the pelvis's vertical acceleration limited (a bounce or a drop smoothed)
  kStanceReach = 14,    // pelvis turned towards level where a stance foot could not lie flat
  kStanceLean = 15,     // pelvis moved so the CoM stands over the ankles as in standing
};
const char* to_string(RepairKind k);

struct Repair {
  double start_s = 0.0, end_s = 0.0;  // output motion's clock (lead-in included)
  RepairKind kind = RepairKind::kLeadIn;
  std::string reason;
};

struct RepairOverride {
  double start_s = 0.0, end_s = 0.0;  // dance clock
  bool force_double = false;
  bool forbid_all = false;
  RepairKind forbid = RepairKind::kFlight;
  bool calm_steps = false;  // "calm steps": RepairConfig's calm_* limits over the range
  // "force square" (force_double too): the feet standing over the range are set side by side
  // at the standing width (the later touchdown beside the earlier foot, same heading) and the
  // pelvis comes over them as in standing: the widest margin a hold can give.
  bool square_stance = false;
};
// Parses the override text; false with a message naming the line.
bool parse_repair_overrides(const std::string& text, std::vector<RepairOverride>& out, std::string& error);

struct RepairedMotion {
  double rate_hz = 100.0;
  std::vector<dynamics::ConfigVector> q;  // the reference for the dynamic stage
  std::vector<ContactLabel> contacts;
  // Output frame i shows geometric frame i − lead_frames (clamped to the clip).
  int lead_frames = 0;
  int dance_frames = 0;
  std::vector<Repair> repairs;
  int human_steps = 0;  // swing phases in the human schedule, and in the repaired one
  int robot_steps = 0;
  double max_leg_ik_error_m = 0.0;  // stance feet (swing feet go as far as the legs reach)
};

// geometric: the geometric stage's frames and its robot contact labels (same length ≥ 2).
// false with a message on bad input (non-finite frames, lengths, a forbidden repair that
// leaves the motion impossible is NOT an error here: see the header).
bool repair_motion(const model::Model& robot, const std::vector<dynamics::ConfigVector>& geometric,
                   const std::vector<ContactLabel>& labels, double rate_hz, const RepairConfig& config,
                   const std::vector<RepairOverride>& overrides, RepairedMotion& out, std::string& error);

// The oracle's second pass (tools/cli/retarget_dynamic.cpp runs it): where the dynamic
// stage's result still asks a leg joint for more than its torque limit, the geometric motion's
// frames [a, b) (dance clock, frames) are scaled about their moving average over ±window_s
// (joints and pelvis height; q ← q̄ + gain·(q − q̄), blended in and out over window_s), so the
// gestures there keep their shape at a smaller amplitude and speed; the repair and the TO then
// run again. Frames an override forbids (kind attenuate, dance clock) are left alone; false
// if nothing was changed. Appends one Repair per range (output clock: + lead_s).
struct AttenuationRange {
  int a = 0, b = 0;
  double torque_ratio = 0.0;  // the worst |τ|/limit that asked for it, for the reason
  std::string why;            // else this is the reason (the closed-loop check's fall)
};
bool attenuate_gestures(std::vector<dynamics::ConfigVector>& geometric, double rate_hz,
                        const std::vector<AttenuationRange>& ranges, double gain, double window_s, double lead_s,
                        const std::vector<RepairOverride>& overrides, std::vector<Repair>& log);

// Count of swing phases (a foot leaving the floor and coming back) in a label sequence.
int count_steps(const std::vector<ContactLabel>& labels);

}  // namespace kuavo::mocap
