// Human → robot correspondence: which BVH joint stands for which robot keypoint.
//
// Keypoints are anatomical landmarks both skeletons have (hip, knee, ankle, toe, shoulder,
// elbow, wrist, hand, thumb, head). The pelvis and the neck are not looked up: they are the
// midpoints of the two hips and of the two shoulders on both sides, which makes the
// pelvis→hip and neck→shoulder vectors purely lateral on human and robot alike.
//
// Built-in naming families (matched after lower-casing, dropping non-alphanumerics and a
// "namespace:" prefix such as "mixamorig:"): CMU/cgspeed (LeftUpLeg, LeftArm ...), Mixamo
// (same names under a prefix), Perfume (LeftHip, LeftShoulder = upper arm ...), iClone
// CC_Base (CC_Base_L_Thigh ...), generic lower-case (l_hip, left_knee ...) and the robot's own
// link names (leg_l3_link ... as written by robot_bvh.h). Anything else: a mapping file.
#pragma once

#include <array>
#include <string>

#include "tools/mocap/bvh.h"

namespace kuavo::mocap {

enum Keypoint : int {
  kKpLeftHip = 0,
  kKpLeftKnee,
  kKpLeftAnkle,
  kKpLeftToe,
  kKpRightHip,
  kKpRightKnee,
  kKpRightAnkle,
  kKpRightToe,
  kKpLeftShoulder,
  kKpLeftElbow,
  kKpLeftWrist,
  kKpLeftHand,
  kKpRightShoulder,
  kKpRightElbow,
  kKpRightWrist,
  kKpRightHand,
  kKpHead,
  kKpLeftThumb,  // optional: makes the wrist's three joints observable
  kKpRightThumb,
  kKpLeftHeel,  // optional: with the toe, fixes the foot's roll against the hip's yaw
  kKpRightHeel,
  kNumMappedKeypoints,
  // Derived (midpoints), never looked up by name.
  kKpPelvis = kNumMappedKeypoints,
  kKpNeck,
  kNumKeypoints
};

// Stable keypoint names, as used in mapping files: "left_hip", ..., "head", "left_thumb",
// "right_thumb", "left_heel", "right_heel", "pelvis", "neck".
const char* keypoint_name(int kp);
// Keypoints that may be missing: toes and hands fall back to their End Site or are dropped;
// head, thumbs and heels are dropped.
bool keypoint_optional(int kp);

struct SkeletonMap {
  std::array<int, kNumMappedKeypoints> joint{};  // BVH joint index per keypoint, -1 if absent
  std::string family;                            // "cmu", "perfume", "cc_base", "robot", "generic", "file"
};

// Maps by the built-in tables. On failure (a required keypoint unmapped) returns false
// with an error listing every unmapped keypoint, the candidates tried and the BVH's joints.
bool map_skeleton(const Bvh& bvh, SkeletonMap& out, std::string& error);

// A mapping file: one "keypoint = BVH joint name" per line, '#' starts a comment, blank
// lines ignored. Entries override the built-in tables; the rest is still matched by name.
bool map_skeleton_with_file(const Bvh& bvh, const std::string& mapping_text, SkeletonMap& out, std::string& error);

}  // namespace kuavo::mocap
