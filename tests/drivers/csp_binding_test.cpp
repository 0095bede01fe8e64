// The CSP binding of the CiA 402 drives: RPDO1 bytes (round trip, refusals),
// the configuration writes (torque offset mapped, gains before the mode), the
// checked conversions (gain registers, position counts: NaN and range refused,
// quantization), the master's refusal of a bad target, and the emulated
// drive's position loop against the closed-form response of a damped
// oscillator. Expectations are literal bytes and formulas, not the code under test.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "drivers/canopen/cia402_drive.h"
#include "drivers/canopen/pdo_layout.h"
#include "drivers/cycle/canopen_io.h"
#include "drivers/emulator/cia402_emulator.h"
#include "tests/drivers/canopen_test_support.h"
#include "tests/drivers/socketpair_wire.h"

namespace kuavo::drivers {
namespace {

using canopen::test_support::expect_bytes;
using test_support::Wire;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(CspPdo, Rpdo1RoundTripsThroughLiteralBytes) {
  can_frame f;
  canopen::encode_rpdo1_rt(5, canopen::RxPdo1{0x000F, -1234, -123456789}, f);
  // little-endian: 0x000F | -1234 = 0xFB2E | -123456789 = 0xF8A432EB
  expect_bytes(f, 0x205, {0x0F, 0x00, 0x2E, 0xFB, 0xEB, 0x32, 0xA4, 0xF8});
  canopen::RxPdo1 back;
  ASSERT_EQ(canopen::decode_rpdo1_rt(f, 5, back), DriverError::kOk);
  EXPECT_EQ(back.controlword, 0x000F);
  EXPECT_EQ(back.target_torque_permille, -1234);
  EXPECT_EQ(back.target_position_counts, -123456789);
}

TEST(CspPdo, Rpdo1DecodeRefusesOtherNodesShortAndRemoteFrames) {
  can_frame f;
  canopen::encode_rpdo1_rt(5, canopen::RxPdo1{0x000F, 1, 2}, f);
  canopen::RxPdo1 out{0x1111, 3, 4};
  EXPECT_EQ(canopen::decode_rpdo1_rt(f, 6, out), DriverError::kWrongCanId);
  can_frame shorter = f;
  shorter.len = 7;
  EXPECT_EQ(canopen::decode_rpdo1_rt(shorter, 5, out), DriverError::kWrongLength);
  can_frame rtr = f;
  rtr.can_id |= CAN_RTR_FLAG;
  EXPECT_EQ(canopen::decode_rpdo1_rt(rtr, 5, out), DriverError::kRemoteFrame);
  EXPECT_EQ(out.controlword, 0x1111);  // untouched by every refusal
  EXPECT_EQ(out.target_position_counts, 4);
}

// Finds the value written to (index, sub), -1 if none; `at` gets its position.
long long written(const canopen::ConfigSequence& s, std::uint16_t index, std::uint8_t sub, int* at = nullptr) {
  for (int i = 0; i < s.count; ++i) {
    if (s.writes[i].index == index && s.writes[i].subindex == sub) {
      if (at != nullptr) *at = i;
      return s.writes[i].value;
    }
  }
  return -1;
}

TEST(CspPdo, ConfigurationMapsTheTorqueOffsetAndWritesTheGainsBeforeTheMode) {
  canopen::DriveLoop loop;
  loop.mode = canopen::kModeCyclicSyncPosition;
  loop.kp_register = 60000;
  loop.kd_register = 3000;
  const canopen::ConfigSequence csp = canopen::pdo_config_sequence(3, 20, 2000, loop);
  EXPECT_LE(csp.count, canopen::kMaxConfigWrites);
  EXPECT_EQ(written(csp, 0x1600, 2), 0x60B20010);  // torque offset, 16 bit
  EXPECT_EQ(written(csp, 0x1600, 3), 0x607A0020);  // target position, 32 bit
  int kp_at = -1, kd_at = -1, mode_at = -1;
  EXPECT_EQ(written(csp, 0x2010, 1, &kp_at), 60000);
  EXPECT_EQ(written(csp, 0x2010, 2, &kd_at), 3000);
  EXPECT_EQ(written(csp, 0x6060, 0, &mode_at), 8);
  EXPECT_LT(kp_at, mode_at);
  EXPECT_LT(kd_at, mode_at);
  const canopen::ConfigSequence cst = canopen::pdo_config_sequence(3, 20, 2000);
  EXPECT_EQ(written(cst, 0x1600, 2), 0x60710010);  // target torque
  EXPECT_EQ(written(cst, 0x6060, 0), 10);
  EXPECT_EQ(written(cst, 0x2010, 1), -1);
  EXPECT_EQ(csp.count, cst.count + 2);
}

TEST(CspPdo, GainRegistersRoundToMilliUnitsAndRefuseBadValues) {
  std::uint32_t reg = 77;
  ASSERT_TRUE(canopen::gain_to_register(60.0, reg));
  EXPECT_EQ(reg, 60000u);
  ASSERT_TRUE(canopen::gain_to_register(1.2344, reg));
  EXPECT_EQ(reg, 1234u);
  ASSERT_TRUE(canopen::gain_to_register(1.2346, reg));
  EXPECT_EQ(reg, 1235u);
  ASSERT_TRUE(canopen::gain_to_register(0.0, reg));
  EXPECT_EQ(reg, 0u);
  reg = 77;
  EXPECT_FALSE(canopen::gain_to_register(kNaN, reg));
  EXPECT_FALSE(canopen::gain_to_register(-0.001, reg));
  EXPECT_FALSE(canopen::gain_to_register(4000.001, reg));
  EXPECT_FALSE(canopen::gain_to_register(std::numeric_limits<double>::infinity(), reg));
  EXPECT_EQ(reg, 77u);
  EXPECT_DOUBLE_EQ(canopen::register_to_gain(1235), 1.235);
}

TEST(CspPdo, PositionCountsAreCheckedNeverClamped) {
  canopen::DriveConfig cfg;
  cfg.counts_per_rev = 131072.0 * 10.0;
  std::int32_t counts = 7;
  // 0.5 rad * 1310720 / (2 pi) = 104303.78
  ASSERT_EQ(canopen::position_to_counts_rt(cfg, 0.5, counts), DriverError::kOk);
  EXPECT_EQ(counts, 104304);
  ASSERT_EQ(canopen::position_to_counts_rt(cfg, -0.5, counts), DriverError::kOk);
  EXPECT_EQ(counts, -104304);
  counts = 7;
  EXPECT_EQ(canopen::position_to_counts_rt(cfg, kNaN, counts), DriverError::kCommandRefused);
  EXPECT_EQ(canopen::position_to_counts_rt(cfg, 1.0e5, counts), DriverError::kCommandRefused);  // 2.1e10 counts
  EXPECT_EQ(canopen::position_to_counts_rt(cfg, -std::numeric_limits<double>::infinity(), counts),
            DriverError::kCommandRefused);
  EXPECT_EQ(counts, 7);
  // Quantization: the round trip is within half a count everywhere.
  const double half_count_rad = std::numbers::pi / cfg.counts_per_rev;
  for (double q = -3.0; q <= 3.0; q += 0.0137) {
    ASSERT_EQ(canopen::position_to_counts_rt(cfg, q, counts), DriverError::kOk);
    EXPECT_LE(std::abs(canopen::counts_to_rad(cfg, counts) - q), half_count_rad * (1.0 + 1e-9));
  }
}

TEST(CspPdo, DriveLoopRefusesModesAndGainsItCannotWrite) {
  canopen::DriveConfig cfg;
  canopen::DriveLoop loop;
  EXPECT_TRUE(canopen::drive_loop(cfg, loop));  // CST default
  cfg.mode = canopen::kModeCyclicSyncPosition;
  cfg.csp_kp_Nm_per_rad = 30.0;
  cfg.csp_kd_Nm_s_per_rad = 1.5;
  ASSERT_TRUE(canopen::drive_loop(cfg, loop));
  EXPECT_EQ(loop.kp_register, 30000u);
  EXPECT_EQ(loop.kd_register, 1500u);
  cfg.csp_kd_Nm_s_per_rad = kNaN;
  EXPECT_FALSE(canopen::drive_loop(cfg, loop));
  cfg.csp_kd_Nm_s_per_rad = 1.5;
  cfg.mode = 9;  // CSV: not offered
  EXPECT_FALSE(canopen::drive_loop(cfg, loop));
}

// One CSP drive booted over the wire: supervisor on one end, emulator on the other.
class CspLoop : public ::testing::Test {
 protected:
  canopen::DriveConfig cfg{};
  std::array<canopen::DriveConfig, 1> cfgs{};
  std::array<canopen::DriveState, 1> st{};
  std::array<canopen::DriveCommand, 1> cmd{};
  emulator::Cia402Emulator emu;
  Wire wire;
  hal::TimeNs now = 0;

  void SetUp() override {
    cfg.node_id = 4;
    cfg.counts_per_rev = 131072.0 * 10.0;
    cfg.rated_torque_Nm = 10.0;   // 0.01 N m per mille
    cfg.torque_limit_Nm = 60.0;
    cfg.mode = canopen::kModeCyclicSyncPosition;
    cfg.csp_kp_Nm_per_rad = 50.0;
    cfg.csp_kd_Nm_s_per_rad = 2.0;
    cfgs[0] = cfg;
    emulator::add_drive(emu, cfg);
    can_frame f;
    canopen::start_drive(cfg, st[0], now, f);
    EXPECT_EQ(send_rt(wire.host, f), DriverError::kOk);
  }
  void cycle() {
    emulator::serve_rt(emu, wire.device, now);
    canopen_receive_rt(wire.host, cfgs, st, now, 0);
    canopen_send_rt(wire.host, cfgs, st, cmd, now);
    now += 2'000'000;
  }
  bool enable(double position_rad) {
    emu.drives[0].position_rad = position_rad;
    cmd[0].enable = true;
    cmd[0].position_rad = position_rad;
    for (int k = 0; k < 500; ++k) {
      cycle();
      if (st[0].power == canopen::Cia402State::kOperationEnabled) {
        cycle();  // the first target sent while enabled reaches the drive
        cycle();
        return true;
      }
    }
    return false;
  }
};

TEST_F(CspLoop, TheDriveDecodesModeGainsAndTargetsFromTheWire) {
  ASSERT_TRUE(enable(0.3));
  const emulator::EmulatedDrive& d = emu.drives[0];
  EXPECT_EQ(d.mode, canopen::kModeCyclicSyncPosition);
  EXPECT_EQ(d.rpdo1_torque_object, 0x60B2);
  EXPECT_EQ(d.kp_register, 50000u);
  EXPECT_EQ(d.kd_register, 2000u);
  cmd[0].position_rad = 0.5;
  cmd[0].torque_Nm = 1.234;
  cycle();
  cycle();
  EXPECT_EQ(d.target_position_counts, 104304);  // 0.5 rad, as above
  EXPECT_EQ(d.target_torque_permille, 123);     // 1.234 N m / 0.01, rounded
  // At q = 0.45, v = 0.1: 50 (0.5 - 0.45) - 2 (0.1) + 1.23, target quantized to a count.
  const double target = 104304 * 2.0 * std::numbers::pi / cfg.counts_per_rev;
  EXPECT_NEAR(emulator::drive_torque_at_Nm(d, 0.45, 0.1), 50.0 * (target - 0.45) - 0.2 + 1.23, 1e-12);
  // Saturation at the drive's limit is reported.
  bool saturated = false;
  EXPECT_DOUBLE_EQ(emulator::drive_torque_at_Nm(d, -2.0, 0.0, &saturated), 60.0);
  EXPECT_TRUE(saturated);
  EXPECT_EQ(st[0].refused_commands, 0u);
}

// The clamp is on the drive's torque at the sample it closes on, not on the offset field: a
// moving joint needs an offset beyond the limit (the drive's −kd·q̇ takes kd·q̇ off), and an
// offset is cut back only as far as makes that torque the limit. Oracle: the emulated drive's
// own law evaluated at the reported state.
TEST_F(CspLoop, TheTorqueAtTheSampleIsClampedNotTheOffset) {
  ASSERT_TRUE(enable(0.3));
  emulator::EmulatedDrive& d = emu.drives[0];
  d.velocity_rad_s = 20.0;  // kd·q̇ = 40 N·m, the limit 60 N·m
  cycle();
  cycle();  // the sample (0.3 rad, 20 rad/s) has reached the supervisor
  const double q = canopen::counts_to_rad(cfg, st[0].tpdo1.actual_position_counts);
  const double v = canopen::counts_to_rad(cfg, st[0].tpdo2.actual_velocity_counts_s);
  ASSERT_NEAR(v, 20.0, 1e-3);
  const std::uint32_t clamps = st[0].torque_clamps;
  auto torque_at_sample = [&] { return emulator::drive_torque_at_Nm(d, q, v); };
  // 95 N·m of offset on the sample's position: 55 N·m at the sample, within the limit.
  cmd[0].position_rad = q;
  cmd[0].torque_Nm = 95.0;
  cycle();
  cycle();
  EXPECT_EQ(d.target_torque_permille, 9500);
  EXPECT_NEAR(torque_at_sample(), 55.0, 0.05);
  EXPECT_EQ(st[0].torque_clamps, clamps);
  // 130 N·m would be 90 at the sample: cut to the limit there, and counted.
  cmd[0].torque_Nm = 130.0;
  cycle();
  EXPECT_EQ(st[0].torque_clamps, clamps + 1);
  cycle();
  EXPECT_NEAR(torque_at_sample(), 60.0, 0.05);
  EXPECT_NEAR(d.target_torque_permille * cfg.rated_torque_Nm / 1000.0, 100.0, 0.05);
  // A position error's kp share counts too: 0.2 rad short of the target adds 10 N·m, so −60 at
  // the sample is an offset of −60 + 40 − 10 = −30 N·m, and −100 (−130 there) is cut back to it.
  cmd[0].position_rad = q + 0.2;
  cmd[0].torque_Nm = -100.0;
  cycle();
  cycle();
  EXPECT_NEAR(torque_at_sample(), -60.0, 0.05);
  EXPECT_NEAR(d.target_torque_permille * cfg.rated_torque_Nm / 1000.0, -60.0 + 40.0 - 10.0, 0.05);
  EXPECT_EQ(st[0].refused_commands, 0u);
}

TEST_F(CspLoop, ABadTargetIsRefusedAndTheDriveHeldWhereItIs) {
  ASSERT_TRUE(enable(0.3));
  emu.drives[0].position_rad = 0.2;  // the drive's own position, reported by the TPDO next cycle
  cycle();
  for (double bad : {kNaN, 1.0e5}) {
    cmd[0].position_rad = bad;
    cmd[0].torque_Nm = 5.0;
    cycle();
    cycle();
    const emulator::EmulatedDrive& d = emu.drives[0];
    EXPECT_EQ(d.target_position_counts, 41722);  // 0.2 rad * 1310720 / (2 pi) = 41721.5, last reported
    EXPECT_EQ(d.target_torque_permille, 0);
  }
  EXPECT_EQ(st[0].refused_commands, 4u);
  EXPECT_EQ(st[0].error, DriverError::kCommandRefused);
  // A non-finite torque offset is refused too.
  cmd[0].position_rad = 0.2;
  cmd[0].torque_Nm = kNaN;
  cycle();
  EXPECT_EQ(st[0].refused_commands, 5u);
}

TEST_F(CspLoop, DisabledDriveTargetsItsOwnPositionAndProducesNoTorque) {
  ASSERT_TRUE(enable(0.3));
  cmd[0].enable = false;
  cmd[0].position_rad = 1.0;
  cmd[0].torque_Nm = 3.0;
  for (int k = 0; k < 5; ++k) cycle();
  const emulator::EmulatedDrive& d = emu.drives[0];
  EXPECT_NE(d.power, canopen::Cia402State::kOperationEnabled);
  EXPECT_EQ(emulator::drive_torque_Nm(d), 0.0);
  EXPECT_EQ(d.target_torque_permille, 0);
  EXPECT_NEAR(canopen::counts_to_rad(cfg, d.target_position_counts), 0.3, 1e-5);
}

// The emulated drive's loop closed on a 1-DOF inertia, integrated finely (RK4, 10 us):
// J q'' = kp (q_t - q) - kd q' + tau_off is a damped oscillator with equilibrium
// q_eq = q_t + tau_off / kp; from rest at q0:
//   q(t) = q_eq + (q0 - q_eq) e^(-z w t) (cos(wd t) + z w / wd sin(wd t)).
TEST_F(CspLoop, DrivePdMatchesTheDampedOscillatorInClosedForm) {
  ASSERT_TRUE(enable(0.0));
  cmd[0].position_rad = 0.4;
  cmd[0].torque_Nm = -2.5;
  cycle();
  cycle();
  const emulator::EmulatedDrive& d = emu.drives[0];
  const double q_t = canopen::counts_to_rad(cfg, d.target_position_counts);
  const double tau_off = d.target_torque_permille * cfg.rated_torque_Nm / 1000.0;
  ASSERT_NEAR(q_t, 0.4, 1e-5);
  ASSERT_NEAR(tau_off, -2.5, 1e-12);
  const double J = 0.05, kp = 50.0, kd = 2.0;
  const double w = std::sqrt(kp / J), z = kd / (2.0 * std::sqrt(kp * J)), wd = w * std::sqrt(1.0 - z * z);
  const double q_eq = q_t + tau_off / kp, q0 = 0.0;
  double q = q0, v = 0.0, max_err = 0.0;
  const double h = 1e-5;
  auto acc = [&](double qq, double vv) { return emulator::drive_torque_at_Nm(d, qq, vv) / J; };
  for (int n = 1; n <= 50000; ++n) {  // 0.5 s
    const double k1q = v, k1v = acc(q, v);
    const double k2q = v + 0.5 * h * k1v, k2v = acc(q + 0.5 * h * k1q, v + 0.5 * h * k1v);
    const double k3q = v + 0.5 * h * k2v, k3v = acc(q + 0.5 * h * k2q, v + 0.5 * h * k2v);
    const double k4q = v + h * k3v, k4v = acc(q + h * k3q, v + h * k3v);
    q += h / 6.0 * (k1q + 2 * k2q + 2 * k3q + k4q);
    v += h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    const double t = n * h;
    const double exact = q_eq + (q0 - q_eq) * std::exp(-z * w * t) * (std::cos(wd * t) + z * w / wd * std::sin(wd * t));
    max_err = std::max(max_err, std::abs(q - exact));
  }
  EXPECT_LT(max_err, 1e-9);
  EXPECT_NEAR(q, q_eq, 1e-3);  // settled at the offset-shifted equilibrium (0.35 rad)
}

}  // namespace
}  // namespace kuavo::drivers
