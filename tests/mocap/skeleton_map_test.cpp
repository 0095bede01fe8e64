// Naming families without a mapping file: one skeleton geometry and motion, written with each
// family's joint names, maps every keypoint to the same joint and gives the same retargeting
// targets as the canonical CMU names. Names that look close but mean something else (a thumb
// beside the hand, "Leg" beside the l/r prefix, twist bones, a left joint under the right hip)
// never map silently: they map to nothing, or the import stops with a message.
#include "tools/mocap/skeleton_map.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tools/mocap/human_targets.h"

namespace kuavo::mocap {
namespace {

// The test skeleton's joints (End Sites are added after their parent, as "<parent>_End").
enum Role : int {
  kHips,
  kLThigh,
  kLThighTwist,  // a twist bone between hip and knee (CC_Base, DAZ, Rigify have them)
  kLKnee,
  kLAnkle,
  kLToe,
  kRThigh,
  kRThighTwist,
  kRKnee,
  kRAnkle,
  kRToe,
  kSpine,
  kChest,
  kNeck,
  kHead,
  kLClavicle,
  kLUpperArm,
  kLForearm,
  kLHand,
  kLThumb1,
  kLThumb2,
  kLMiddle1,
  kRClavicle,
  kRUpperArm,
  kRForearm,
  kRHand,
  kRThumb1,
  kRThumb2,
  kRMiddle1,
  kRoles
};

struct RoleDef {
  int parent;
  double x, y, z;  // offset [cm], Y up, the dancer faces +z
  bool end_site;   // the role has an End Site child
  double ex, ey, ez;
};
constexpr RoleDef kRoleDefs[kRoles] = {
    {-1, 0, 95, 0, false, 0, 0, 0},
    {kHips, 9, -5, 0, false, 0, 0, 0},
    {kLThigh, 0, -20, 0, false, 0, 0, 0},
    {kLThighTwist, 0, -22, 0, false, 0, 0, 0},
    {kLKnee, 0, -40, 0, false, 0, 0, 0},
    {kLAnkle, 0, -6, 12, true, 0, 0, 5},
    {kHips, -9, -5, 0, false, 0, 0, 0},
    {kRThigh, 0, -20, 0, false, 0, 0, 0},
    {kRThighTwist, 0, -22, 0, false, 0, 0, 0},
    {kRKnee, 0, -40, 0, false, 0, 0, 0},
    {kRAnkle, 0, -6, 12, true, 0, 0, 5},
    {kHips, 0, 10, 0, false, 0, 0, 0},
    {kSpine, 0, 15, 0, false, 0, 0, 0},
    {kChest, 0, 22, 0, false, 0, 0, 0},
    {kNeck, 0, 10, 1, true, 0, 18, 0},
    {kChest, 4, 18, 0, false, 0, 0, 0},
    {kLClavicle, 14, 0, 0, false, 0, 0, 0},
    {kLUpperArm, 28, 0, 0, false, 0, 0, 0},
    {kLForearm, 25, 0, 0, false, 0, 0, 0},
    {kLHand, 3, 0, 3, false, 0, 0, 0},
    {kLThumb1, 3, 0, 2, true, 2, 0, 1},
    {kLHand, 9, 0, 0, true, 4, 0, 0},
    {kChest, -4, 18, 0, false, 0, 0, 0},
    {kRClavicle, -14, 0, 0, false, 0, 0, 0},
    {kRUpperArm, -28, 0, 0, false, 0, 0, 0},
    {kRForearm, -25, 0, 0, false, 0, 0, 0},
    {kRHand, -3, 0, 3, false, 0, 0, 0},
    {kRThumb1, -3, 0, 2, true, -2, 0, 1},
    {kRHand, -9, 0, 0, true, -4, 0, 0},
};

using Names = std::array<const char*, kRoles>;

// Writes the skeleton with the given names (depth-first, End Sites after their joint) and a
// smooth 2 s motion at 50 Hz, then reads it back through the BVH parser.
Bvh skeleton(const Names& names) {
  Bvh b;
  std::vector<int> joint_of_role(kRoles, -1);
  // Depth-first order: children follow their parent; roles are listed parent-first per branch.
  std::vector<int> order;
  std::vector<int> stack = {kHips};
  while (!stack.empty()) {
    const int r = stack.back();
    stack.pop_back();
    order.push_back(r);
    for (int c = kRoles - 1; c >= 0; --c)
      if (kRoleDefs[c].parent == r) stack.push_back(c);
  }
  for (int r : order) {
    const RoleDef& d = kRoleDefs[r];
    BvhJoint j;
    j.name = names[r];
    j.parent = d.parent < 0 ? -1 : joint_of_role[d.parent];
    j.offset = Vec3(d.x, d.y, d.z);
    if (r == kHips)
      j.channels = {BvhChannel::kXposition, BvhChannel::kYposition, BvhChannel::kZposition,
                    BvhChannel::kZrotation, BvhChannel::kXrotation, BvhChannel::kYrotation};
    else
      j.channels = {BvhChannel::kZrotation, BvhChannel::kXrotation, BvhChannel::kYrotation};
    j.first_column = b.channel_count;
    b.channel_count += static_cast<int>(j.channels.size());
    joint_of_role[r] = static_cast<int>(b.joints.size());
    b.joints.push_back(j);
    if (d.end_site) {
      BvhJoint e;
      e.name = j.name + "_End";
      e.parent = joint_of_role[r];
      e.end_site = true;
      e.offset = Vec3(d.ex, d.ey, d.ez);
      b.joints.push_back(e);
    }
  }
  b.frame_time_s = 0.02;
  b.frame_count = 100;
  for (int f = 0; f < b.frame_count; ++f) {
    const double t = f * b.frame_time_s;
    for (int c = 0; c < b.channel_count; ++c) {
      double v = 12.0 * std::sin(2.0 * M_PI * 0.7 * t + 0.37 * c);                               // every joint moves
      if (c < 3) v = c == 1 ? 2.0 * std::sin(2.0 * M_PI * t) : 10.0 * t * (c == 0 ? 1.0 : 0.5);  // root path
      b.motion.push_back(v);
    }
  }
  Bvh back;
  std::string error;
  EXPECT_TRUE(parse_bvh(write_bvh(b), back, error)) << error;
  return back;
}

// The joint each keypoint must land on, by role; -1: absent.
constexpr int kExpectedRole[kNumMappedKeypoints] = {kLThigh,
                                                    kLKnee,
                                                    kLAnkle,
                                                    kLToe,
                                                    kRThigh,
                                                    kRKnee,
                                                    kRAnkle,
                                                    kRToe,
                                                    kLUpperArm,
                                                    kLForearm,
                                                    kLHand,
                                                    kLMiddle1,
                                                    kRUpperArm,
                                                    kRForearm,
                                                    kRHand,
                                                    kRMiddle1,
                                                    -2 /* head: its End Site */,
                                                    kLThumb2,
                                                    kRThumb2,
                                                    -1,
                                                    -1};

// clang-format off
const Names kCmu = {"Hips", "LeftUpLeg", "LeftUpLegRoll", "LeftLeg", "LeftFoot", "LeftToeBase",
    "RightUpLeg", "RightUpLegRoll", "RightLeg", "RightFoot", "RightToeBase", "Spine", "Spine1", "Neck", "Head",
    "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand", "LeftHandThumb1", "LeftHandThumb2", "LeftHandMiddle1",
    "RightShoulder", "RightArm", "RightForeArm", "RightHand", "RightHandThumb1", "RightHandThumb2",
    "RightHandMiddle1"};
struct Family {
  const char* family;  // what map_skeleton reports
  Names names;
  int thumb_role = kLThumb2;  // left thumb keypoint's joint; the right one mirrors it
};
const Family kFamilies[] = {
    {"cmu", kCmu},
    {"mixamo", {"mixamorig:Hips", "mixamorig:LeftUpLeg", "mixamorig:LeftUpLegRoll", "mixamorig:LeftLeg",
     "mixamorig:LeftFoot", "mixamorig:LeftToeBase", "mixamorig:RightUpLeg", "mixamorig:RightUpLegRoll",
     "mixamorig:RightLeg", "mixamorig:RightFoot", "mixamorig:RightToeBase", "mixamorig:Spine", "mixamorig:Spine1",
     "mixamorig:Neck", "mixamorig:Head", "mixamorig:LeftShoulder", "mixamorig:LeftArm", "mixamorig:LeftForeArm",
     "mixamorig:LeftHand", "mixamorig:LeftHandThumb1", "mixamorig:LeftHandThumb2", "mixamorig:LeftHandMiddle1",
     "mixamorig:RightShoulder", "mixamorig:RightArm", "mixamorig:RightForeArm", "mixamorig:RightHand",
     "mixamorig:RightHandThumb1", "mixamorig:RightHandThumb2", "mixamorig:RightHandMiddle1"}},
    {"blender", {"hips", "thigh.L", "thigh_twist.L", "shin.L", "foot.L", "toe.L", "thigh.R", "thigh_twist.R",
     "shin.R", "foot.R", "toe.R", "spine", "chest", "neck", "head", "shoulder.L", "upper_arm.L", "forearm.L",
     "hand.L", "thumb.01.L", "thumb.02.L", "f_middle.01.L", "shoulder.R", "upper_arm.R", "forearm.R", "hand.R",
     "thumb.01.R", "thumb.02.R", "f_middle.01.R"}},
    {"blender", {"DEF-hips", "DEF-thigh.L", "DEF-thigh_twist.L", "DEF-shin.L", "DEF-foot.L", "DEF-toe.L",
     "DEF-thigh.R", "DEF-thigh_twist.R", "DEF-shin.R", "DEF-foot.R", "DEF-toe.R", "DEF-spine", "DEF-chest",
     "DEF-neck", "DEF-head", "DEF-shoulder.L", "DEF-upper_arm.L", "DEF-forearm.L", "DEF-hand.L", "DEF-thumb.01.L",
     "DEF-thumb.02.L", "DEF-f_middle.01.L", "DEF-shoulder.R", "DEF-upper_arm.R", "DEF-forearm.R", "DEF-hand.R",
     "DEF-thumb.01.R", "DEF-thumb.02.R", "DEF-f_middle.01.R"}},
    {"side_suffix", {"Hips", "UpperLeg_L", "UpperLegTwist_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R",
     "UpperLegTwist_R", "LowerLeg_R", "Foot_R", "Toes_R", "Spine", "Chest", "Neck", "Head", "Shoulder_L",
     "UpperArm_L", "LowerArm_L", "Hand_L", "ThumbProximal_L", "ThumbIntermediate_L", "MiddleProximal_L",
     "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R", "ThumbProximal_R", "ThumbIntermediate_R",
     "MiddleProximal_R"}},
    {"generic", {"Pelvis", "Left Thigh", "Left ThighTwist", "Left Knee", "Left Ankle", "Left Toe", "Right Thigh",
     "Right ThighTwist", "Right Knee", "Right Ankle", "Right Toe", "Spine", "Chest", "Neck", "Head", "Left Collar",
     "Left Shoulder", "Left Elbow", "Left Wrist", "Left Thumb1", "Left Thumb2", "Left Middle1", "Right Collar",
     "Right Shoulder", "Right Elbow", "Right Wrist", "Right Thumb1", "Right Thumb2", "Right Middle1"}},
    {"side_prefix", {"hip", "lThigh", "lThighTwist", "lShin", "lFoot", "lToe", "rThigh", "rThighTwist", "rShin",
     "rFoot", "rToe", "abdomen", "chest", "neck", "head", "lCollar", "lShldr", "lForeArm", "lHand", "lThumb1",
     "lThumb2", "lMid1", "rCollar", "rShldr", "rForeArm", "rHand", "rThumb1", "rThumb2", "rMid1"}},
    {"side_prefix", {"HIP", "LTHIGH", "LTHIGHTWIST", "LSHIN", "LFOOT", "LTOE", "RTHIGH", "RTHIGHTWIST", "RSHIN",
     "RFOOT", "RTOE", "ABDOMEN", "CHEST", "NECK", "HEAD", "LCOLLAR", "LSHLDR", "LFOREARM", "LHAND", "LTHUMB1",
     "LTHUMB2", "LMID1", "RCOLLAR", "RSHLDR", "RFOREARM", "RHAND", "RTHUMB1", "RTHUMB2", "RMID1"}},
    {"cc_base", {"CC_Base_Hip", "CC_Base_L_Thigh", "CC_Base_L_ThighTwist01", "CC_Base_L_Calf", "CC_Base_L_Foot",
     "CC_Base_L_ToeBase", "CC_Base_R_Thigh", "CC_Base_R_ThighTwist01", "CC_Base_R_Calf", "CC_Base_R_Foot",
     "CC_Base_R_ToeBase", "CC_Base_Waist", "CC_Base_Spine01", "CC_Base_NeckTwist01", "CC_Base_Head",
     "CC_Base_L_Clavicle", "CC_Base_L_Upperarm", "CC_Base_L_Forearm", "CC_Base_L_Hand", "CC_Base_L_Thumb1",
     "CC_Base_L_Thumb2", "CC_Base_L_Mid1", "CC_Base_R_Clavicle", "CC_Base_R_Upperarm", "CC_Base_R_Forearm",
     "CC_Base_R_Hand", "CC_Base_R_Thumb1", "CC_Base_R_Thumb2", "CC_Base_R_Mid1"}},
    {"biped", {"Bip01", "Bip01 L Thigh", "Bip01 L ThighTwist", "Bip01 L Calf", "Bip01 L Foot", "Bip01 L Toe0",
     "Bip01 R Thigh", "Bip01 R ThighTwist", "Bip01 R Calf", "Bip01 R Foot", "Bip01 R Toe0", "Bip01 Spine",
     "Bip01 Spine1", "Bip01 Neck", "Bip01 Head", "Bip01 L Clavicle", "Bip01 L UpperArm", "Bip01 L Forearm",
     "Bip01 L Hand", "Bip01 L Finger0", "Bip01 L Finger01", "Bip01 L Finger2", "Bip01 R Clavicle",
     "Bip01 R UpperArm", "Bip01 R Forearm", "Bip01 R Hand", "Bip01 R Finger0", "Bip01 R Finger01",
     "Bip01 R Finger2"}},
    {"side_suffix", {"pelvis", "thigh_l", "thigh_twist_01_l", "calf_l", "foot_l", "ball_l", "thigh_r",
     "thigh_twist_01_r", "calf_r", "foot_r", "ball_r", "spine_01", "spine_02", "neck_01", "head", "clavicle_l",
     "upperarm_l", "lowerarm_l", "hand_l", "thumb_01_l", "thumb_02_l", "middle_01_l", "clavicle_r", "upperarm_r",
     "lowerarm_r", "hand_r", "thumb_01_r", "thumb_02_r", "middle_01_r"}},  // Unreal mannequin
    // SMPL-H: "L_Foot" is the toe joint below "L_Ankle", and the collar is the clavicle.
    {"side_prefix", {"Pelvis", "L_Hip", "L_HipTwist", "L_Knee", "L_Ankle", "L_Foot", "R_Hip", "R_HipTwist",
     "R_Knee", "R_Ankle", "R_Foot", "Spine1", "Spine3", "Neck", "Head", "L_Collar", "L_Shoulder", "L_Elbow",
     "L_Wrist", "L_Thumb1", "L_Thumb2", "L_Middle1", "R_Collar", "R_Shoulder", "R_Elbow", "R_Wrist", "R_Thumb1",
     "R_Thumb2", "R_Middle1"}},
    {"generic", {"pelvis", "left_hip", "left_hip_twist", "left_knee", "left_ankle", "left_foot", "right_hip",
     "right_hip_twist", "right_knee", "right_ankle", "right_foot", "spine1", "spine3", "neck", "head",
     "left_collar", "left_shoulder", "left_elbow", "left_wrist", "left_thumb1", "left_thumb2", "left_middle1",
     "right_collar", "right_shoulder", "right_elbow", "right_wrist", "right_thumb1", "right_thumb2",
     "right_middle1"}},  // SMPL-X
    // ASF bone names (amc2bvh): the wrist is "lwrist", the hand beyond it, the thumb one bone.
    {"side_prefix", {"root", "lfemur", "lfemurtwist", "ltibia", "lfoot", "ltoes", "rfemur", "rfemurtwist", "rtibia",
     "rfoot", "rtoes", "lowerback", "thorax", "lowerneck", "head", "lclavicle", "lhumerus", "lradius", "lwrist",
     "lthumb", "lthumbtip", "lfingers", "rclavicle", "rhumerus", "rradius", "rwrist", "rthumb", "rthumbtip",
     "rfingers"}, kLThumb1},
    // MotionBuilder HumanIK: every name carries the character's name.
    {"generic", {"Character1_Hips", "Character1_LeftUpLeg", "Character1_LeftUpLegRoll", "Character1_LeftLeg",
     "Character1_LeftFoot", "Character1_LeftToeBase", "Character1_RightUpLeg", "Character1_RightUpLegRoll",
     "Character1_RightLeg", "Character1_RightFoot", "Character1_RightToeBase", "Character1_Spine",
     "Character1_Spine1", "Character1_Neck", "Character1_Head", "Character1_LeftShoulder", "Character1_LeftArm",
     "Character1_LeftForeArm", "Character1_LeftHand", "Character1_LeftHandThumb1", "Character1_LeftHandThumb2",
     "Character1_LeftHandMiddle1", "Character1_RightShoulder", "Character1_RightArm", "Character1_RightForeArm",
     "Character1_RightHand", "Character1_RightHandThumb1", "Character1_RightHandThumb2",
     "Character1_RightHandMiddle1"}},
    // OptiTrack Motive: the asset name in front, UArm/FArm for the arm bones.
    {"side_prefix", {"Skeleton_Hip", "Skeleton_LThigh", "Skeleton_LThighTwist", "Skeleton_LShin", "Skeleton_LFoot",
     "Skeleton_LToe", "Skeleton_RThigh", "Skeleton_RThighTwist", "Skeleton_RShin", "Skeleton_RFoot",
     "Skeleton_RToe", "Skeleton_Ab", "Skeleton_Chest", "Skeleton_Neck", "Skeleton_Head", "Skeleton_LShoulder",
     "Skeleton_LUArm", "Skeleton_LFArm", "Skeleton_LHand", "Skeleton_LThumb1", "Skeleton_LThumb2",
     "Skeleton_LMiddle1", "Skeleton_RShoulder", "Skeleton_RUArm", "Skeleton_RFArm", "Skeleton_RHand",
     "Skeleton_RThumb1", "Skeleton_RThumb2", "Skeleton_RMiddle1"}},
    // Kinect v2: side word after the part; FootLeft is the toe joint below AnkleLeft; the hand
    // point is the wrist's child that is not the thumb.
    {"generic", {"SpineBase", "HipLeft", "ThighTwistLeft", "KneeLeft", "AnkleLeft", "FootLeft", "HipRight",
     "ThighTwistRight", "KneeRight", "AnkleRight", "FootRight", "SpineMid", "SpineShoulder", "Neck", "Head",
     "ClavicleLeft", "ShoulderLeft", "ElbowLeft", "WristLeft", "ThumbLeft", "ThumbTipLeft", "HandTipLeft",
     "ClavicleRight", "ShoulderRight", "ElbowRight", "WristRight", "ThumbRight", "ThumbTipRight", "HandTipRight"},
     kLThumb1},
};
// clang-format on

int joint_of(const Bvh& b, const Names& names, int role) { return b.find(names[role]); }

bool targets(const Bvh& b, HumanTargets& t, std::string& error) {
  model::Model robot;
  model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
  SkeletonMap map;
  return map_skeleton(b, map, error) && make_targets(b, map, robot, {}, t, error);
}

TEST(mocap_skeleton_map, EveryFamilyMapsEachKeypointToItsJointAndGivesTheCmuTargets) {
  const Bvh cmu = skeleton(kCmu);
  HumanTargets reference;
  std::string error;
  ASSERT_TRUE(targets(cmu, reference, error)) << error;
  for (const Family& fam : kFamilies) {
    SCOPED_TRACE(fam.names[kLThigh]);
    const Bvh b = skeleton(fam.names);
    SkeletonMap map;
    ASSERT_TRUE(map_skeleton(b, map, error)) << error;
    EXPECT_EQ(map.family, fam.family);
    for (int k = 0; k < kNumMappedKeypoints; ++k) {
      int role = kExpectedRole[k];
      if (k == kKpLeftThumb) role = fam.thumb_role;
      if (k == kKpRightThumb) role = fam.thumb_role + (kRThumb1 - kLThumb1);
      const int expected = role == -2 ? b.find(std::string(fam.names[kHead]) + "_End")
                           : role < 0 ? -1
                                      : joint_of(b, fam.names, role);
      EXPECT_EQ(map.joint[k], expected) << keypoint_name(k) << " got "
                                        << (map.joint[k] >= 0 ? b.joints[map.joint[k]].name : "nothing");
    }
    HumanTargets t;
    ASSERT_TRUE(targets(b, t, error)) << error;
    ASSERT_EQ(t.frames.size(), reference.frames.size());
    EXPECT_EQ(t.present, reference.present);
    double worst = 0.0;
    for (std::size_t f = 0; f < t.frames.size(); ++f)
      for (int k = 0; k < kNumKeypoints; ++k)
        if (fam.thumb_role == kLThumb2 || (k != kKpLeftThumb && k != kKpRightThumb))  // the same thumb joint
          worst = std::max(worst, (t.frames[f].position_m[k] - reference.frames[f].position_m[k]).norm());
    EXPECT_LT(worst, 1e-9);
  }
}

Names renamed(Names names, int role, const char* name) {
  names[role] = name;
  return names;
}

std::string map_error(const Names& names) {
  SkeletonMap map;
  std::string error;
  EXPECT_FALSE(map_skeleton(skeleton(names), map, error));
  return error;
}

// Close names that mean something else are not taken for the keypoint.
TEST(mocap_skeleton_map, LookAlikeNamesNeverMapSilently) {
  const Names* blender = &kFamilies[2].names;
  const Names* daz = &kFamilies[6].names;
  // No joint is the hand (wrist) any more: the thumb and finger beside it are not taken.
  std::string e = map_error(renamed(kCmu, kLHand, "LeftHandThumb"));
  EXPECT_NE(e.find("unmapped keypoints: left_wrist (a joint named by one of wrist, hand)"), std::string::npos) << e;
  // "Leg" without a side is not l + "eg", nor any knee.
  e = map_error(renamed(*daz, kLKnee, "leg"));
  EXPECT_NE(e.find("unmapped keypoints: left_knee"), std::string::npos) << e;
  e = map_error(renamed(*daz, kLKnee, "Lowerleg"));  // l + "owerleg": no part
  EXPECT_NE(e.find("unmapped keypoints: left_knee"), std::string::npos) << e;
  // Twist and helper bones are not the joint they sit beside.
  e = map_error(renamed(*blender, kLThigh, "thigh_parent.L"));
  EXPECT_NE(e.find("unmapped keypoints: left_hip"), std::string::npos) << e;
  // Two joints read the same: refused, both named.
  e = map_error(renamed(*blender, kLThighTwist, "THIGH.L"));
  EXPECT_NE(e.find("ambiguous names: left_hip: both 'thigh.L' and 'THIGH.L' read as 'thigh'"), std::string::npos) << e;
  // A left knee under the right hip (names swapped on one level): refused.
  e = map_error(renamed(renamed(kCmu, kLKnee, "RightLeg"), kRKnee, "LeftLeg"));
  EXPECT_NE(e.find("left_knee 'LeftLeg' is not below left_hip 'LeftUpLeg'"), std::string::npos) << e;
  // A whole right arm named inside the left one (each chain consistent in itself): refused.
  Names nested = kCmu;
  for (const auto& [role, name] : {std::pair{kLClavicle, "LeftArm"},
                                   {kLUpperArm, "LeftForeArm"},
                                   {kLForearm, "LeftHand"},
                                   {kLHand, "RightArm"},
                                   {kLThumb1, "RightForeArm"},
                                   {kLThumb2, "RightHand"},
                                   {kRUpperArm, "Rupper"},
                                   {kRForearm, "Rfore"},
                                   {kRHand, "Rpalm"},
                                   {kRThumb1, "x1"},
                                   {kRThumb2, "x2"},
                                   {kRMiddle1, "x3"}})
    nested[role] = name;
  e = map_error(nested);
  EXPECT_NE(e.find("left_shoulder 'LeftArm' and right_shoulder 'RightArm' are not separate branches"),
            std::string::npos)
      << e;
}

// "Foot" is a toe word only below another ankle (SMPL): where it is the ankle and the toe joint
// has no toe name, the toe is the joint below it, not the foot a second time.
TEST(mocap_skeleton_map, AJointIsNeverTwoKeypoints) {
  const Names& blender = kFamilies[2].names;
  const Bvh b = skeleton(renamed(renamed(blender, kLToe, "toe_helper.L"), kRToe, "toe_helper.R"));
  SkeletonMap map;
  std::string error;
  ASSERT_TRUE(map_skeleton(b, map, error)) << error;
  EXPECT_EQ(map.joint[kKpLeftAnkle], b.find("foot.L"));
  EXPECT_EQ(map.joint[kKpLeftToe], b.find("toe_helper.L"));
  EXPECT_EQ(map.joint[kKpRightToe], b.find("toe_helper.R"));
}

TEST(mocap_skeleton_map, UnmappableSkeletonNamesEveryMissingKeypoint) {
  Names nonsense{};
  static std::array<std::string, kRoles> storage;
  for (int r = 0; r < kRoles; ++r) {
    storage[r] = "Bone" + std::to_string(r);
    nonsense[r] = storage[r].c_str();
  }
  const std::string e = map_error(nonsense);
  for (int k = 0; k < kNumMappedKeypoints; ++k) {
    if (keypoint_optional(k)) continue;
    EXPECT_NE(e.find(std::string(keypoint_name(k)) + " (a joint named by one of"), std::string::npos)
        << keypoint_name(k) << ": " << e;
  }
  EXPECT_NE(e.find("BVH joints: Bone0, Bone1"), std::string::npos) << e;
  EXPECT_NE(e.find("--map"), std::string::npos) << e;
}

}  // namespace
}  // namespace kuavo::mocap
