// Human → robot correspondence: which BVH joint stands for which robot keypoint.
//
// Keypoints are anatomical landmarks both skeletons have (hip, knee, ankle, toe, shoulder,
// elbow, wrist, hand, thumb, head). The pelvis and the neck are not looked up: they are the
// midpoints of the two hips and of the two shoulders on both sides, which makes the
// pelvis→hip and neck→shoulder vectors purely lateral on human and robot alike.
//
// Built-in naming, no mapping file needed: a joint name is read, case-insensitively, as a
// side plus a body-part word, after dropping a rig prefix (a "namespace:" such as "mixamorig:",
// "mixamorig", "CC_Base_", "Bip01 ", Rigify's "DEF-", a prefix all names share). The side is written as a word before or
// after the part ("LeftUpLeg", "Left Knee", "ThighLeft") or a letter after a separator
// ("thigh.L", "UpperLeg_L", "L_Thigh", "Bip01 L Calf") or before the part ("lThigh", "rShin").
// The part must then be one of a keypoint's words as a whole: "LeftHandThumb1" is never the
// wrist ("hand"), "Leg" never l + "eg", and a joint is never two keypoints. That covers
// CMU/cgspeed, Mixamo, Perfume, iClone CC_Base, Blender/Rigify, Unity-style suffixes, the Unreal
// mannequin, DAZ/Poser prefixes, 3ds Max Biped, SMPL, ASF bone names and generic names (words per
// keypoint in skeleton_map.cpp); the robot's own link names (robot_bvh.h) are
// matched exactly. A match that cannot be right stops the import with a message: two joints
// reading the same, or a keypoint not below its chain parent (knee below hip, ...), or the two
// legs or arms not on separate branches. Anything else: a mapping file.
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

// The keypoint chain (pelvis at the root): the keypoint each one hangs from, -1 for the
// pelvis. Rebuilding targets with robot proportions walks it; the import checks that mapped
// joints sit below their parents in the BVH hierarchy.
int keypoint_parent(int k);

// Stable keypoint names, as used in mapping files: "left_hip", ..., "head", "left_thumb",
// "right_thumb", "left_heel", "right_heel", "pelvis", "neck".
const char* keypoint_name(int kp);
// Keypoints that may be missing: toes and hands fall back to their End Site or are dropped;
// head, thumbs and heels are dropped.
bool keypoint_optional(int kp);

struct SkeletonMap {
  std::array<int, kNumMappedKeypoints> joint{};  // BVH joint index per keypoint, -1 if absent
  // "cmu", "mixamo", "perfume", "cc_base", "biped", "blender", "side_suffix", "side_prefix",
  // "robot", "generic" or "file" (how the names were written; for the report).
  std::string family;
};

// Maps by name. On failure (a required keypoint unmapped, two joints reading the same, a
// keypoint not below its chain parent) returns false with an error naming the keypoints, the
// words looked for and the BVH's joints.
bool map_skeleton(const Bvh& bvh, SkeletonMap& out, std::string& error);

// A mapping file: one "keypoint = BVH joint name" per line, '#' starts a comment, blank
// lines ignored. Entries override the name matching (and its checks); the rest is still
// matched by name.
bool map_skeleton_with_file(const Bvh& bvh, const std::string& mapping_text, SkeletonMap& out, std::string& error);

}  // namespace kuavo::mocap
