// From a parsed BVH to robot-proportioned keypoint targets at 100 Hz.
//
// Steps (each one is a documented choice, reported in HumanTargets):
//  1. Reference frames: T-poses, calibration or origin poses put before the motion (cgspeed's
//     T-pose, Perfume's pose at the origin) are dropped whatever the dialect: repeatedly, a
//     held run of leading frames (still within 0.05 leg lengths) that ends in a jump no human
//     makes (over 0.2 leg lengths, and faster than 30 leg lengths/s or 5 times the median step of
//     the next 0.25 s) goes; the first run that moves before any jump is the motion, and nothing
//     after it is ever dropped. Searched over the first 5 s; the count is reported.
//  2. Units: BVH has none. The stature implied by the leg length picks metres, centimetres,
//     millimetres, inches or CMU units (×0.056444 m), whichever gives the most human height.
//     Only the report uses it: all geometry below is scaled by ratios. A skeleton that no unit
//     makes 0.57 .. 5.1 m tall (a factor 3 around 1.7 m) is no human and is refused.
//  3. Axes: the up axis is the file axis closest to the mean pelvis→neck direction (Y for
//     most files, Z for SFU-style files); heading: the left-hip minus right-hip direction,
//     averaged over the first half second, becomes the robot's +y, so the dancer starts
//     facing +x. Sides as named must hold: if the toes point backward of that facing over most
//     of the clip (median cosine below -0.5), left and right are swapped and the import stops.
//  4. Proportional scaling: the pelvis path is scaled by robot/human leg length; every other
//     keypoint is rebuilt down the chain pelvis→hip→knee→ankle→toe/heel and
//     pelvis→neck→shoulder→elbow→wrist→hand/thumb, neck→head, each human segment vector scaled
//     by the ratio of robot to human segment length. Human lengths come from the hierarchy's
//     zero-rotation pose unless that is more than 10 % off the clip's median (iClone CC_Base),
//     then from the median. An identical skeleton therefore maps onto itself exactly (the
//     retargeting oracle relies on it). Pelvis and neck are the hip and shoulder midpoints.
//  5. Resampling to the output rate (linear in positions; the pelvis orientation is rebuilt
//     from the resampled hips and neck).
//  6. Ground and origin: the 5th percentile of the lowest foot point is put at z = 0 (robot
//     sole height, so a flat human stance foot becomes a flat robot foot); the start pelvis at
//     x = y = 0; foot targets below the floor are raised to it (counted in the report).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "controllers/model/model.h"
#include "tools/mocap/bvh.h"
#include "tools/mocap/skeleton_map.h"

namespace kuavo::mocap {

// Where a keypoint sits on the robot: a point fixed on one body.
struct RobotKeypoint {
  int body = 0;
  Vec3 point_m = Vec3::Zero();  // in the body frame
};
std::array<RobotKeypoint, kNumKeypoints> robot_keypoints(const model::Model& robot);
// Robot keypoint positions in the zero pose, base frame.
std::array<Vec3, kNumKeypoints> robot_rest_keypoints(const model::Model& robot);
// Height of the ankle and toe keypoints above the sole plane with the foot flat [m].
double robot_ankle_height_m(const model::Model& robot);
double robot_toe_height_m(const model::Model& robot);

// Pelvis frame from keypoints: y = right→left hip, z = pelvis→neck made orthogonal to y.
Mat3 pelvis_frame(const std::array<Vec3, kNumKeypoints>& p);

struct TargetFrame {
  std::array<Vec3, kNumKeypoints> position_m{};  // robot world, z up, ground at z = 0
  Mat3 base_rotation = Mat3::Identity();         // target base_link orientation
};

struct ImportOptions {
  double rate_hz = 100.0;
  int drop_first_frames = -1;     // -1: detect leading reference frames; >= 0: drop exactly this many
  double heading_window_s = 0.5;  // the start heading is the mean hip line over this time
  bool feet_above_floor = true;   // clamp ankle/toe/heel targets to flat-foot height (step 6)
};

struct HumanTargets {
  double rate_hz = 100.0;
  std::vector<TargetFrame> frames;
  std::array<bool, kNumKeypoints> present{};  // optional keypoints may be absent

  // What the import decided (for the report).
  std::string family;
  std::string unit;  // "m", "cm", "mm", "inch", "cmu"
  double unit_to_m = 1.0;
  double human_height_m = 0.0;  // estimated stature
  double root_scale = 1.0;      // robot / human leg length
  char up_axis[3] = "+Y";
  int dropped_frames = 0;
  int feet_below_floor_frames = 0;  // frames where a foot target was raised by more than 1 mm
  double source_rate_hz = 0.0;
  int source_frames = 0;
};

bool make_targets(const Bvh& bvh, const SkeletonMap& map, const model::Model& robot, const ImportOptions& options,
                  HumanTargets& out, std::string& error);

}  // namespace kuavo::mocap
