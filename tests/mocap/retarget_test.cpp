// Retargeting: acceptance on the three shared clips and the built-in dance, the oracle
// (a robot-shaped BVH retargets back to its own joint angles), determinism and no
// allocation per frame.
#include "tools/mocap/retarget.h"

#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "tests/support/alloc_trap.h"
#include "tools/mocap/default_dance.h"
#include "tools/mocap/robot_bvh.h"

namespace kuavo::mocap {
namespace {

const std::string kMocap = std::string(KUAVO_SHARED_DIR) + "/mocap/";

std::unique_ptr<model::Model> make_robot(model::Variant v = model::Variant::kS45) {
  auto robot = std::make_unique<model::Model>();
  EXPECT_EQ(model::build_model(v, model::kDefaultTotalMass_kg, *robot), model::ModelError::kOk);
  return robot;
}

HumanTargets targets_of(const Bvh& bvh, const model::Model& robot, const ImportOptions& options = {}) {
  SkeletonMap map;
  std::string error;
  EXPECT_TRUE(map_skeleton(bvh, map, error)) << error;
  HumanTargets t;
  EXPECT_TRUE(make_targets(bvh, map, robot, options, t, error)) << error;
  return t;
}

void expect_acceptance(const std::string& name, const Bvh& bvh, model::Variant variant, double duration_s) {
  SCOPED_TRACE(name);
  const auto robot = make_robot(variant);
  const HumanTargets t = targets_of(bvh, *robot);
  RetargetResult r;
  retarget_motion(*robot, t, detect_contacts(t, *robot), {}, r);
  const RetargetReport& rep = r.report;
  EXPECT_NEAR(rep.duration_s, duration_s, 0.03);
  EXPECT_EQ(rep.frames, static_cast<int>(r.q.size()));
  EXPECT_EQ(rep.joint_limit_violations, 0);
  EXPECT_EQ(rep.velocity_limit_violations, 0);
  EXPECT_LT(rep.foot_slide_max_m_s, 0.01);  // issue 5: stance-foot slide below 1 cm/s
  EXPECT_LE(rep.penetration_max_m, 0.005);  // no penetration beyond 5 mm
  EXPECT_LE(rep.float_max_m, 0.005);        // stance feet on the floor
  EXPECT_GT(rep.contact_phases, 2);         // the dancer does step
  EXPECT_LT(rep.keypoint_error_mean_m, 0.1);
  for (const ConfigVector& q : r.q) ASSERT_TRUE(q.allFinite());
}

TEST(mocap_retarget, PerfumeClip) {
  Bvh b;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kMocap + "perfume_C_test.bvh", b, error)) << error;
  expect_acceptance("perfume", b, model::Variant::kS45, 32.45);  // 1300 frames minus the reference frame
}

TEST(mocap_retarget, CmuMotionBuilderClip) {
  Bvh b;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kMocap + "cmu_05_20_mb.bvh", b, error)) << error;
  expect_acceptance("cmu 05_20", b, model::Variant::kS45, 1094 * 0.0083333);
}

TEST(mocap_retarget, IcloneCcBaseClip) {
  Bvh b;
  std::string error;
  ASSERT_TRUE(load_bvh_file(kMocap + "cmu_05_07_iclone_ccrig.bvh", b, error)) << error;
  expect_acceptance("cc_base 05_07", b, model::Variant::kS45, 595 * 0.016667);
}

TEST(mocap_retarget, BuiltInDanceBothVariants) {
  const Bvh dance = default_dance_bvh();
  expect_acceptance("dance s45", dance, model::Variant::kS45, kDefaultDanceDuration_s);
  expect_acceptance("dance s42", dance, model::Variant::kS42, kDefaultDanceDuration_s);
}

// Oracle: the BVH skeleton is the robot's own tree, written in centimetres and Y-up,
// driven by known joint angles. Import (units, axes, scaling, resampling) and retargeting
// must hand those angles back to solver tolerance.
TEST(mocap_retarget, OracleRobotSkeletonRecoversItsJointAngles) {
  const auto robot = make_robot();
  constexpr int kFrames = 240;
  const std::vector<ConfigVector> truth = robot_test_motion(*robot, kFrames, 100.0);
  Bvh bvh;
  std::string error;
  ASSERT_TRUE(parse_bvh(write_bvh(robot_bvh(*robot, truth, 0.01, 100.0)), bvh, error)) << error;
  SkeletonMap map;
  ASSERT_TRUE(map_skeleton(bvh, map, error)) << error;
  EXPECT_EQ(map.family, "robot");
  HumanTargets t;
  ImportOptions import;
  import.heading_window_s = 0.0;    // heading from frame 0 alone, where the base yaw is 0
  import.feet_above_floor = false;  // the robot floats: no floor to keep the feet above
  ASSERT_TRUE(make_targets(bvh, map, *robot, import, t, error)) << error;
  EXPECT_EQ(t.dropped_frames, 0);
  EXPECT_EQ(t.unit, "cm");
  EXPECT_NEAR(t.root_scale, 0.01, 1e-12);
  ASSERT_EQ(t.frames.size(), truth.size());
  RetargetOptions options;
  options.pin_stance_feet = false;  // the robot floats: no contacts
  options.ground_rows = false;      // nor floor handling
  options.iterations = 8;
  options.first_frame_iterations = 200;
  options.weights.joint_smoothness = 0.0;  // no bias toward the previous frame
  options.weights.joint_acceleration = 0.0;
  RetargetResult r;
  retarget_motion(*robot, t, std::vector<ContactLabel>(t.frames.size(), ContactLabel::kFlight), options, r);
  double worst = 0.0;
  int worst_joint = -1;
  for (std::size_t f = 0; f < truth.size(); ++f) {
    for (int j = 0; j < model::kNumJoints; ++j) {
      const double e = std::abs(r.q[f][7 + j] - truth[f][7 + j]);
      if (e > worst) worst = e, worst_joint = j;
    }
    // Base orientation: the import turns the dancer to face +x at the start, which for this
    // motion (yaw 0 at t = 0) is the identity.
    const Eigen::Quaterniond a(r.q[f][6], r.q[f][3], r.q[f][4], r.q[f][5]);
    const Eigen::Quaterniond b(truth[f][6], truth[f][3], truth[f][4], truth[f][5]);
    ASSERT_LT(a.angularDistance(b), 1e-6) << "frame " << f;
  }
  EXPECT_LT(worst, 1e-6) << "worst joint " << (worst_joint >= 0 ? model::joint_name(*robot, worst_joint) : "-");
  EXPECT_LT(r.report.keypoint_error_max_m, 1e-7);
}

// The whole pipeline on mutated dances (wild values in the motion rows, swapped joint
// names): every stage either refuses with a message or produces a finite, in-limit motion.
TEST(mocap_retarget, MutatedDancesNeverYieldNonFiniteMotion) {
  const auto robot = make_robot();
  Bvh base = default_dance_bvh();
  base.frame_count = 40;
  base.motion.resize(static_cast<std::size_t>(base.frame_count) * base.channel_count);
  std::mt19937 rng(5u);
  std::uniform_real_distribution<double> wild(-1e4, 1e4);
  int refused = 0, produced = 0;
  for (int iter = 0; iter < 40; ++iter) {
    Bvh b = base;
    const int edits = 1 + static_cast<int>(rng() % 20);
    for (int e = 0; e < edits; ++e) b.motion[rng() % b.motion.size()] = wild(rng);
    if (iter % 4 == 0) std::swap(b.joints[1].name, b.joints[6].name);           // left/right hips swapped
    if (iter % 5 == 0) b.joints[1].offset = b.joints[6].offset = Vec3::Zero();  // hips on one point
    SkeletonMap map;
    HumanTargets t;
    std::string error;
    if (!map_skeleton(b, map, error) || !make_targets(b, map, *robot, {}, t, error)) {
      EXPECT_FALSE(error.empty());
      ++refused;
      continue;
    }
    RetargetResult r;
    retarget_motion(*robot, t, detect_contacts(t, *robot), {}, r);
    for (const ConfigVector& q : r.q) ASSERT_TRUE(q.allFinite()) << "iteration " << iter;
    EXPECT_EQ(r.report.joint_limit_violations, 0);
    EXPECT_EQ(r.report.velocity_limit_violations, 0);
    ++produced;
  }
  EXPECT_GT(produced, 0);
  EXPECT_GT(refused, 0);
}

TEST(mocap_retarget, DeterministicAndAllocationFreePerFrame) {
  const auto robot = make_robot();
  const HumanTargets t = targets_of(default_dance_bvh(), *robot);
  const auto labels = detect_contacts(t, *robot);
  const auto pins = plan_foot_pins(t, labels, *robot, t.rate_hz);
  Retargeter a(*robot, {}, t.rate_hz), b(*robot, {}, t.rate_hz);
  for (std::size_t i = 0; i < 400; ++i) {
    a.step(t.frames[i], t.present, pins[i]);
    if (i < 5) {
      b.step(t.frames[i], t.present, pins[i]);
      continue;
    }
    test::AllocTrap trap;
    b.step(t.frames[i], t.present, pins[i]);
    ASSERT_EQ(trap.count(), 0u) << "frame " << i << " allocated " << trap.first_size_bytes() << " bytes";
    ASSERT_EQ(a.q(), b.q()) << "frame " << i;
  }
}

}  // namespace
}  // namespace kuavo::mocap
