// Per-cycle bus I/O helpers (drivers/cycle): reports, clamps, a full transmit
// queue, error frames, unknown frames, and receive stamps on the monotonic base.
#include <gtest/gtest.h>

#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include "controllers/model/model.h"
#include "drivers/cycle/canopen_io.h"
#include "drivers/cycle/ruiwo_io.h"
#include "drivers/cycle/rx_stamp.h"
#include "drivers/emulator/ruiwo_emulator.h"

namespace kuavo::drivers {
namespace {

class RuiwoIo : public ::testing::Test {
 protected:
  int fd[2]{-1, -1};
  CanPort host, dev;
  ruiwo::Bus bus;
  hal::CommandFrame commands;
  hal::SensorFrame sensors;

  void SetUp() override {
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_DGRAM, 0, fd), 0);
    host = attach_can_port(fd[0], false);
    dev = attach_can_port(fd[1], false);
    ruiwo::MotorConfig a, b;
    a.motor_id = 1;
    a.joint = 13;
    b.motor_id = 2;
    b.joint = 14;
    for (ruiwo::MotorConfig* m : {&a, &b}) {
      m->position_min_rad = -1.0;
      m->position_max_rad = 1.0;
      m->torque_max_Nm = 10.0;
    }
    std::string msg;
    ASSERT_EQ(ruiwo::build_bus({a, b}, bus, msg), DriverError::kOk) << msg;
  }
  void TearDown() override {
    close(fd[0]);
    close(fd[1]);
  }
  void reply(std::uint8_t id, std::uint8_t fault = 0) {
    can_frame f;
    ruiwo::encode_status_rt(ruiwo::Status{id, 0.1, 0, 0, 30, fault}, f);
    ASSERT_EQ(send_rt(dev, f), DriverError::kOk);
  }
};

TEST_F(RuiwoIo, SendReportsClampsPerCycle) {
  commands.joints[13].mode = hal::JointMode::kPdTorque;
  commands.joints[13].position_ref_rad = 3.0;    // beyond +1
  commands.joints[14].mode = hal::JointMode::kPdTorque;
  commands.joints[14].torque_ff_Nm = -20.0;     // beyond 10
  const RuiwoSendReport r = ruiwo_send_rt(host, bus, commands, 0);
  EXPECT_EQ(r.sent, 2);
  EXPECT_EQ(r.clamped, 2);
  EXPECT_EQ(r.clamp_flags, ruiwo::kClampPosition | ruiwo::kClampTorque);
}

TEST_F(RuiwoIo, ReceiveCountsRepliesFaultsUnknownsAndErrorFrames) {
  ruiwo_send_rt(host, bus, commands, 0);
  reply(1);
  reply(2, 0x21);
  reply(9);
  can_frame err{};
  err.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  err.len = CAN_ERR_DLC;
  err.data[1] = CAN_ERR_CRTL_RX_WARNING;
  ASSERT_EQ(send_rt(dev, err), DriverError::kOk);
  const RuiwoReceiveReport r = ruiwo_receive_rt(host, bus, 1'000'000, 0, sensors);
  EXPECT_EQ(r.replies, 2);
  EXPECT_EQ(r.faulted, 1);
  EXPECT_EQ(r.rejected, 1);
  EXPECT_EQ(r.error_frames, 1);
  EXPECT_EQ(r.silent, 0);
  EXPECT_TRUE(host.health.error_warning);
  EXPECT_EQ(sensors.joints[13].stamp_ns, 1'000'000);  // no kernel stamp: the cycle time
}

TEST_F(RuiwoIo, KernelStampsAreShiftedToTheMonotonicBase) {
  ASSERT_TRUE(enable_rx_timestamps(fd[0]));
  ruiwo_send_rt(host, bus, commands, 0);
  reply(1);
  timespec rt;
  clock_gettime(CLOCK_REALTIME, &rt);
  const hal::TimeNs realtime_ns = rt.tv_sec * 1'000'000'000LL + rt.tv_nsec;
  const hal::TimeNs offset = 5'000'000'000 - realtime_ns;  // pretend monotonic = 5 s now
  ruiwo_receive_rt(host, bus, 5'000'000'000, offset, sensors);
  EXPECT_NEAR(static_cast<double>(sensors.joints[13].stamp_ns), 5e9, 1e8);
  EXPECT_LE(sensors.joints[13].stamp_ns, 5'000'000'000);
}

TEST_F(RuiwoIo, PersistentlyFullQueueMakesMotorsSilent) {
  const int small = 2048;
  ASSERT_EQ(setsockopt(fd[0], SOL_SOCKET, SO_SNDBUF, &small, sizeof(small)), 0);
  can_frame filler{};
  filler.len = 8;
  int guard = 0;
  while (send_rt(host, filler) == DriverError::kOk && ++guard < 100000) {
  }
  ASSERT_LT(guard, 100000);
  int dropped = 0, silent = 0;
  hal::TimeNs now = 0;
  for (int k = 0; k < 200 && silent == 0; ++k) {
    dropped += ruiwo_send_rt(host, bus, commands, now).dropped;
    now += 4'000'000;
    silent = ruiwo_receive_rt(host, bus, now, 0, sensors).silent;  // nobody answers
  }
  EXPECT_EQ(silent, 2);
  // Once the queue is full nothing blocks: the loop reached silence in kMaxConsecutiveMisses
  // cycles, 2 motors dropped in each.
  EXPECT_EQ(now, static_cast<hal::TimeNs>(ruiwo::kMaxConsecutiveMisses) * 4'000'000);
  EXPECT_EQ(dropped, 2 * static_cast<int>(ruiwo::kMaxConsecutiveMisses));
}

TEST(CanopenIo, UnclaimedFramesAndSyncLast) {
  int fd[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd), 0);
  CanPort host = attach_can_port(fd[0], false), dev = attach_can_port(fd[1], false);
  std::array<canopen::DriveConfig, 2> cfg{};
  std::array<canopen::DriveState, 2> st{};
  cfg[0].node_id = 1;
  cfg[1].node_id = 2;
  can_frame f;
  for (int i = 0; i < 2; ++i) canopen::start_drive(cfg[i], st[i], 0, f);
  // Boot-up of node 2 and a stray heartbeat of node 9.
  f = can_frame{};
  f.can_id = 0x702;
  f.len = 1;
  ASSERT_EQ(send_rt(dev, f), DriverError::kOk);
  f.can_id = 0x709;
  ASSERT_EQ(send_rt(dev, f), DriverError::kOk);
  const CanopenReceiveReport r = canopen_receive_rt(host, cfg, st, 1000, 0);
  EXPECT_EQ(r.frames, 1);
  EXPECT_EQ(r.unclaimed, 1);
  EXPECT_EQ(st[1].phase, canopen::DrivePhase::kConfiguring);
  const std::array<canopen::DriveCommand, 2> cmds{};
  const CanopenSendReport s = canopen_send_rt(host, cfg, st, cmds, 2000);
  EXPECT_TRUE(s.sync_sent);
  EXPECT_EQ(s.sent, 2);  // node 2's first SDO write, then SYNC
  RxFrame rx;
  ASSERT_EQ(receive_rt(dev, rx), DriverError::kOk);
  EXPECT_EQ(rx.frame.can_id, 0x602u);
  ASSERT_EQ(receive_rt(dev, rx), DriverError::kOk);
  EXPECT_EQ(rx.frame.can_id, 0x080u);
  close(fd[0]);
  close(fd[1]);
}

}  // namespace
}  // namespace kuavo::drivers
