// Drive supervisor: boot, SDO configuration, NMT start, enabling, cyclic
// torque, and the failure paths (heartbeat, TPDO timeout, SDO abort/timeout,
// boot timeout, unexpected reboot).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "drivers/canopen/canopen_frames.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/canopen/pdo_layout.h"
#include "tests/support/alloc_trap.h"
#include "tests/drivers/canopen_test_support.h"

namespace kuavo::drivers::canopen {
namespace {

using namespace canopen::test_support;

// Drives a DriveState through boot and configuration against a scripted node.
class DriveSupervisor : public ::testing::Test {
 protected:
  DriveConfig cfg;
  DriveState st;
  FakeDrive drive;
  hal::TimeNs now = 1'000'000'000;
  can_frame out{};

  void SetUp() override {
    cfg.node_id = 4;
    cfg.counts_per_rev = 131072.0 * 18.0;
    cfg.rated_torque_Nm = 88.9;
    cfg.torque_limit_Nm = 127.0;
  }
  void feed(const can_frame& f) { handle_frame_rt(cfg, st, f, now); }
  void heartbeat(int state) { feed(frame(0x704, {state})); }
  void tpdos(std::int32_t pos_counts = 0) {
    can_frame f{};
    f.can_id = 0x184;
    f.len = 8;
    put_u16(&f.data[0], drive.statusword());
    put_u16(&f.data[2], static_cast<std::uint16_t>(250));
    put_u32(&f.data[4], static_cast<std::uint32_t>(pos_counts));
    feed(f);
    feed(frame(0x284, {0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x0A}));
  }
  // Boots and configures; returns the number of SDO writes the node saw.
  int bring_up() {
    start_drive(cfg, st, now, out);
    expect_bytes(out, 0x000, {0x82, 0x04});
    EXPECT_FALSE(step_rt(cfg, st, now, DriveCommand{}, out));  // waiting for boot-up
    heartbeat(0x00);
    EXPECT_EQ(st.phase, DrivePhase::kConfiguring);
    int writes = 0;
    for (int guard = 0; guard < 100 && st.phase == DrivePhase::kConfiguring; ++guard) {
      now += 1'000'000;
      if (!step_rt(cfg, st, now, DriveCommand{}, out)) continue;
      if ((out.can_id & 0x780) == 0x600) {
        ++writes;
        feed(frame(0x584, {0x60, out.data[1], out.data[2], out.data[3], 0, 0, 0, 0}));
      }
    }
    EXPECT_EQ(st.phase, DrivePhase::kStarting);
    expect_bytes(out, 0x000, {0x01, 0x04});
    heartbeat(0x05);
    return writes;
  }
};

TEST_F(DriveSupervisor, BootConfigureStartEnableAndCyclicTorque) {
  EXPECT_EQ(bring_up(), pdo_config_sequence(4, 20, 2000).count);
  DriveCommand cmd;
  cmd.enable = true;
  cmd.torque_Nm = 44.45;  // half the rated torque -> 500 per mille
  std::vector<std::uint16_t> controlwords;
  for (int cycle = 0; cycle < 6; ++cycle) {
    now += 2'000'000;
    tpdos();
    heartbeat(0x05);
    ASSERT_TRUE(step_rt(cfg, st, now, cmd, out));
    ASSERT_EQ(out.can_id, 0x204u);
    const std::uint16_t cw = get_u16(&out.data[0]);
    const auto torque = static_cast<std::int16_t>(get_u16(&out.data[2]));
    controlwords.push_back(cw);
    // Torque only once the drive reports operation enabled.
    EXPECT_EQ(torque, drive.state == Cia402State::kOperationEnabled ? 500 : 0) << cycle;
    drive.apply(cw);
  }
  EXPECT_EQ(st.phase, DrivePhase::kOperational);
  EXPECT_EQ(st.error, DriverError::kOk);
  EXPECT_EQ(controlwords[0], 0x06);
  EXPECT_EQ(controlwords[1], 0x07);
  EXPECT_EQ(controlwords[2], 0x0F);
  const MotorSample s = motor_sample(cfg, st);
  EXPECT_TRUE(s.valid);
  EXPECT_NEAR(s.torque_Nm, 0.25 * 88.9, 1e-12);
  EXPECT_NEAR(s.velocity_rad_s, 4096 * 2 * std::numbers::pi / cfg.counts_per_rev, 1e-12);
}

TEST_F(DriveSupervisor, TorqueIsClampedAndNaNBecomesZero) {
  bool clamped = false;
  EXPECT_EQ(torque_to_permille(cfg, 500.0, clamped), std::lround(127.0 / 88.9 * 1000));
  EXPECT_TRUE(clamped);
  EXPECT_EQ(torque_to_permille(cfg, std::nan(""), clamped), 0);
  EXPECT_TRUE(clamped);
  EXPECT_EQ(torque_to_permille(cfg, -8.89, clamped), -100);
  EXPECT_FALSE(clamped);
}

TEST_F(DriveSupervisor, HeartbeatLossFails) {
  bring_up();
  now += 1'000'000;
  tpdos();
  ASSERT_TRUE(step_rt(cfg, st, now, DriveCommand{}, out));
  now += cfg.heartbeat_timeout_ns + 1;
  tpdos();
  DriveCommand cmd;
  cmd.enable = true;
  cmd.torque_Nm = 50.0;
  // Failed, but the drive may still listen: it gets disable voltage and zero
  // torque every cycle, never the last target again.
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(step_rt(cfg, st, now, cmd, out));
    expect_bytes(out, 0x204, {0, 0, 0, 0, 0, 0, 0, 0});
    now += 2'000'000;
  }
  EXPECT_EQ(st.phase, DrivePhase::kFailed);
  EXPECT_EQ(st.error, DriverError::kHeartbeatLost);
}

TEST_F(DriveSupervisor, MissingTpdosMakeTheSampleInvalid) {
  bring_up();
  now += 1'000'000;
  tpdos();
  heartbeat(0x05);
  ASSERT_TRUE(step_rt(cfg, st, now, DriveCommand{}, out));
  EXPECT_TRUE(motor_sample(cfg, st).valid);
  now += cfg.tpdo_timeout_ns + 1;
  heartbeat(0x05);
  ASSERT_TRUE(step_rt(cfg, st, now, DriveCommand{}, out));
  EXPECT_FALSE(motor_sample(cfg, st).valid);
  EXPECT_EQ(st.error, DriverError::kReplyTimeout);
}

TEST_F(DriveSupervisor, SdoAbortAndTimeoutFail) {
  start_drive(cfg, st, now, out);
  heartbeat(0x00);
  ASSERT_TRUE(step_rt(cfg, st, now, DriveCommand{}, out));
  feed(frame(0x584, {0x80, out.data[1], out.data[2], out.data[3], 0x00, 0x00, 0x02, 0x06}));
  EXPECT_EQ(st.phase, DrivePhase::kFailed);
  EXPECT_EQ(st.error, DriverError::kSdoAbort);
  EXPECT_EQ(st.last_abort_code, 0x06020000u);

  start_drive(cfg, st, now, out);
  heartbeat(0x00);
  int sent = 0;
  for (int i = 0; i < 10; ++i) {
    if (step_rt(cfg, st, now, DriveCommand{}, out)) ++sent;
    now += kSdoTimeout_ns + 1;
  }
  EXPECT_EQ(sent, kSdoRetries + 1);
  EXPECT_EQ(st.error, DriverError::kSdoTimeout);
}

TEST_F(DriveSupervisor, BootTimeoutAndUnexpectedReboot) {
  start_drive(cfg, st, now, out);
  EXPECT_FALSE(step_rt(cfg, st, now + kBootTimeout_ns + 1, DriveCommand{}, out));
  EXPECT_EQ(st.error, DriverError::kBootTimeout);
  bring_up();
  heartbeat(0x00);  // the drive rebooted: its PDO mapping is gone
  EXPECT_EQ(st.phase, DrivePhase::kFailed);
  EXPECT_EQ(st.error, DriverError::kUnexpectedNmtState);
}

TEST_F(DriveSupervisor, CyclicStepDoesNotAllocate) {
  bring_up();
  DriveCommand cmd;
  cmd.enable = true;
  cmd.torque_Nm = 3.0;
  test::AllocTrap trap;
  for (int i = 0; i < 50; ++i) {
    now += 2'000'000;
    tpdos();
    heartbeat(0x05);
    step_rt(cfg, st, now, cmd, out);
    drive.apply(get_u16(&out.data[0]));
    (void)motor_sample(cfg, st);
  }
  EXPECT_EQ(trap.count(), 0u);
}

}  // namespace
}  // namespace kuavo::drivers::canopen
