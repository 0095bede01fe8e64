// Motion file: round trip, CSV, and every corruption the reader must refuse.
#include "tools/mocap/motion_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace kuavo::mocap {
namespace {

// Recomputes the header checksum after an edit of the header.
void put_header_crc(std::vector<std::uint8_t>& b) {
  const std::uint32_t crc = motion_header_crc(b.data());
  for (int i = 0; i < 4; ++i) b[kMotionHeaderCrcOffset + i] = static_cast<std::uint8_t>(crc >> (8 * i));
}

struct Fixture {
  model::Model s45, s42;
  std::vector<dynamics::ConfigVector> q;
  std::vector<ContactLabel> labels;
  Fixture() {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, s45);
    model::build_model(model::Variant::kS42, model::kDefaultTotalMass_kg, s42);
    for (int f = 0; f < 50; ++f) {
      // A plausible frame (the loader checks plausibility): base 0.8 m high, unit quaternion,
      // joints within the limits of both variants.
      dynamics::ConfigVector v = dynamics::ConfigVector::Constant(0.01 * f);
      v[2] = 0.8;
      v[6] = 1.0;
      v.segment<4>(3).normalize();
      for (int j = 0; j < model::kNumJoints; ++j) {
        v[7 + j] = std::clamp(v[7 + j], std::max(s45.limits.position_min_rad[j], s42.limits.position_min_rad[j]),
                              std::min(s45.limits.position_max_rad[j], s42.limits.position_max_rad[j]));
      }
      q.push_back(v);
      labels.push_back(static_cast<ContactLabel>(f % 4));
    }
  }
};

// A frame rate outside 4..500 Hz with valid checksums (kuavo_fuzz, parse:motion, seed 22:
// 1e308 Hz and 6400 Hz were accepted, a motion of zero duration) is refused as kBadRate.
TEST(mocap_motion_file, FrameRateOutsideFourTo500HzIsRefused) {
  Fixture fx;
  for (const double rate : {1e308, 6400.0, 500.1, 3.9, 0.0, -100.0}) {
    auto bytes = encode_motion(fx.s45, 100.0, fx.q, fx.labels);
    std::memcpy(&bytes[24], &rate, 8);
    put_header_crc(bytes);
    MotionHeader h;
    EXPECT_EQ(read_motion_header(bytes.data(), bytes.size(), fx.s45, h), MotionError::kBadRate) << rate;
  }
  for (const double rate : {4.0, 100.0, 500.0}) {
    auto bytes = encode_motion(fx.s45, rate, fx.q, fx.labels);
    MotionHeader h;
    EXPECT_EQ(read_motion_header(bytes.data(), bytes.size(), fx.s45, h), MotionError::kOk) << rate;
  }
}

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
  // An unknown variant byte is named as such (it said "file: s45, expected: s45").
  auto unknown = encode_motion(fx.s45, 100.0, fx.q, fx.labels);
  unknown[16] = 7;
  put_header_crc(unknown);
  ASSERT_TRUE(write_motion_file(path, unknown, error)) << error;
  EXPECT_FALSE(load_motion_file(path, fx.s45, h, q, labels, error));
  EXPECT_NE(error.find("unknown robot variant byte 7 at offset 16 (expected 0 = s45)"), std::string::npos) << error;
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
  for (MotionError e = MotionError::kOk; e <= MotionError::kTooManyFrames; e = static_cast<MotionError>(static_cast<int>(e) + 1))
    EXPECT_STRNE(to_string(e), "unknown motion error");
}

// Hostile files with valid checksums: the loader refuses them with a message naming the file,
// the frame and the joint (issue 22).
TEST(mocap_motion_file, ImplausibleFramesAreRefusedAtLoad) {
  Fixture fx;
  const std::string path = std::string(KUAVO_BINARY_DIR) + "/motion_file_test_hostile.motion";
  const auto load = [&](const std::vector<std::uint8_t>& bytes, std::string& error) {
    EXPECT_TRUE(write_motion_file(path, bytes, error)) << error;
    MotionHeader h;
    std::vector<dynamics::ConfigVector> q;
    std::vector<ContactLabel> labels;
    return load_motion_file(path, fx.s45, h, q, labels, error);
  };
  std::string error;
  ASSERT_TRUE(load(encode_motion(fx.s45, 100.0, fx.q, fx.labels), error)) << error;
  const int knee = 3;  // leg_l4_joint, limits [0, 2.5307] rad
  for (const double bad_rad : {1e308, 100.0, -0.01, 2.6}) {
    auto q = fx.q;
    q[7][7 + knee] = bad_rad;
    EXPECT_FALSE(load(encode_motion(fx.s45, 100.0, q, fx.labels), error)) << bad_rad;
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_NE(error.find("frame 7"), std::string::npos) << error;
    EXPECT_NE(error.find("leg_l4_joint"), std::string::npos) << error;
    EXPECT_NE(error.find("position limits"), std::string::npos) << error;
  }
  // Within the stated tolerance of a limit still loads.
  auto q = fx.q;
  q[7][7 + knee] = fx.s45.limits.position_max_rad[knee] + 0.5 * kMotionJointLimitTolerance_rad;
  EXPECT_TRUE(load(encode_motion(fx.s45, 100.0, q, fx.labels), error)) << error;
  // Base: not unit quaternion, under the floor, far off the stage, NaN.
  for (const auto& [index, value] : {std::pair{6, 2.0}, std::pair{2, 0.0}, std::pair{2, 5.0}, std::pair{0, 1e6},
                                     std::pair{1, std::nan("")}}) {
    q = fx.q;
    q[9][index] = value;
    EXPECT_FALSE(load(encode_motion(fx.s45, 100.0, q, fx.labels), error)) << index << " " << value;
    EXPECT_NE(error.find("frame 9"), std::string::npos) << error;
  }
  // Trailing bytes: garbage after the payload, and the file concatenated with itself.
  auto bytes = encode_motion(fx.s45, 100.0, fx.q, fx.labels);
  auto longer = bytes;
  longer.push_back(0);
  MotionHeader h;
  EXPECT_EQ(read_motion_header(longer.data(), longer.size(), fx.s45, h), MotionError::kTrailingBytes);
  EXPECT_FALSE(load(longer, error));
  EXPECT_NE(error.find("after the last frame"), std::string::npos) << error;
  longer = bytes;
  longer.insert(longer.end(), bytes.begin(), bytes.end());
  EXPECT_FALSE(load(longer, error));
  EXPECT_NE(error.find("after the last frame"), std::string::npos) << error;
  // A directory is refused, not thrown on.
  EXPECT_FALSE([&] {
    MotionHeader hd;
    std::vector<dynamics::ConfigVector> qd;
    std::vector<ContactLabel> ld;
    return load_motion_file(KUAVO_BINARY_DIR, fx.s45, hd, qd, ld, error);
  }());
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  std::remove(path.c_str());
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
