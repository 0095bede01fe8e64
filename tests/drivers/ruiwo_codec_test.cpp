// Ruiwo codec: golden frames computed from the protocol description
// (FACTS.md §5.2: u = trunc((x - min) / (max - min) * (2^n - 1)), MIT nibble
// layout), clamping rules, and round trips within one quantisation step.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "drivers/ruiwo/ruiwo_codec.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers::ruiwo {
namespace {

// Independent of the encoder: the spec formula written out in the test.
unsigned spec_uint(double x, double lo, double hi, int bits) {
  return static_cast<unsigned>(std::floor((x - lo) / (hi - lo) * ((1 << bits) - 1)));
}

TEST(RuiwoCodec, GoldenPtmFrameFromHandComputedBytes) {
  // p = 1 rad: (13.5/25)*65535 = 35388.9 -> 0x8A3C;  v = -2: (8/20)*4095 = 1638 -> 0x666
  // kp = 30: 30/250*4095 = 491.4 -> 0x1EB;  kd = 2: 2/50*4095 = 163.8 -> 0x0A3
  // t = 5: 55/100*4095 = 2252.25 -> 0x8CC
  // bytes: [p_hi p_lo] [v_hi8] [v_lo4|kp_hi4] [kp_lo8] [kd_hi8] [kd_lo4|t_hi4] [t_lo8]
  const std::uint8_t expected[8] = {0x8A, 0x3C, 0x66, 0x61, 0xEB, 0x0A, 0x38, 0xCC};
  can_frame f;
  const std::uint8_t flags = encode_ptm_rt(0x05, PtmCommand{1.0, -2.0, 30.0, 2.0, 5.0}, f);
  EXPECT_EQ(flags, 0);
  EXPECT_EQ(f.can_id, 0x05u);
  ASSERT_EQ(f.len, 8);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(f.data[i], expected[i]) << "byte " << i;
}

TEST(RuiwoCodec, ZeroCommandSitsAtMidScale) {
  // Truncation of the exact midpoint 32767.5 / 2047.5 gives 0x7FFF / 0x7FF.
  can_frame f;
  encode_ptm_rt(0x01, PtmCommand{}, f);
  EXPECT_EQ(f.data[0], 0x7F);
  EXPECT_EQ(f.data[1], 0xFF);
  EXPECT_EQ(f.data[2], 0x7F);          // velocity 0x7FF high byte
  EXPECT_EQ(f.data[3], 0xF0);          // velocity low nibble F, kp high nibble 0
  EXPECT_EQ(f.data[4], 0x00);
  EXPECT_EQ(f.data[5], 0x00);
  EXPECT_EQ(f.data[6], 0x07);          // kd low nibble 0, torque high nibble 7
  EXPECT_EQ(f.data[7], 0xFF);
}

TEST(RuiwoCodec, GoldenFieldsAgainstSpecFormulaOverRange) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    PtmCommand c{-12.5 + 25 * u(rng), -10 + 20 * u(rng), 250 * u(rng), 50 * u(rng), -50 + 100 * u(rng)};
    can_frame f;
    ASSERT_EQ(encode_ptm_rt(1, c, f), 0);
    EXPECT_EQ((f.data[0] << 8) | f.data[1], spec_uint(c.position_rad, -12.5, 12.5, 16));
    EXPECT_EQ((f.data[2] << 4) | (f.data[3] >> 4), spec_uint(c.velocity_rad_s, -10, 10, 12));
    EXPECT_EQ(((f.data[3] & 0xF) << 8) | f.data[4], spec_uint(c.kp_Nm_per_rad, 0, 250, 12));
    EXPECT_EQ((f.data[5] << 4) | (f.data[6] >> 4), spec_uint(c.kd_Nm_s_per_rad, 0, 50, 12));
    EXPECT_EQ(((f.data[6] & 0xF) << 8) | f.data[7], spec_uint(c.torque_Nm, -50, 50, 12));
  }
}

TEST(RuiwoCodec, SpecialAndZeroingFrames) {
  const std::pair<SpecialCommand, std::uint8_t> cases[] = {
      {SpecialCommand::kEnable, 0xFC}, {SpecialCommand::kDisable, 0xFD}, {SpecialCommand::kSetZero, 0xFE}};
  for (auto [cmd, last] : cases) {
    can_frame f;
    encode_special_rt(0x0E, cmd, f);
    EXPECT_EQ(f.can_id, 0x0Eu);
    ASSERT_EQ(f.len, 8);
    for (int i = 0; i < 7; ++i) EXPECT_EQ(f.data[i], 0xFF);
    EXPECT_EQ(f.data[7], last);
  }
  can_frame z;
  encode_multiturn_zero_rt(0x03, z);
  EXPECT_EQ(z.can_id, 0x603u);
  const std::uint8_t expected[8] = {0x67, 0x06, 0xFE, 0x00, 0x00, 0x00, 0x00, 0x76};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(z.data[i], expected[i]);
}

TEST(RuiwoCodec, EveryOutOfRangeFieldIsClampedAndReported) {
  struct Case {
    PtmCommand cmd;
    std::uint8_t flag;
  };
  const Case cases[] = {
      {{13.0, 0, 0, 0, 0}, kClampPosition}, {{-13.0, 0, 0, 0, 0}, kClampPosition},
      {{0, 10.5, 0, 0, 0}, kClampVelocity}, {{0, -11, 0, 0, 0}, kClampVelocity},
      {{0, 0, 251, 0, 0}, kClampKp},        {{0, 0, -1, 0, 0}, kClampKp},
      {{0, 0, 0, 51, 0}, kClampKd},         {{0, 0, 0, -0.1, 0}, kClampKd},
      {{0, 0, 0, 0, 60}, kClampTorque},     {{0, 0, 0, 0, -50.01}, kClampTorque},
  };
  for (const Case& c : cases) {
    can_frame f;
    EXPECT_EQ(encode_ptm_rt(1, c.cmd, f), c.flag);
    PtmCommand back;
    ASSERT_EQ(decode_ptm_rt(f, back), DriverError::kOk);
    // The packed value is the range end, not a wrapped value.
    EXPECT_LE(std::abs(back.position_rad), 12.5);
    EXPECT_GE(back.kp_Nm_per_rad, 0.0);
    EXPECT_LE(back.torque_Nm, 50.0);
    EXPECT_GE(back.torque_Nm, -50.0);
  }
  // Exactly at the range ends: nothing to report.
  can_frame f;
  EXPECT_EQ(encode_ptm_rt(1, PtmCommand{12.5, -10, 250, 50, -50}, f), 0);
  EXPECT_EQ(f.data[0], 0xFF);
  EXPECT_EQ(f.data[1], 0xFF);
}

TEST(RuiwoCodec, NonFiniteNeverReachesTheWire) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  can_frame f;
  const std::uint8_t flags = encode_ptm_rt(1, PtmCommand{nan, inf, 100, 2, -inf}, f);
  EXPECT_TRUE(flags & kNonFinite);
  EXPECT_TRUE(flags & kClampPosition);
  EXPECT_TRUE(flags & kClampVelocity);
  EXPECT_TRUE(flags & kClampTorque);
  PtmCommand back;
  ASSERT_EQ(decode_ptm_rt(f, back), DriverError::kOk);
  EXPECT_EQ(back.kp_Nm_per_rad, 0.0) << "a NaN position target must drop the stiffness";
  EXPECT_NEAR(back.kd_Nm_s_per_rad, 2.0, 50.0 / 4095);
  EXPECT_NEAR(back.torque_Nm, 0.0, 100.0 / 4095);
}

TEST(RuiwoCodec, CommandRoundTripWithinOneStep) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const PtmCommand c{-12.5 + 25 * u(rng), -10 + 20 * u(rng), 250 * u(rng), 50 * u(rng), -50 + 100 * u(rng)};
    can_frame f;
    encode_ptm_rt(2, c, f);
    PtmCommand b;
    ASSERT_EQ(decode_ptm_rt(f, b), DriverError::kOk);
    EXPECT_NEAR(b.position_rad, c.position_rad, 25.0 / 65535);
    EXPECT_NEAR(b.velocity_rad_s, c.velocity_rad_s, 20.0 / 4095);
    EXPECT_NEAR(b.kp_Nm_per_rad, c.kp_Nm_per_rad, 250.0 / 4095);
    EXPECT_NEAR(b.kd_Nm_s_per_rad, c.kd_Nm_s_per_rad, 50.0 / 4095);
    EXPECT_NEAR(b.torque_Nm, c.torque_Nm, 100.0 / 4095);
  }
}

TEST(RuiwoCodec, GoldenStatusFrameDecodes) {
  // Built by hand: ID 0x03, position 0xC000, velocity 0x400, torque 0xC00,
  // temperature 0x2A, fault 0x00.
  can_frame f{};
  f.can_id = 0x03;
  f.len = 8;
  const std::uint8_t bytes[8] = {0x03, 0xC0, 0x00, 0x40, 0x0C, 0x00, 0x2A, 0x00};
  for (int i = 0; i < 8; ++i) f.data[i] = bytes[i];
  Status s;
  ASSERT_EQ(decode_status_rt(f, s), DriverError::kOk);
  EXPECT_EQ(s.motor_id, 3);
  EXPECT_DOUBLE_EQ(s.position_rad, 0xC000 / 65535.0 * 25 - 12.5);
  EXPECT_DOUBLE_EQ(s.velocity_rad_s, 0x400 / 4095.0 * 20 - 10);
  EXPECT_DOUBLE_EQ(s.torque_Nm, 0xC00 / 4095.0 * 100 - 50);
  EXPECT_EQ(s.temperature_raw, 0x2A);
  EXPECT_EQ(s.fault_code, 0);
}

TEST(RuiwoCodec, StatusRoundTripAndRejections) {
  Status s{0x09, -3.25, 4.5, -12.0, 40, 7};
  can_frame f;
  encode_status_rt(s, f);
  Status b;
  ASSERT_EQ(decode_status_rt(f, b), DriverError::kOk);
  EXPECT_EQ(b.motor_id, 0x09);
  EXPECT_NEAR(b.position_rad, s.position_rad, 25.0 / 65535);
  EXPECT_NEAR(b.velocity_rad_s, s.velocity_rad_s, 20.0 / 4095);
  EXPECT_NEAR(b.torque_Nm, s.torque_Nm, 100.0 / 4095);
  EXPECT_EQ(b.temperature_raw, 40);
  EXPECT_EQ(b.fault_code, 7);
  f.len = 7;
  EXPECT_EQ(decode_status_rt(f, b), DriverError::kWrongLength);
  f.len = 8;
  f.can_id |= CAN_RTR_FLAG;
  EXPECT_EQ(decode_status_rt(f, b), DriverError::kRemoteFrame);
  f.can_id = CAN_ERR_FLAG | 0x09;
  EXPECT_EQ(decode_status_rt(f, b), DriverError::kWrongCanId);
}

TEST(RuiwoCodec, EncodeDecodeDoNotAllocate) {
  can_frame f;
  Status s;
  PtmCommand c{0.3, 0.1, 30, 2, 1};
  test::AllocTrap trap;
  for (int i = 0; i < 100; ++i) {
    encode_ptm_rt(1, c, f);
    (void)decode_status_rt(f, s);
    encode_status_rt(s, f);
  }
  EXPECT_EQ(trap.count(), 0u);
}

}  // namespace
}  // namespace kuavo::drivers::ruiwo
