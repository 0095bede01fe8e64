// IMU cycle over a non-blocking pipe standing in for the serial port.
#include <gtest/gtest.h>

#include <cstring>
#include <fcntl.h>
#include <unistd.h>
#include <vector>

#include "drivers/cycle/imu_io.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers {
namespace {

std::vector<std::uint8_t> mtdata2(float w, float x, float gyro_z) {
  std::vector<std::uint8_t> p{0xFA, 0xFF, 0x36, 0};
  auto f32 = [&](float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    for (int s = 24; s >= 0; s -= 8) p.push_back(static_cast<std::uint8_t>(u >> s));
  };
  auto header = [&](std::uint8_t hi, std::uint8_t lo, std::uint8_t size) {
    p.push_back(hi);
    p.push_back(lo);
    p.push_back(size);
  };
  header(0x20, 0x10, 16);
  for (float v : {w, x, 0.0f, 0.0f}) f32(v);
  header(0x80, 0x20, 12);
  for (float v : {0.0f, 0.0f, gyro_z}) f32(v);
  header(0x40, 0x20, 12);
  for (float v : {0.0f, 0.0f, 9.81f}) f32(v);
  p[3] = static_cast<std::uint8_t>(p.size() - 4);
  unsigned sum = 0;
  for (std::size_t i = 1; i < p.size(); ++i) sum += p[i];
  p.push_back(static_cast<std::uint8_t>(-static_cast<int>(sum) & 0xFF));
  return p;
}

class ImuIo : public ::testing::Test {
 protected:
  int fd[2]{-1, -1};
  mti::Parser parser;
  hal::ImuSample sample;
  void SetUp() override { ASSERT_EQ(pipe2(fd, O_NONBLOCK), 0); }
  void TearDown() override {
    for (int f : fd)
      if (f >= 0) close(f);
  }
  void write_bytes(const std::vector<std::uint8_t>& b) {
    ASSERT_EQ(write(fd[1], b.data(), b.size()), static_cast<ssize_t>(b.size()));
  }
};

TEST_F(ImuIo, KeepsTheNewestPacketOfTheCycle) {
  write_bytes(mtdata2(1.0f, 0.0f, 0.1f));
  write_bytes(mtdata2(0.0f, 1.0f, 0.2f));
  const ImuReceiveReport r = imu_receive_rt(fd[0], parser, 777, sample);
  EXPECT_EQ(r.packets, 2);
  ASSERT_TRUE(r.updated);
  EXPECT_TRUE(sample.valid);
  EXPECT_EQ(sample.stamp_ns, 777);
  EXPECT_DOUBLE_EQ(sample.orientation_xyzw[0], 1.0);
  EXPECT_DOUBLE_EQ(sample.angular_rate_rad_s[2], static_cast<double>(0.2f));
}

TEST_F(ImuIo, NothingNewLeavesTheSampleAlone) {
  write_bytes(mtdata2(1.0f, 0.0f, 0.1f));
  imu_receive_rt(fd[0], parser, 1, sample);
  const ImuReceiveReport quiet = imu_receive_rt(fd[0], parser, 2, sample);
  EXPECT_FALSE(quiet.updated);
  EXPECT_EQ(sample.stamp_ns, 1);  // the estimator sees its age grow
  std::vector<std::uint8_t> bad = mtdata2(1.0f, 0.0f, 0.3f);
  bad[10] ^= 0x01;  // checksum no longer matches
  write_bytes(bad);
  EXPECT_FALSE(imu_receive_rt(fd[0], parser, 3, sample).updated);
  EXPECT_EQ(parser.stats.checksum_errors, 1u);
}

TEST_F(ImuIo, PacketSplitAcrossCycles) {
  const std::vector<std::uint8_t> p = mtdata2(1.0f, 0.0f, 0.1f);
  write_bytes({p.begin(), p.begin() + 20});
  EXPECT_FALSE(imu_receive_rt(fd[0], parser, 1, sample).updated);
  write_bytes({p.begin() + 20, p.end()});
  EXPECT_TRUE(imu_receive_rt(fd[0], parser, 2, sample).updated);
}

TEST_F(ImuIo, UnpluggedDeviceIsReported) {
  close(fd[1]);
  fd[1] = -1;
  EXPECT_TRUE(imu_receive_rt(fd[0], parser, 1, sample).device_lost);
}

TEST_F(ImuIo, CycleDoesNotAllocate) {
  write_bytes(mtdata2(1.0f, 0.0f, 0.1f));
  test::AllocTrap trap;
  imu_receive_rt(fd[0], parser, 1, sample);
  EXPECT_EQ(trap.count(), 0u);
}

}  // namespace
}  // namespace kuavo::drivers
