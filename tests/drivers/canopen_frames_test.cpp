// CANopen frames and our PDO layout: golden bytes from CiA 301/402.
#include <gtest/gtest.h>

#include "drivers/canopen/canopen_frames.h"
#include "drivers/canopen/pdo_layout.h"
#include "tests/drivers/canopen_test_support.h"

namespace kuavo::drivers::canopen {
namespace {

using namespace canopen::test_support;

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

}  // namespace
}  // namespace kuavo::drivers::canopen
