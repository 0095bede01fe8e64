// Xsens MTi: hand-built MTData2 packets (layout and checksum from the Xsens
// low-level protocol), any chunking, garbage and bad-checksum resync, extended
// length, float64 items, the HAL conversion, and the missing-device error.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "drivers/imu/mti_parser.h"
#include "drivers/imu/serial_port.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers::mti {
namespace {

using Bytes = std::vector<std::uint8_t>;

void put_be32(Bytes& b, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<std::uint8_t>(v >> s));
}
void put_f32(Bytes& b, float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  put_be32(b, u);
}
void put_f64(Bytes& b, double d) {
  std::uint64_t u;
  std::memcpy(&u, &d, 8);
  put_be32(b, static_cast<std::uint32_t>(u >> 32));
  put_be32(b, static_cast<std::uint32_t>(u));
}
void item_header(Bytes& b, std::uint16_t xdi, std::uint8_t size) {
  b.push_back(static_cast<std::uint8_t>(xdi >> 8));
  b.push_back(static_cast<std::uint8_t>(xdi));
  b.push_back(size);
}

// FA FF MID LEN data CS with CS = -(BID + MID + LEN... + data) mod 256.
Bytes packet(std::uint8_t mid, const Bytes& payload) {
  Bytes b{0xFA, 0xFF, mid};
  if (payload.size() < 0xFF) {
    b.push_back(static_cast<std::uint8_t>(payload.size()));
  } else {
    b.push_back(0xFF);
    b.push_back(static_cast<std::uint8_t>(payload.size() >> 8));
    b.push_back(static_cast<std::uint8_t>(payload.size()));
  }
  b.insert(b.end(), payload.begin(), payload.end());
  unsigned sum = 0;
  for (std::size_t i = 1; i < b.size(); ++i) sum += b[i];
  b.push_back(static_cast<std::uint8_t>(-static_cast<int>(sum) & 0xFF));
  return b;
}

Bytes standard_payload(std::uint16_t counter = 42) {
  Bytes p;
  item_header(p, 0x1020, 2);  // packet counter
  p.push_back(static_cast<std::uint8_t>(counter >> 8));
  p.push_back(static_cast<std::uint8_t>(counter));
  item_header(p, 0x1060, 4);  // sample time fine
  put_be32(p, 123456);
  item_header(p, 0x2010, 16);  // quaternion float32, ENU: w x y z
  for (float f : {0.5f, 0.5f, -0.5f, 0.5f}) put_f32(p, f);
  item_header(p, 0x8020, 12);  // rate of turn
  for (float f : {0.1f, -0.2f, 0.3f}) put_f32(p, f);
  item_header(p, 0x4020, 12);  // acceleration
  for (float f : {0.0f, 0.25f, 9.81f}) put_f32(p, f);
  return p;
}

// Feeds everything; collects every decoded packet.
std::vector<MtData2> feed(Parser& p, const Bytes& bytes, std::size_t chunk) {
  std::vector<MtData2> out;
  for (std::size_t off = 0; off < bytes.size(); off += chunk) {
    const std::size_t n = std::min(chunk, bytes.size() - off);
    std::size_t pos = 0;
    while (pos < n) {
      std::size_t used = 0;
      MtData2 d;
      if (parse_rt(p, bytes.data() + off + pos, n - pos, used, d) == DriverError::kOk) out.push_back(d);
      pos += used;
    }
  }
  return out;
}

TEST(MtiParser, DecodesHandBuiltPacketInAnyChunking) {
  const Bytes pk = packet(0x36, standard_payload());
  for (std::size_t chunk : {std::size_t{1}, std::size_t{3}, std::size_t{7}, pk.size()}) {
    Parser p;
    const auto got = feed(p, pk, chunk);
    ASSERT_EQ(got.size(), 1u) << "chunk " << chunk;
    const MtData2& d = got[0];
    EXPECT_TRUE(d.has_quaternion && d.has_rate_of_turn && d.has_acceleration);
    EXPECT_EQ(d.packet_counter, 42);
    EXPECT_EQ(d.sample_time_fine, 123456u);
    EXPECT_DOUBLE_EQ(d.quaternion_wxyz[2], -0.5);
    EXPECT_DOUBLE_EQ(d.rate_of_turn_rad_s[1], static_cast<double>(-0.2f));
    EXPECT_DOUBLE_EQ(d.acceleration_m_s2[2], static_cast<double>(9.81f));
    EXPECT_EQ(p.stats.packets, 1u);
    EXPECT_EQ(p.stats.checksum_errors, 0u);
  }
}

TEST(MtiParser, SkipsGarbageAndResyncsAfterBadChecksum) {
  Bytes stream{0x00, 0x13, 0xFA, 0x00, 0xFA};  // garbage incl. a false preamble
  Bytes bad = packet(0x36, standard_payload(1));
  bad.back() ^= 0x5A;  // corrupt the checksum
  stream.insert(stream.end(), bad.begin(), bad.end());
  const Bytes good = packet(0x36, standard_payload(2));
  stream.insert(stream.end(), good.begin(), good.end());
  Parser p;
  const auto got = feed(p, stream, 5);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].packet_counter, 2);
  EXPECT_EQ(p.stats.checksum_errors, 1u);
  EXPECT_GT(p.stats.skipped_bytes, 0u);
}

TEST(MtiParser, FindsAPacketThatStartsInsideARejectedOne) {
  // A truncated packet head claims 60 bytes; the real packet starts right after
  // its 4-byte header, so it lies inside the bytes the bad claim swallowed.
  Bytes stream{0xFA, 0xFF, 0x36, 60};
  const Bytes good = packet(0x36, standard_payload(7));
  stream.insert(stream.end(), good.begin(), good.end());
  for (int i = 0; i < 40; ++i) stream.push_back(0x00);  // trailing noise completes the bad claim
  Parser p;
  const auto got = feed(p, stream, 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].packet_counter, 7);
  EXPECT_EQ(p.stats.checksum_errors, 1u);
}

TEST(MtiParser, ExtendedLengthFloat64AndOtherMessages) {
  Bytes payload;
  item_header(payload, 0x2013, 32);  // quaternion, float64
  for (double v : {1.0, 0.0, 0.0, 0.0}) put_f64(payload, v);
  item_header(payload, 0x8023, 24);
  for (double v : {1e-3, 2e-3, 3e-3}) put_f64(payload, v);
  item_header(payload, 0x4023, 24);
  for (double v : {0.0, 0.0, 9.80665}) put_f64(payload, v);
  item_header(payload, 0xE020, 200);  // unknown (status-like) item, skipped
  payload.insert(payload.end(), 200, 0xAB);
  ASSERT_GE(payload.size(), 255u);  // forces the extended length form
  Bytes stream = packet(0x3E, {});  // WakeUp: valid, not MTData2
  const Bytes pk = packet(0x36, payload);
  stream.insert(stream.end(), pk.begin(), pk.end());
  Parser p;
  const auto got = feed(p, stream, 16);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_DOUBLE_EQ(got[0].rate_of_turn_rad_s[2], 3e-3);
  EXPECT_DOUBLE_EQ(got[0].acceleration_m_s2[2], 9.80665);
  EXPECT_EQ(p.stats.other_messages, 1u);
}

TEST(MtiParser, ImpossibleLengthAndBadItemsAreRejected) {
  Parser p;
  const Bytes too_long{0xFA, 0xFF, 0x36, 0xFF, 0x10, 0x00};  // 4096 bytes
  feed(p, too_long, 1);
  EXPECT_EQ(p.stats.length_errors, 1u);
  Bytes payload;
  item_header(payload, 0x2010, 12);  // quaternion with 3 floats: wrong size
  payload.insert(payload.end(), 12, 0);
  const auto got = feed(p, packet(0x36, payload), 4);
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(p.stats.bad_items, 1u);
  MtData2 d;
  const std::uint8_t overrun[] = {0x20, 0x10, 0x10, 0x00};  // size 16, 1 byte present
  EXPECT_EQ(decode_mtdata2_rt(overrun, sizeof(overrun), d), DriverError::kMtiBadItem);
}

TEST(MtiParser, ToImuSampleReordersAndValidates) {
  Parser p;
  const auto got = feed(p, packet(0x36, standard_payload()), 64);
  ASSERT_EQ(got.size(), 1u);
  hal::ImuSample s;
  ASSERT_EQ(to_imu_sample(got[0], 777, s), DriverError::kOk);
  EXPECT_TRUE(s.valid);
  EXPECT_EQ(s.stamp_ns, 777);
  // w x y z = 0.5 0.5 -0.5 0.5  ->  x y z w
  EXPECT_DOUBLE_EQ(s.orientation_xyzw[0], 0.5);
  EXPECT_DOUBLE_EQ(s.orientation_xyzw[1], -0.5);
  EXPECT_DOUBLE_EQ(s.orientation_xyzw[3], 0.5);
  MtData2 partial = got[0];
  partial.has_acceleration = false;
  EXPECT_EQ(to_imu_sample(partial, 1, s), DriverError::kMtiIncomplete);
  EXPECT_FALSE(s.valid);
  MtData2 ned = got[0];
  ned.orientation_frame_bits = 0x4;
  EXPECT_EQ(to_imu_sample(ned, 1, s), DriverError::kBadConfig);
  MtData2 bad = got[0];
  bad.quaternion_wxyz = {0.1, 0.0, 0.0, 0.0};
  EXPECT_EQ(to_imu_sample(bad, 1, s), DriverError::kMtiBadItem);
}

TEST(MtiParser, ParsingDoesNotAllocate) {
  const Bytes pk = packet(0x36, standard_payload());
  Parser p;
  MtData2 d;
  hal::ImuSample s;
  test::AllocTrap trap;
  int packets = 0;
  for (int rep = 0; rep < 10; ++rep) {
    std::size_t pos = 0;
    while (pos < pk.size()) {
      std::size_t used = 0;
      if (parse_rt(p, pk.data() + pos, pk.size() - pos, used, d) == DriverError::kOk) {
        ++packets;
        (void)to_imu_sample(d, 0, s);
      }
      pos += used;
    }
  }
  EXPECT_EQ(trap.count(), 0u);
  EXPECT_EQ(packets, 10);
}

TEST(SerialPort, MissingDeviceGivesClearError) {
  int fd = 123;
  std::string msg;
  EXPECT_EQ(open_serial_port("/dev/kuavo_no_such_tty", kMtiDefaultBaud, fd, msg), DriverError::kDeviceMissing);
  EXPECT_EQ(fd, -1);
  EXPECT_NE(msg.find("/dev/kuavo_no_such_tty"), std::string::npos) << msg;
  EXPECT_NE(msg.find("No such file or directory"), std::string::npos) << msg;
  EXPECT_NE(msg.find("IMU not connected"), std::string::npos) << msg;
  EXPECT_EQ(open_serial_port("/dev/null", 12345, fd, msg), DriverError::kBadConfig);
  // /dev/null exists but is no tty.
  EXPECT_EQ(open_serial_port("/dev/null", kMtiDefaultBaud, fd, msg), DriverError::kSetupFailed);
  EXPECT_NE(msg.find("not a serial port"), std::string::npos) << msg;
}

TEST(SerialPort, DefaultImuDeviceAbsentHere) {
  int fd = -1;
  std::string msg;
  const DriverError e = open_serial_port("/dev/ttyUSB0", kMtiDefaultBaud, fd, msg);
  if (e == DriverError::kOk) {
    GTEST_SKIP() << "/dev/ttyUSB0 exists on this machine";
  }
  EXPECT_EQ(e, DriverError::kDeviceMissing) << msg;
  EXPECT_NE(msg.find("/dev/ttyUSB0: open failed"), std::string::npos) << msg;
}

}  // namespace
}  // namespace kuavo::drivers::mti
