// Import: naming families, mapping file, unit / up-axis / reference-frame inference and the
// proportional scaling, on the shared clips and on transformed copies of the built-in dance.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "tools/mocap/default_dance.h"
#include "tools/mocap/human_targets.h"
#include "tools/mocap/skeleton_map.h"

namespace kuavo::mocap {
namespace {

const std::string kMocap = std::string(KUAVO_SHARED_DIR) + "/mocap/";

struct Imported {
  SkeletonMap map;
  HumanTargets targets;
};

Imported import(const Bvh& bvh) {
  model::Model robot;
  model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
  Imported out;
  std::string error;
  EXPECT_TRUE(map_skeleton(bvh, out.map, error)) << error;
  EXPECT_TRUE(make_targets(bvh, out.map, robot, {}, out.targets, error)) << error;
  return out;
}

Bvh load(const char* file) {
  Bvh b;
  std::string error;
  EXPECT_TRUE(load_bvh_file(kMocap + file, b, error)) << error;
  return b;
}

TEST(mocap_import, SharedClipsFamiliesUnitsAndReferenceFrames) {
  const Bvh perfume = load("perfume_C_test.bvh");
  const Imported p = import(perfume);
  EXPECT_EQ(p.map.family, "perfume");
  EXPECT_EQ(perfume.joints[p.map.joint[kKpLeftShoulder]].name, "LeftShoulder");  // upper arm here
  EXPECT_EQ(p.targets.unit, "cm");
  EXPECT_EQ(p.targets.dropped_frames, 1);  // the reference pose at the origin
  EXPECT_STREQ(p.targets.up_axis, "+Y");

  const Bvh cmu = load("cmu_05_20_mb.bvh");
  const Imported c = import(cmu);
  EXPECT_EQ(c.map.family, "cmu");
  EXPECT_EQ(cmu.joints[c.map.joint[kKpLeftShoulder]].name, "LeftArm");  // not the clavicle
  EXPECT_EQ(c.targets.unit, "cmu");
  EXPECT_EQ(c.targets.dropped_frames, 1);  // the converter's T-pose
  EXPECT_NEAR(c.targets.human_height_m, 1.75, 0.2);

  const Imported cc = import(load("cmu_05_07_iclone_ccrig.bvh"));
  EXPECT_EQ(cc.map.family, "cc_base");
  EXPECT_EQ(cc.targets.unit, "cm");
  // Resampled to 100 Hz, the robot starts at the origin facing +x with its sole on the floor.
  for (const Imported* im : {&p, &c, &cc}) {
    EXPECT_EQ(im->targets.rate_hz, 100.0);
    const TargetFrame& f0 = im->targets.frames[0];
    EXPECT_NEAR(f0.position_m[kKpPelvis].x(), 0.0, 1e-12);
    EXPECT_NEAR(f0.position_m[kKpPelvis].y(), 0.0, 1e-12);
    EXPECT_GT(f0.position_m[kKpPelvis].z(), 0.5);
    EXPECT_LT(f0.position_m[kKpPelvis].z(), 1.0);
    EXPECT_GT(f0.position_m[kKpLeftHip].y(), f0.position_m[kKpRightHip].y());
  }
}

// A Z-up, inch-unit, Mixamo-named copy of the dance imports to the same robot targets.
TEST(mocap_import, ZUpInchesMixamoNamesGiveTheSameTargets) {
  const Bvh dance = default_dance_bvh();
  Bvh other = dance;
  constexpr double kCmToInch = 1.0 / 2.54;
  for (BvhJoint& j : other.joints) {
    j.offset *= kCmToInch;
    if (!j.end_site) j.name = "mixamorig:" + j.name;
    ++j.first_column;  // one channel for the new root comes first
  }
  for (double& v : other.motion) v *= 1.0;  // rotations unchanged
  for (int f = 0; f < other.frame_count; ++f)
    for (int c = 0; c < 3; ++c) other.motion[static_cast<std::size_t>(f) * other.channel_count + c] *= kCmToInch;
  // New root rotating the whole dance +90° about X: Y up becomes Z up (SFU style).
  BvhJoint root;
  root.name = "Reference";
  root.channels = {BvhChannel::kXrotation};
  other.joints.insert(other.joints.begin(), root);
  for (std::size_t i = 1; i < other.joints.size(); ++i) ++other.joints[i].parent;
  std::vector<double> motion;
  for (int f = 0; f < other.frame_count; ++f) {
    motion.push_back(90.0);
    const double* row = other.motion.data() + static_cast<std::size_t>(f) * other.channel_count;
    motion.insert(motion.end(), row, row + other.channel_count);
  }
  other.motion = motion;
  ++other.channel_count;

  Bvh reread;
  std::string error;
  ASSERT_TRUE(parse_bvh(write_bvh(other), reread, error)) << error;
  const Imported a = import(dance), b = import(reread);
  EXPECT_EQ(b.map.family, "mixamo");
  EXPECT_EQ(b.targets.unit, "inch");
  EXPECT_STREQ(b.targets.up_axis, "+Z");
  ASSERT_EQ(a.targets.frames.size(), b.targets.frames.size());
  double worst = 0.0;
  for (std::size_t f = 0; f < a.targets.frames.size(); ++f)
    for (int k = 0; k < kNumKeypoints; ++k)
      worst = std::max(worst, (a.targets.frames[f].position_m[k] - b.targets.frames[f].position_m[k]).norm());
  EXPECT_LT(worst, 1e-6);
}

// SFU-style: the hierarchy's rest pose lies Z-up while the animation is Y-up (every joint's
// rotation compensates). Only the world pose matters, so the targets are the same.
TEST(mocap_import, ZUpRestPoseWithYUpAnimationGivesTheSameTargets) {
  const Bvh dance = default_dance_bvh();
  Bvh sfu = dance;
  const Mat3 r = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();  // rest Y → Z
  for (BvhJoint& j : sfu.joints) j.offset = r * j.offset;
  std::vector<Vec3> pos;
  std::vector<Mat3> rot;
  for (int f = 0; f < sfu.frame_count; ++f) {
    bvh_pose(dance, f, pos, rot);
    double* row = sfu.motion.data() + static_cast<std::size_t>(f) * sfu.channel_count;
    for (std::size_t i = 0; i < sfu.joints.size(); ++i) {
      const BvhJoint& j = sfu.joints[i];
      if (j.end_site) continue;
      // New global = old global · rᵀ, so local = parent_newᵀ · global_new.
      const Mat3 parent = j.parent < 0 ? Mat3::Identity() : Mat3(rot[j.parent] * r.transpose());
      const Mat3 local = parent.transpose() * rot[i] * r.transpose();
      const Vec3 e = local.eulerAngles(2, 0, 1);  // the dance writes Z X Y
      const int c = j.first_column + (j.parent < 0 ? 3 : 0);
      for (int a = 0; a < 3; ++a) row[c + a] = e[a] * 180.0 / M_PI;
    }
  }
  Bvh reread;
  std::string error;
  ASSERT_TRUE(parse_bvh(write_bvh(sfu), reread, error)) << error;
  const Imported a = import(dance), b = import(reread);
  EXPECT_STREQ(b.targets.up_axis, "+Y");
  ASSERT_EQ(a.targets.frames.size(), b.targets.frames.size());
  double worst = 0.0;
  for (std::size_t f = 0; f < a.targets.frames.size(); ++f)
    for (int k = 0; k < kNumKeypoints; ++k)
      worst = std::max(worst, (a.targets.frames[f].position_m[k] - b.targets.frames[f].position_m[k]).norm());
  EXPECT_LT(worst, 1e-6);
}

TEST(mocap_import, UnmappedSkeletonListsWhatIsMissing) {
  Bvh b;
  std::string error;
  ASSERT_TRUE(
      parse_bvh("HIERARCHY\nROOT Pelvis\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n"
                "JOINT Thigh_L\n{\nOFFSET 1 -1 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n"
                "End Site\n{\nOFFSET 0 -1 0\n}\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0\n",
                b, error))
      << error;
  SkeletonMap map;
  EXPECT_FALSE(map_skeleton(b, map, error));
  // Thigh_L is the left hip (side suffix); everything below and beside it is missing.
  EXPECT_NE(error.find("unmapped keypoints: left_knee"), std::string::npos) << error;
  EXPECT_EQ(error.find("left_hip ("), std::string::npos) << error;
  EXPECT_NE(error.find("right_wrist"), std::string::npos) << error;
  EXPECT_NE(error.find("BVH joints: Pelvis, Thigh_L"), std::string::npos) << error;
  EXPECT_NE(error.find("mapping file"), std::string::npos) << error;
}

TEST(mocap_import, MappingFileOverridesAndReportsBadLines) {
  const Bvh dance = default_dance_bvh();
  SkeletonMap map;
  std::string error;
  ASSERT_TRUE(map_skeleton_with_file(dance, "# my rig\nleft_hand = LeftForeArm\n\n", map, error)) << error;
  EXPECT_EQ(dance.joints[map.joint[kKpLeftHand]].name, "LeftForeArm");
  EXPECT_EQ(dance.joints[map.joint[kKpLeftKnee]].name, "LeftLeg");  // the rest still by table
  EXPECT_FALSE(map_skeleton_with_file(dance, "left_hand LeftForeArm\n", map, error));
  EXPECT_NE(error.find("mapping line 1: expected 'keypoint = joint name'"), std::string::npos) << error;
  EXPECT_FALSE(map_skeleton_with_file(dance, "\nleft_paw = LeftHand\n", map, error));
  EXPECT_NE(error.find("mapping line 2: unknown keypoint 'left_paw'"), std::string::npos) << error;
  EXPECT_FALSE(map_skeleton_with_file(dance, "head = Skull\n", map, error));
  EXPECT_NE(error.find("mapping line 1: the BVH has no joint named 'Skull'"), std::string::npos) << error;
}

}  // namespace
}  // namespace kuavo::mocap
