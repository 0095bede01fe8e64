// Seeded mutations of a valid motion file with both checksums recomputed (so every mutation
// reaches the frame checks), through the loader kuavo simulate and kuavo_fw share. Nothing may
// throw, and a file the loader accepts must hold only what the robot can do: every value
// finite, a unit quaternion, the base between 0.1 and 2 m high, every joint within the model's
// limits, and exactly the header and its frames (issue 22).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include "tests/support/test_robot.h"
#include "tools/mocap/motion_file.h"

namespace kuavo::mocap {
namespace {

void put_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void recompute_checksums(std::vector<std::uint8_t>& b) {
  if (b.size() < kMotionHeaderBytes) return;
  const std::size_t frames = motion_get_u32(b.data() + 32);
  const std::size_t payload = std::min(frames * kMotionRecordBytes, b.size() - kMotionHeaderBytes);
  put_u32(b, kMotionPayloadCrcOffset, crc32(b.data() + kMotionHeaderBytes, payload));
  put_u32(b, kMotionHeaderCrcOffset, motion_header_crc(b.data()));
}

TEST(mocap_motion_fuzz, AcceptedFilesHoldOnlyWhatTheRobotCanDo) {
  model::Model robot;
  ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot), model::ModelError::kOk);
  const std::vector<dynamics::ConfigVector> q0(20, test::standing_configuration());
  const std::vector<ContactLabel> labels(q0.size(), ContactLabel::kDoubleSupport);
  const std::vector<std::uint8_t> good = encode_motion(robot, 100.0, q0, labels);
  const std::string path = std::string(KUAVO_BINARY_DIR) + "/motion_fuzz_test.motion";
  std::mt19937_64 rng(22);  // seeded: the same cases every run
  const double specials[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                             1e308, -1e308, 100.0, -100.0, 0.0, 2.6, -0.01, 1e-320};
  int accepted = 0, refused = 0;
  constexpr int kCases = 3000;
  for (int n = 0; n < kCases; ++n) {
    std::vector<std::uint8_t> b = good;
    const std::size_t frame = rng() % q0.size(), value = rng() % model::kNq;
    const std::size_t at = kMotionHeaderBytes + frame * kMotionRecordBytes + 8 * value;
    switch (rng() % 5) {
      case 0: {  // a special value
        const double v = specials[rng() % std::size(specials)];
        std::memcpy(&b[at], &v, 8);
        break;
      }
      case 1: {  // a small change (stays plausible or just crosses a limit)
        double v;
        std::memcpy(&v, &b[at], 8);
        v += std::uniform_real_distribution<double>(-3.0, 3.0)(rng);
        std::memcpy(&b[at], &v, 8);
        break;
      }
      case 2:  // a random byte anywhere in the frames
        b[kMotionHeaderBytes + rng() % (b.size() - kMotionHeaderBytes)] = static_cast<std::uint8_t>(rng());
        break;
      case 3:  // bytes appended (garbage, or the file once more)
        if (rng() % 2) b.insert(b.end(), good.begin(), good.end());
        else b.resize(b.size() + 1 + rng() % 300, static_cast<std::uint8_t>(rng()));
        break;
      default:  // a frame count that lies
        put_u32(b, 32, static_cast<std::uint32_t>(rng() % 2 ? rng() % 40 : rng()));
        break;
    }
    recompute_checksums(b);
    std::string error;
    ASSERT_TRUE(write_motion_file(path, b, error)) << error;
    MotionHeader h;
    std::vector<dynamics::ConfigVector> q;
    std::vector<ContactLabel> l;
    bool ok = false;
    ASSERT_NO_THROW(ok = load_motion_file(path, robot, h, q, l, error)) << "case " << n;
    if (!ok) {
      ++refused;
      EXPECT_NE(error.find(path), std::string::npos) << error;
      continue;
    }
    ++accepted;
    ASSERT_EQ(b.size(), kMotionHeaderBytes + q.size() * kMotionRecordBytes) << "case " << n;
    for (std::size_t f = 0; f < q.size(); ++f) {
      ASSERT_TRUE(q[f].allFinite()) << "case " << n << " frame " << f;
      ASSERT_NEAR(q[f].segment<4>(3).norm(), 1.0, 1e-6) << "case " << n << " frame " << f;
      ASSERT_TRUE(q[f][2] >= 0.1 && q[f][2] <= 2.0) << "case " << n << " frame " << f;
      for (int j = 0; j < model::kNumJoints; ++j) {
        ASSERT_GE(q[f][7 + j], robot.limits.position_min_rad[j] - 1e-6) << "case " << n << " frame " << f << " joint " << j;
        ASSERT_LE(q[f][7 + j], robot.limits.position_max_rad[j] + 1e-6) << "case " << n << " frame " << f << " joint " << j;
      }
    }
  }
  // Both outcomes occur: the mutations reach the checks and do not all break the file.
  EXPECT_GT(accepted, kCases / 20);
  EXPECT_GT(refused, kCases / 2);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace kuavo::mocap
