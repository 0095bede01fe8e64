// Leading reference frames (T-poses, calibration and origin poses put before the motion) are
// dropped whatever the dialect, and the motion after them is never touched: the oracle is the
// same dance imported without the prepended frames.
#include "tools/mocap/human_targets.h"

#include <gtest/gtest.h>

#include <cctype>

#include "tools/mocap/default_dance.h"

namespace kuavo::mocap {
namespace {

const std::string kMocap = std::string(KUAVO_SHARED_DIR) + "/mocap/";

bool import(const Bvh& bvh, HumanTargets& t, std::string& error) {
  model::Model robot;
  model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
  SkeletonMap map;
  return map_skeleton(bvh, map, error) && make_targets(bvh, map, robot, {}, t, error);
}

HumanTargets import(const Bvh& bvh) {
  HumanTargets t;
  std::string error;
  EXPECT_TRUE(import(bvh, t, error)) << error;
  return t;
}

std::vector<double> row_of(const Bvh& b, int frame) { return {b.row(frame), b.row(frame) + b.channel_count}; }

// The hierarchy's zero-rotation pose with the root where `like` has it: the dance skeleton's
// rest pose is a T-pose (arms along ±x).
std::vector<double> t_pose(const std::vector<double>& like) {
  std::vector<double> row(like.size(), 0.0);
  for (int c = 0; c < 3; ++c) row[c] = like[c];  // the root's position channels come first
  return row;
}

Bvh with_leading(const Bvh& b, const std::vector<std::vector<double>>& rows) {
  Bvh out = b;
  std::vector<double> motion;
  for (const auto& r : rows) motion.insert(motion.end(), r.begin(), r.end());
  motion.insert(motion.end(), b.motion.begin(), b.motion.end());
  out.motion = motion;
  out.frame_count += static_cast<int>(rows.size());
  return out;
}

// The dance's targets, unchanged by what came before it.
void expect_same_targets(const HumanTargets& a, const HumanTargets& b) {
  ASSERT_EQ(a.frames.size(), b.frames.size());
  double worst = 0.0;
  for (std::size_t f = 0; f < a.frames.size(); ++f)
    for (int k = 0; k < kNumKeypoints; ++k)
      worst = std::max(worst, (a.frames[f].position_m[k] - b.frames[f].position_m[k]).norm());
  EXPECT_LT(worst, 1e-9);
}

TEST(mocap_human_targets, LeadingTPosesAreDropped) {
  const Bvh dance = default_dance_bvh();
  const HumanTargets plain = import(dance);
  EXPECT_EQ(plain.dropped_frames, 0);
  const std::vector<double> pose = t_pose(row_of(dance, 0));
  for (int n : {1, 3, 20}) {  // one converter frame, a few, a calibration pose held 0.4 s
    SCOPED_TRACE(n);
    const HumanTargets t = import(with_leading(dance, std::vector<std::vector<double>>(n, pose)));
    EXPECT_EQ(t.dropped_frames, n);
    expect_same_targets(t, plain);
  }
}

// Perfume style: a reference pose at the origin, then the root jumps to the stage position.
// The pose itself is the dance's own first pose, so only the root jump tells.
TEST(mocap_human_targets, ReferencePoseAtTheOriginBeforeARootJumpIsDropped) {
  Bvh dance = default_dance_bvh();
  for (int f = 0; f < dance.frame_count; ++f) dance.motion[static_cast<std::size_t>(f) * dance.channel_count] += 300.0;
  const HumanTargets plain = import(dance);
  std::vector<double> at_origin = row_of(dance, 0);
  at_origin[0] = at_origin[2] = 0.0;
  const HumanTargets t = import(with_leading(dance, {at_origin}));
  EXPECT_EQ(t.dropped_frames, 1);
  expect_same_targets(t, plain);
  // A T-pose first, then the origin pose: both go.
  const HumanTargets both = import(with_leading(dance, {t_pose(at_origin), at_origin}));
  EXPECT_EQ(both.dropped_frames, 2);
  expect_same_targets(both, plain);
}

// Nothing precedes the motion: nothing is dropped. A capture that starts in a T-pose and moves
// out of it is motion too (no jump), so is a fast move at a low frame rate, and so is
// everything after the first frames that move.
TEST(mocap_human_targets, MotionIsNeverDropped) {
  const Bvh dance = default_dance_bvh();
  EXPECT_EQ(import(dance).dropped_frames, 0);
  // 1 s from the T-pose into the dance's first pose, smoothly.
  const std::vector<double> first = row_of(dance, 0), pose = t_pose(first);
  std::vector<std::vector<double>> blend;
  const int n = static_cast<int>(1.0 / dance.frame_time_s);
  for (int i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) / n, w = 0.5 - 0.5 * std::cos(M_PI * s);
    std::vector<double> r(first.size());
    for (std::size_t c = 0; c < r.size(); ++c) r[c] = (1.0 - w) * pose[c] + w * first[c];
    blend.push_back(r);
  }
  EXPECT_EQ(import(with_leading(dance, blend)).dropped_frames, 0);
  // A glitch inside the first seconds (one frame at the T-pose, 3 s in): the dance moved
  // before it, so it is motion with a glitch, not a reference.
  Bvh glitch = dance;
  const int at = static_cast<int>(3.0 / dance.frame_time_s);
  std::copy(pose.begin(), pose.end(), glitch.motion.begin() + static_cast<std::ptrdiff_t>(at) * dance.channel_count);
  EXPECT_EQ(import(glitch).dropped_frames, 0);
  // The dance sampled at 5 Hz: large steps from frame to frame, but all of them motion.
  Bvh slow = dance;
  const int every = static_cast<int>(std::lround(0.2 / dance.frame_time_s));
  slow.motion.clear();
  slow.frame_count = 0;
  for (int f = 0; f < dance.frame_count; f += every, ++slow.frame_count)
    slow.motion.insert(slow.motion.end(), dance.row(f), dance.row(f) + dance.channel_count);
  slow.frame_time_s = 0.2;
  EXPECT_EQ(import(slow).dropped_frames, 0);
}

// The shared clips, each with what its first frames hold (../shared/mocap/README.md, and the
// data): cgspeed's T-pose and Perfume's origin pose are dropped. The iClone clip's frame 0 is
// documented as a T-pose, but in this file it is a dance pose continuous with frame 1 (arms
// down, largest keypoint step 2.4 cm against 2.7 cm for the next frame), so it stays.
TEST(mocap_human_targets, SharedClipsDropTheirReferenceFrames) {
  for (const auto& [file, dropped] : {std::pair{"perfume_C_test.bvh", 1}, std::pair{"cmu_05_20_mb.bvh", 1},
                                      std::pair{"cmu_05_07_iclone_ccrig.bvh", 0}}) {
    Bvh b;
    std::string error;
    ASSERT_TRUE(load_bvh_file(kMocap + file, b, error)) << error;
    EXPECT_EQ(import(b).dropped_frames, dropped) << file;
  }
}

// A skeleton no unit makes human-sized is refused, not scaled to nothing.
TEST(mocap_human_targets, SkeletonOfNoHumanSizeIsRefused) {
  const Bvh dance = default_dance_bvh();
  for (double scale : {1e4, 1e-3}) {
    Bvh b = dance;
    for (BvhJoint& j : b.joints) j.offset *= scale;
    for (int f = 0; f < b.frame_count; ++f)
      for (int c = 0; c < 3; ++c) b.motion[static_cast<std::size_t>(f) * b.channel_count + c] *= scale;
    HumanTargets t;
    std::string error;
    EXPECT_FALSE(import(b, t, error)) << scale;
    EXPECT_NE(error.find("the skeleton fits no human size in any unit"), std::string::npos) << error;
  }
  // Every unit in use still imports: metres, millimetres (the dance is in centimetres).
  for (double scale : {0.01, 10.0}) {
    Bvh b = dance;
    for (BvhJoint& j : b.joints) j.offset *= scale;
    for (int f = 0; f < b.frame_count; ++f)
      for (int c = 0; c < 3; ++c) b.motion[static_cast<std::size_t>(f) * b.channel_count + c] *= scale;
    HumanTargets t;
    std::string error;
    EXPECT_TRUE(import(b, t, error)) << error;
  }
}

// A skeleton that names its sides from the viewer's side maps without complaint (every chain is
// consistent), but the dancer would face backward with knees bending the wrong way: refused.
TEST(mocap_human_targets, SwappedSidesAreRefused) {
  const auto swap_sides = [](Bvh b) {
    for (BvhJoint& j : b.joints) {
      std::string& n = j.name;
      if (n.rfind("Left", 0) == 0)
        n = "Right" + n.substr(4);
      else if (n.rfind("Right", 0) == 0)
        n = "Left" + n.substr(5);
      else if (n.size() > 1 && (n[0] == 'L' || n[0] == 'R') && std::isupper(static_cast<unsigned char>(n[1])))
        // cgspeed's LHipJoint, LThumb
        n[0] = n[0] == 'L' ? 'R' : 'L';
    }
    return b;
  };
  Bvh clip;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kMocap + "cmu_05_20_mb.bvh", clip, error)) << error;
  for (const Bvh& b : {default_dance_bvh(), clip}) {
    HumanTargets t;
    ASSERT_TRUE(import(b, t, error)) << error;  // as named: accepted
    const Bvh swapped = swap_sides(b);
    SkeletonMap map;
    ASSERT_TRUE(map_skeleton(swapped, map, error)) << error;  // the names alone cannot tell
    EXPECT_FALSE(import(swapped, t, error));
    EXPECT_NE(error.find("left and right look swapped"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace kuavo::mocap
