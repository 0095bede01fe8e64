// Motion file: round trip, CSV, and every corruption the reader must refuse.
#include "tools/mocap/motion_file.h"

#include <gtest/gtest.h>

#include <cstdio>

namespace kuavo::mocap {
namespace {

struct Fixture {
  model::Model s45, s42;
  std::vector<dynamics::ConfigVector> q;
  std::vector<ContactLabel> labels;
  Fixture() {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, s45);
    model::build_model(model::Variant::kS42, model::kDefaultTotalMass_kg, s42);
    for (int f = 0; f < 50; ++f) {
      dynamics::ConfigVector v = dynamics::ConfigVector::Constant(0.01 * f);
      v[6] = 1.0;
      q.push_back(v);
      labels.push_back(static_cast<ContactLabel>(f % 4));
    }
  }
};

TEST(mocap_motion_file, RoundTripIsExact) {
  Fixture fx;
  const auto bytes = encode_motion(fx.s45, 100.0, fx.q, fx.labels);
  EXPECT_EQ(bytes.size(), kMotionHeaderBytes + fx.q.size() * kMotionRecordBytes);
  MotionHeader h;
  ASSERT_EQ(read_motion_header(bytes.data(), bytes.size(), fx.s45, h), MotionError::kOk);
  EXPECT_EQ(h.frame_count, fx.q.size());
  EXPECT_EQ(h.rate_hz, 100.0);
  for (std::uint32_t i = 0; i < h.frame_count; ++i) {
    dynamics::ConfigVector q;
    ContactLabel l;
    ASSERT_EQ(read_motion_frame(bytes.data(), bytes.size(), i, q, l), MotionError::kOk);
    EXPECT_EQ(q, fx.q[i]);
    EXPECT_EQ(l, fx.labels[i]);
  }
  const std::string path = std::string(KUAVO_BINARY_DIR) + "/motion_file_test.motion";
  std::string error;
  ASSERT_TRUE(write_motion_file(path, bytes, error)) << error;
  std::vector<dynamics::ConfigVector> q;
  std::vector<ContactLabel> labels;
  ASSERT_TRUE(load_motion_file(path, fx.s45, h, q, labels, error)) << error;
  EXPECT_EQ(q, fx.q);
  EXPECT_EQ(labels, fx.labels);
  // The wrong variant is named in the message.
  EXPECT_FALSE(load_motion_file(path, fx.s42, h, q, labels, error));
  EXPECT_NE(error.find("other robot variant (file: s45, expected: s42)"), std::string::npos) << error;
  std::remove(path.c_str());
}

TEST(mocap_motion_file, CorruptionIsDetected) {
  Fixture fx;
  const auto good = encode_motion(fx.s45, 100.0, fx.q, fx.labels);
  MotionHeader h;
  EXPECT_EQ(read_motion_header(good.data(), good.size(), fx.s42, h), MotionError::kWrongVariant);
  EXPECT_EQ(read_motion_header(good.data(), good.size() - 1, fx.s45, h), MotionError::kTruncated);
  EXPECT_EQ(read_motion_header(good.data(), 10, fx.s45, h), MotionError::kTooShort);
  EXPECT_EQ(read_motion_header(nullptr, 0, fx.s45, h), MotionError::kTooShort);
  auto bad = good;
  bad[0] = 'X';
  EXPECT_EQ(read_motion_header(bad.data(), bad.size(), fx.s45, h), MotionError::kBadMagic);
  bad = good;
  bad[8] = 2;
  EXPECT_EQ(read_motion_header(bad.data(), bad.size(), fx.s45, h), MotionError::kBadVersion);
  bad = good;
  bad[100] ^= 1;  // a joint name byte
  EXPECT_EQ(read_motion_header(bad.data(), bad.size(), fx.s45, h), MotionError::kBadHeaderChecksum);
  bad = good;
  bad[kMotionHeaderBytes + 5 * kMotionRecordBytes + 17] ^= 0x40;  // one bit of one q value
  EXPECT_EQ(read_motion_header(bad.data(), bad.size(), fx.s45, h), MotionError::kBadPayloadChecksum);
  // Every single-byte flip anywhere is caught by one check or another.
  for (std::size_t i = 0; i < good.size(); i += 7) {
    bad = good;
    bad[i] ^= 0x01;
    EXPECT_NE(read_motion_header(bad.data(), bad.size(), fx.s45, h), MotionError::kOk) << "byte " << i;
  }
  for (MotionError e = MotionError::kOk; e <= MotionError::kIo; e = static_cast<MotionError>(static_cast<int>(e) + 1))
    EXPECT_STRNE(to_string(e), "unknown motion error");
}

TEST(mocap_motion_file, Crc32MatchesTheStandardCheckValue) {
  const char* text = "123456789";
  EXPECT_EQ(crc32(reinterpret_cast<const std::uint8_t*>(text), 9), 0xCBF43926u);
}

TEST(mocap_motion_file, CsvHasHeaderAndOneRowPerFrame) {
  Fixture fx;
  const std::string csv = motion_csv(fx.s45, 100.0, fx.q, fx.labels);
  EXPECT_EQ(csv.rfind("t_s,base_x_m,base_y_m,base_z_m,base_qx,base_qy,base_qz,base_qw,leg_l1_joint_rad", 0), 0u);
  EXPECT_EQ(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')), fx.q.size() + 1);
  EXPECT_NE(csv.find(",double\n"), std::string::npos);
}

}  // namespace
}  // namespace kuavo::mocap
