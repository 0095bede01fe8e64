// The online loader (controllers/motion/load_motion.h) on files the offline writer makes
// (tools/mocap/motion_file.h, as `kuavo retarget` writes them). Oracles: the frames written,
// the model's forward kinematics for the standing check, the format's own byte layout.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "controllers/motion/load_motion.h"
#include "tests/support/test_robot.h"
#include "tools/mocap/motion_file.h"

namespace kuavo::motion {
namespace {

using dynamics::ConfigVector;

constexpr double kRate_hz = 100.0;
constexpr int kArmJoint = 2 * model::kLegJoints;  // the first arm joint, controller order

// frames frames of the standing pose with the first arm joint swinging by 0.2 rad at 0.5 Hz.
std::vector<ConfigVector> swaying_stand(int frames) {
  std::vector<ConfigVector> q(frames, test::standing_configuration());
  for (int i = 0; i < frames; ++i) q[i][7 + kArmJoint] += 0.2 * std::sin(M_PI * i / kRate_hz);
  return q;
}

std::string write(const std::string& name, const std::vector<ConfigVector>& q,
                  std::vector<ContactLabel> labels = {}) {
  if (labels.empty()) labels.assign(q.size(), ContactLabel::kDoubleSupport);
  const std::string path = testing::TempDir() + name;
  std::string error;
  EXPECT_TRUE(mocap::write_motion_file(path, mocap::encode_motion(test::s45_robot(), kRate_hz, q, labels), error))
      << error;
  return path;
}

struct Loaded {
  bool ok = false;
  std::string error;
  std::unique_ptr<planner::MotionPlan> plan = std::make_unique<planner::MotionPlan>();
};

Loaded load(const std::string& path, MotionOptions options = {}) {
  Loaded r;
  planner::BalanceFilterReport report;
  r.ok = load_motion(path, test::s45_robot(), options, *r.plan, report, r.error);
  return r;
}

TEST(LoadMotion, HoldsExactlyWhatTheWriterWrote) {
  const std::vector<ConfigVector> q = swaying_stand(201);
  std::vector<ContactLabel> labels(q.size(), ContactLabel::kDoubleSupport);
  labels[0] = ContactLabel::kFlight;  // as the contact detector labels the built-in dance's frame 0
  labels[100] = ContactLabel::kLeftSupport;
  const Loaded r = load(write("load_sway.motion", q, labels));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.plan->frame_count, 201);
  EXPECT_EQ(r.plan->rate_hz, kRate_hz);
  for (int i = 0; i < 201; ++i) ASSERT_EQ(r.plan->q[i], q[i]) << "frame " << i;  // bit for bit
  // Frame 0 stands (its soles are on the floor), so it is double support whatever the file says.
  EXPECT_TRUE(r.plan->foot_contact[0][planner::kLeftFoot] && r.plan->foot_contact[0][planner::kRightFoot]);
  EXPECT_TRUE(r.plan->foot_contact[100][planner::kLeftFoot]);
  EXPECT_FALSE(r.plan->foot_contact[100][planner::kRightFoot]);
}

// From bytes in memory (`kuavo retarget`'s closed-loop check) the same plan as from the file,
// and the same refusal, named by the caller's `what`.
TEST(LoadMotion, FromBytesHoldsWhatTheFileHolds) {
  const std::vector<ConfigVector> q = swaying_stand(151);
  const std::vector<ContactLabel> labels(q.size(), ContactLabel::kDoubleSupport);
  const Loaded from_file = load(write("load_bytes.motion", q, labels));
  ASSERT_TRUE(from_file.ok) << from_file.error;
  const std::vector<std::uint8_t> bytes = mocap::encode_motion(test::s45_robot(), kRate_hz, q, labels);
  auto plan = std::make_unique<planner::MotionPlan>();
  planner::BalanceFilterReport report;
  std::string error;
  ASSERT_TRUE(load_motion_bytes(bytes, "in memory", test::s45_robot(), {}, *plan, report, error)) << error;
  ASSERT_EQ(plan->frame_count, from_file.plan->frame_count);
  for (int i = 0; i < plan->frame_count; ++i) {
    ASSERT_EQ(plan->q[i], from_file.plan->q[i]) << "frame " << i;
    ASSERT_EQ(plan->foot_contact[i], from_file.plan->foot_contact[i]) << "frame " << i;
  }
  std::vector<std::uint8_t> cut(bytes.begin(), bytes.end() - 1);
  EXPECT_FALSE(load_motion_bytes(cut, "in memory", test::s45_robot(), {}, *plan, report, error));
  EXPECT_EQ(error.rfind("in memory", 0), 0u) << error;
}

// The robot dances from standing: a first frame with the soles 2 cm up is refused, by the
// one loader the firmware and `kuavo simulate` share (tests/cli: both binaries refuse it).
TEST(LoadMotion, RefusesAMotionThatDoesNotStartStanding) {
  std::vector<ConfigVector> q = swaying_stand(201);
  for (auto& f : q) f[2] += 0.02;
  Loaded r = load(write("load_lifted.motion", q));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("load_lifted.motion: the first frame does not stand"), std::string::npos) << r.error;
  // 5 mm (within kStartSoleHeight_m) still stands.
  q = swaying_stand(201);
  for (auto& f : q) f[2] += 0.005;
  r = load(write("load_5mm.motion", q));
  EXPECT_TRUE(r.ok) << r.error;
}

TEST(LoadMotion, MessagesNameTheFrameAndTheJoint) {
  std::vector<ConfigVector> q = swaying_stand(201);
  q[57][7 + kArmJoint] = test::s45_robot().limits.position_max_rad[kArmJoint] + 0.01;
  Loaded r = load(write("load_limits.motion", q));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("frame 57: joint angle outside the robot's position limits: " +
                         std::string(model::joint_name(test::s45_robot(), kArmJoint))),
            std::string::npos)
      << r.error;
  r = load(testing::TempDir() + "no_such.motion");
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("no_such.motion: cannot open"), std::string::npos) << r.error;
}

// Five minutes at 100 Hz, both end frames, plus what the dynamic stage adds: the plan's
// capacity, written by the tool writer, loads through the online reader and the plan holds it
// (frames, and velocities against the sway's analytic derivative); one frame more is refused
// with the capacity named, by the file size and, for a header that lies, by the header.
TEST(LoadMotion, HoldsFiveMinutesAndRefusesOneFrameMore) {
  ASSERT_GE(planner::kMaxMotionFrames, 5 * 60 * 100 + 1);
  RecordProperty("sizeof_MotionPlan_bytes", std::to_string(sizeof(planner::MotionPlan)));
  const std::vector<ConfigVector> q = swaying_stand(planner::kMaxMotionFrames);
  Loaded r = load(write("load_capacity.motion", q));
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_EQ(r.plan->frame_count, planner::kMaxMotionFrames);
  EXPECT_GE(planner::motion_plan_duration_s(*r.plan), 300.0);
  for (int i : {0, 1, 15000, planner::kMaxMotionFrames - 1}) EXPECT_EQ(r.plan->q[i], q[i]) << "frame " << i;
  for (int i : {1, 12345, planner::kMaxMotionFrames - 2}) {
    const double expected = 0.2 * M_PI * std::cos(M_PI * i / kRate_hz);  // d/dt of 0.2 sin(π t)
    EXPECT_NEAR(planner::motion_plan_velocity(*r.plan, i)[6 + kArmJoint], expected, 1e-3) << "frame " << i;
  }

  std::vector<ConfigVector> more = q;
  more.push_back(q.back());
  r = load(write("load_capacity_plus_one.motion", more));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("more than the largest motion"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find(std::to_string(planner::kMaxMotionFrames) + " frames"), std::string::npos) << r.error;
  // The header check on its own (a file cut to its header plus what fits cannot get past it).
  const std::vector<ContactLabel> labels(more.size(), ContactLabel::kDoubleSupport);
  const std::vector<std::uint8_t> bytes = mocap::encode_motion(test::s45_robot(), kRate_hz, more, labels);
  MotionHeader header;
  std::string error;
  EXPECT_FALSE(check_motion_header(bytes, test::s45_robot(), "forged", header, error));
  EXPECT_NE(error.find("forged: more frames than the controller can hold: the header says " +
                       std::to_string(planner::kMaxMotionFrames + 1) + " frames, the capacity is " +
                       std::to_string(planner::kMaxMotionFrames)),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace kuavo::motion
