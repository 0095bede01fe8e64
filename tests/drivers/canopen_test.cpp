// CANopen frames (golden bytes from CiA 301/402), the 402 power state machine,
// and the drive supervisor through boot, SDO configuration, NMT start,
// enabling, cyclic torque and its failure paths.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "drivers/canopen/canopen_frames.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/canopen/cia402_state.h"
#include "drivers/canopen/pdo_layout.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers::canopen {
namespace {

void expect_bytes(const can_frame& f, std::uint32_t id, std::initializer_list<int> bytes) {
  EXPECT_EQ(f.can_id, id);
  ASSERT_EQ(f.len, bytes.size());
  int i = 0;
  for (int b : bytes) {
    EXPECT_EQ(f.data[i], b) << "byte " << i;
    ++i;
  }
}

can_frame frame(std::uint32_t id, std::initializer_list<int> bytes) {
  can_frame f{};
  f.can_id = id;
  f.len = static_cast<std::uint8_t>(bytes.size());
  int i = 0;
  for (int b : bytes) f.data[i++] = static_cast<std::uint8_t>(b);
  return f;
}

TEST(CanopenFrames, GoldenNmtSyncSdo) {
  can_frame f;
  encode_nmt_rt(NmtCommand::kStart, 5, f);
  expect_bytes(f, 0x000, {0x01, 0x05});
  encode_nmt_rt(NmtCommand::kResetCommunication, 0, f);
  expect_bytes(f, 0x000, {0x82, 0x00});
  encode_sync_rt(f);
  expect_bytes(f, 0x080, {});
  // Expedited download: 0x2F (1 byte), 0x2B (2), 0x23 (4); index little-endian.
  encode_sdo_download_rt(5, SdoWrite{0x6060, 0, 1, 10}, f);
  expect_bytes(f, 0x605, {0x2F, 0x60, 0x60, 0x00, 0x0A, 0x00, 0x00, 0x00});
  encode_sdo_download_rt(5, SdoWrite{0x1017, 0, 2, 20}, f);
  expect_bytes(f, 0x605, {0x2B, 0x17, 0x10, 0x00, 0x14, 0x00, 0x00, 0x00});
  encode_sdo_download_rt(0x7F, SdoWrite{0x1A00, 1, 4, 0x60410010}, f);
  expect_bytes(f, 0x67F, {0x23, 0x00, 0x1A, 0x01, 0x10, 0x00, 0x41, 0x60});
}

TEST(CanopenFrames, SdoRepliesHeartbeatEmergency) {
  const SdoWrite w{0x6060, 0, 1, 10};
  std::uint32_t abort_code = 0;
  EXPECT_EQ(decode_sdo_reply_rt(frame(0x585, {0x60, 0x60, 0x60, 0, 0, 0, 0, 0}), 5, w, abort_code),
            DriverError::kOk);
  EXPECT_EQ(decode_sdo_reply_rt(frame(0x585, {0x80, 0x60, 0x60, 0, 0x11, 0x00, 0x09, 0x06}), 5, w,
                                abort_code),
            DriverError::kSdoAbort);
  EXPECT_EQ(abort_code, 0x06090011u);  // "sub-index does not exist"
  EXPECT_EQ(decode_sdo_reply_rt(frame(0x586, {0x60, 0x60, 0x60, 0, 0, 0, 0, 0}), 5, w, abort_code),
            DriverError::kWrongCanId);
  EXPECT_EQ(decode_sdo_reply_rt(frame(0x585, {0x60, 0x61, 0x60, 0, 0, 0, 0, 0}), 5, w, abort_code),
            DriverError::kWrongCanId);

  std::uint8_t node = 0;
  NmtState st = NmtState::kUnknown;
  ASSERT_EQ(decode_heartbeat_rt(frame(0x70C, {0x05}), node, st), DriverError::kOk);
  EXPECT_EQ(node, 12);
  EXPECT_EQ(st, NmtState::kOperational);
  ASSERT_EQ(decode_heartbeat_rt(frame(0x701, {0x7F}), node, st), DriverError::kOk);
  EXPECT_EQ(st, NmtState::kPreOperational);
  ASSERT_EQ(decode_heartbeat_rt(frame(0x701, {0x00}), node, st), DriverError::kOk);
  EXPECT_EQ(st, NmtState::kBootUp);
  EXPECT_EQ(decode_heartbeat_rt(frame(0x701, {0x05, 0}), node, st), DriverError::kWrongLength);
  EXPECT_EQ(decode_heartbeat_rt(frame(0x700, {0x05}), node, st), DriverError::kWrongCanId);
  EXPECT_EQ(decode_heartbeat_rt(frame(0x701, {0x33}), node, st), DriverError::kUnknownCommand);

  Emergency em;
  ASSERT_EQ(decode_emergency_rt(frame(0x083, {0x10, 0x23, 0x04, 0, 0, 0, 0, 0}), em), DriverError::kOk);
  EXPECT_EQ(em.node, 3);
  EXPECT_EQ(em.error_code, 0x2310);
  EXPECT_EQ(em.error_register, 0x04);
  EXPECT_EQ(decode_emergency_rt(frame(0x080, {}), em), DriverError::kWrongCanId);  // SYNC
}

TEST(PdoLayout, GoldenRpdoAndTpdos) {
  can_frame f;
  encode_rpdo1_rt(3, RxPdo1{0x000F, -1000, 0x01020304}, f);
  // controlword 0x000F LE, torque -1000 = 0xFC18 LE, position LE.
  expect_bytes(f, 0x203, {0x0F, 0x00, 0x18, 0xFC, 0x04, 0x03, 0x02, 0x01});
  TxPdo1 t1;
  ASSERT_EQ(decode_tpdo1_rt(frame(0x183, {0x37, 0x02, 0xF4, 0x01, 0xFF, 0xFF, 0xFF, 0xFF}), 3, t1),
            DriverError::kOk);
  EXPECT_EQ(t1.statusword, 0x0237);
  EXPECT_EQ(t1.actual_torque_permille, 500);
  EXPECT_EQ(t1.actual_position_counts, -1);
  TxPdo2 t2;
  ASSERT_EQ(decode_tpdo2_rt(frame(0x283, {0x00, 0x00, 0x01, 0x00, 0x10, 0x23, 0x0A}), 3, t2),
            DriverError::kOk);
  EXPECT_EQ(t2.actual_velocity_counts_s, 0x10000);
  EXPECT_EQ(t2.error_code, 0x2310);
  EXPECT_EQ(t2.mode_display, 10);
  EXPECT_EQ(decode_tpdo1_rt(frame(0x184, {0, 0, 0, 0, 0, 0, 0, 0}), 3, t1), DriverError::kWrongCanId);
  EXPECT_EQ(decode_tpdo1_rt(frame(0x183, {0, 0, 0}), 3, t1), DriverError::kWrongLength);
}

TEST(PdoLayout, ConfigSequenceDisablesRemapsAndEnables) {
  const ConfigSequence s = pdo_config_sequence(7, 20, 2000);
  ASSERT_GT(s.count, 0);
  ASSERT_LE(s.count, kMaxConfigWrites);
  // RPDO1: invalidate, sync type, count 0, 3 entries, count 3, valid COB-ID.
  EXPECT_EQ(s.writes[0].index, 0x1400);
  EXPECT_EQ(s.writes[0].value, 0x80000207u);
  EXPECT_EQ(s.writes[1].value, 1u);
  EXPECT_EQ(s.writes[2].index, 0x1600);
  EXPECT_EQ(s.writes[2].value, 0u);
  EXPECT_EQ(s.writes[3].value, 0x60400010u);
  EXPECT_EQ(s.writes[4].value, 0x60710010u);
  EXPECT_EQ(s.writes[5].value, 0x607A0020u);
  EXPECT_EQ(s.writes[6].value, 3u);
  EXPECT_EQ(s.writes[7].value, 0x207u);
  // The mapped bits of every PDO fit 8 bytes.
  for (int i = 0; i < s.count; ++i) {
    const SdoWrite& w = s.writes[i];
    if ((w.index & 0xFE00) == 0x1600 || (w.index & 0xFE00) == 0x1A00) {
      if (w.subindex == 0 && w.value != 0) {
        int bits = 0;
        for (int k = 1; k <= static_cast<int>(w.value); ++k) bits += s.writes[i - k].value & 0xFF;
        EXPECT_LE(bits, 64) << std::hex << w.index;
      }
    }
  }
  EXPECT_EQ(s.writes[s.count - 3].index, 0x6060);
  EXPECT_EQ(s.writes[s.count - 3].value, 10u);
  EXPECT_EQ(s.writes[s.count - 2].index, 0x1017);
  EXPECT_EQ(s.writes[s.count - 1].index, 0x1006);
  EXPECT_EQ(s.writes[s.count - 1].value, 2000u);
}

TEST(Cia402, StatuswordDecoding) {
  EXPECT_EQ(decode_statusword(0x0000), Cia402State::kNotReadyToSwitchOn);
  EXPECT_EQ(decode_statusword(0x0250), Cia402State::kSwitchOnDisabled);
  EXPECT_EQ(decode_statusword(0x0231), Cia402State::kReadyToSwitchOn);
  EXPECT_EQ(decode_statusword(0x0233), Cia402State::kSwitchedOn);
  EXPECT_EQ(decode_statusword(0x0237), Cia402State::kOperationEnabled);
  EXPECT_EQ(decode_statusword(0x0217), Cia402State::kQuickStopActive);
  EXPECT_EQ(decode_statusword(0x021F), Cia402State::kFaultReactionActive);
  EXPECT_EQ(decode_statusword(0x0218), Cia402State::kFault);
  EXPECT_EQ(decode_statusword(0x0208), Cia402State::kFault);
}

// A minimal drive following the CiA 402 transitions the master relies on.
struct FakeDrive {
  Cia402State state = Cia402State::kSwitchOnDisabled;
  bool last_reset_bit = false;
  bool fault_sticky = false;  // reset does not clear it
  void apply(std::uint16_t cw) {
    const bool reset_edge = (cw & 0x80) && !last_reset_bit;
    last_reset_bit = cw & 0x80;
    if (state == Cia402State::kFault) {
      if (reset_edge && !fault_sticky) state = Cia402State::kSwitchOnDisabled;
      return;
    }
    if ((cw & 0x02) == 0) {  // disable voltage
      state = Cia402State::kSwitchOnDisabled;
      return;
    }
    const std::uint16_t low = cw & 0x0F;
    if (low == 0x06) state = Cia402State::kReadyToSwitchOn;
    else if (low == 0x07 && state == Cia402State::kReadyToSwitchOn) state = Cia402State::kSwitchedOn;
    else if (low == 0x07 && state == Cia402State::kOperationEnabled) state = Cia402State::kSwitchedOn;
    else if (low == 0x0F && (state == Cia402State::kSwitchedOn || state == Cia402State::kOperationEnabled))
      state = Cia402State::kOperationEnabled;
  }
  std::uint16_t statusword() const {
    switch (state) {
      case Cia402State::kSwitchOnDisabled: return 0x0250;
      case Cia402State::kReadyToSwitchOn: return 0x0231;
      case Cia402State::kSwitchedOn: return 0x0233;
      case Cia402State::kOperationEnabled: return 0x0237;
      case Cia402State::kFault: return 0x0218;
      default: return 0x0000;
    }
  }
};

TEST(Cia402, EnableSequenceIsShutdownSwitchOnEnable) {
  FakeDrive d;
  Cia402Control ctl;
  DriverError e;
  std::vector<std::uint16_t> sent;
  for (int i = 0; i < 5; ++i) {
    const std::uint16_t cw = next_controlword_rt(d.state, true, ctl, e);
    EXPECT_EQ(e, DriverError::kOk);
    sent.push_back(cw);
    d.apply(cw);
  }
  EXPECT_EQ(sent, (std::vector<std::uint16_t>{0x06, 0x07, 0x0F, 0x0F, 0x0F}));
  EXPECT_EQ(d.state, Cia402State::kOperationEnabled);
  // Disabling walks straight to switch-on disabled.
  d.apply(next_controlword_rt(d.state, false, ctl, e));
  EXPECT_EQ(d.state, Cia402State::kSwitchOnDisabled);
}

TEST(Cia402, FaultResetUsesRisingEdgeThenGivesUp) {
  FakeDrive d;
  d.state = Cia402State::kFault;
  Cia402Control ctl;
  DriverError e;
  std::uint16_t cw = next_controlword_rt(d.state, true, ctl, e);
  EXPECT_EQ(cw, 0x80);
  d.apply(cw);
  EXPECT_EQ(d.state, Cia402State::kSwitchOnDisabled);
  // A sticky fault: edges 0x80, 0x00, 0x80, 0x00, 0x80, then the budget is spent.
  d.state = Cia402State::kFault;
  d.fault_sticky = true;
  ctl = Cia402Control{};
  std::vector<std::uint16_t> sent;
  for (int i = 0; i < 8; ++i) {
    cw = next_controlword_rt(d.state, true, ctl, e);
    sent.push_back(cw);
    d.apply(cw);
  }
  EXPECT_EQ(sent, (std::vector<std::uint16_t>{0x80, 0x00, 0x80, 0x00, 0x80, 0x00, 0x00, 0x00}));
  EXPECT_EQ(e, DriverError::kFaultResetFailed);
  // Asking for disable re-arms the budget.
  next_controlword_rt(d.state, false, ctl, e);
  EXPECT_EQ(next_controlword_rt(d.state, true, ctl, e), 0x80);
}

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
  EXPECT_FALSE(step_rt(cfg, st, now, DriveCommand{}, out));
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
