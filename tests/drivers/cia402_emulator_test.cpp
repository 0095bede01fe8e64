// Firmware-in-the-loop, CANopen side: the real drive supervisors on one end
// of a socketpair, emulated CiA 402 drives on the other. Boot to torque,
// disabling, a silent drive, a drive fault and its reset, frame count vs the
// load model, and no heap in an operational cycle.
#include <gtest/gtest.h>

#include <array>

#include "drivers/bus/bus_plan.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/cycle/canopen_io.h"
#include "drivers/emulator/cia402_emulator.h"
#include "tests/drivers/socketpair_wire.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers {
namespace {

using test_support::Wire;

class CanopenLoop : public ::testing::Test {
 protected:
  static constexpr int kDrives = 3;
  std::array<canopen::DriveConfig, kDrives> cfg{};
  std::array<canopen::DriveState, kDrives> st{};
  std::array<canopen::DriveCommand, kDrives> cmd{};
  emulator::Cia402Emulator emu;
  Wire wire;
  hal::TimeNs now = 0;
  static constexpr hal::TimeNs kCycle_ns = 2'000'000;

  void SetUp() override {
    for (int i = 0; i < kDrives; ++i) {
      cfg[i].node_id = static_cast<std::uint8_t>(i + 1);
      cfg[i].counts_per_rev = 131072.0 * 18.0;
      cfg[i].rated_torque_Nm = 88.9;
      cfg[i].torque_limit_Nm = 127.0;
      emulator::add_drive(emu, cfg[i]);
      can_frame f;
      canopen::start_drive(cfg[i], st[i], now, f);
      EXPECT_EQ(send_rt(wire.host, f), DriverError::kOk);
    }
  }
  // One control cycle as the firmware runs it.
  void cycle() {
    emulator::serve_rt(emu, wire.device, now);
    canopen_receive_rt(wire.host, cfg, st, now, 0);
    canopen_send_rt(wire.host, cfg, st, cmd, now);
    now += kCycle_ns;
  }
  int cycles_until_enabled(int limit) {
    for (int k = 0; k < limit; ++k) {
      cycle();
      bool all = true;
      for (int i = 0; i < kDrives; ++i)
        all = all && st[i].phase == canopen::DrivePhase::kOperational &&
              st[i].power == canopen::Cia402State::kOperationEnabled;
      if (all) return k;
    }
    return -1;
  }
};

TEST_F(CanopenLoop, BootConfigureEnableAndTorqueFlow) {
  for (int i = 0; i < kDrives; ++i) {
    cmd[i].enable = true;
    cmd[i].torque_Nm = 10.0 * (i + 1);
    emu.drives[i].position_rad = 0.2 * i;
    emu.drives[i].velocity_rad_s = -1.0;
  }
  const int k = cycles_until_enabled(500);
  ASSERT_GE(k, 0) << "phase " << int(st[0].phase) << " error " << to_string(st[0].error);
  for (int n = 0; n < 5; ++n) cycle();
  for (int i = 0; i < kDrives; ++i) {
    EXPECT_EQ(st[i].error, DriverError::kOk) << to_string(st[i].error);
    EXPECT_EQ(emu.drives[i].sdo_writes, static_cast<std::uint32_t>(st[i].config.count));
    EXPECT_EQ(emu.drives[i].mode, canopen::kModeCyclicSyncTorque);
    EXPECT_NEAR(emulator::drive_torque_Nm(emu.drives[i]), 10.0 * (i + 1), 88.9 / 1000);
    const canopen::MotorSample s = canopen::motor_sample(cfg[i], st[i]);
    EXPECT_TRUE(s.valid);
    EXPECT_NEAR(s.position_rad, 0.2 * i, 1e-5);
    EXPECT_NEAR(s.velocity_rad_s, -1.0, 1e-5);
    EXPECT_NEAR(s.torque_Nm, 10.0 * (i + 1), 88.9 / 1000);
  }
}

TEST_F(CanopenLoop, DisablingRemovesTorqueAtTheDrive) {
  for (auto& c : cmd) {
    c.enable = true;
    c.torque_Nm = 5.0;
  }
  ASSERT_GE(cycles_until_enabled(500), 0);
  for (auto& c : cmd) c.enable = false;
  cycle();
  cycle();
  for (int i = 0; i < kDrives; ++i) {
    EXPECT_EQ(emulator::drive_torque_Nm(emu.drives[i]), 0.0);
    EXPECT_EQ(emu.drives[i].power, canopen::Cia402State::kSwitchOnDisabled);
  }
}

TEST_F(CanopenLoop, SilentDriveGoesStaleThenLosesHeartbeat) {
  for (auto& c : cmd) {
    c.enable = true;
    c.torque_Nm = 5.0;
  }
  ASSERT_GE(cycles_until_enabled(500), 0);
  cycle();
  ASSERT_NEAR(emulator::drive_torque_Nm(emu.drives[1]), 5.0, 0.1);
  EXPECT_FALSE(emulator::set_drive_silent(emu, 2, true)) << "disarmed injection must be refused";
  emulator::arm_fault_injection(emu.faults, 3);
  ASSERT_TRUE(emulator::set_drive_silent(emu, 2, true));
  int stale_after = -1;
  for (int k = 0; k < 60 && st[1].phase != canopen::DrivePhase::kFailed; ++k) {
    cycle();
    if (stale_after < 0 && !canopen::motor_sample(cfg[1], st[1]).valid) stale_after = k;
  }
  EXPECT_GE(stale_after, 0);
  EXPECT_LE(stale_after * kCycle_ns, 10'000'000) << "silent drive must be flagged within 10 ms";
  EXPECT_EQ(st[1].phase, canopen::DrivePhase::kFailed);
  EXPECT_EQ(st[1].error, DriverError::kHeartbeatLost);
  EXPECT_EQ(st[0].error, DriverError::kOk);
  // A drive that only lost its transmitter still listens: the master's safe
  // RPDO1 takes its torque away instead of leaving the last target latched.
  cycle();
  EXPECT_EQ(emulator::drive_torque_Nm(emu.drives[1]), 0.0);
  EXPECT_EQ(emu.drives[1].power, canopen::Cia402State::kSwitchOnDisabled);
}

TEST_F(CanopenLoop, DriveFaultIsReportedAndResetByEdge) {
  for (auto& c : cmd) {
    c.enable = true;
    c.torque_Nm = 4.0;
  }
  ASSERT_GE(cycles_until_enabled(500), 0);
  emulator::arm_fault_injection(emu.faults, 4);
  ASSERT_TRUE(emulator::inject_drive_fault(emu, 1, 0x2310));
  cycle();  // the drive reports the fault at the SYNC; the master answers with a reset edge
  EXPECT_EQ(st[0].power, canopen::Cia402State::kFault);
  EXPECT_EQ(st[0].error, DriverError::kDriveFault);
  EXPECT_EQ(st[0].tpdo2.error_code, 0x2310);
  EXPECT_EQ(emulator::drive_torque_Nm(emu.drives[0]), 0.0);
  // The master's fault reset brings it back (the emulated fault is not sticky).
  st[0].error = DriverError::kOk;
  ASSERT_GE(cycles_until_enabled(20), 0) << canopen::to_string(st[0].power);
  EXPECT_EQ(st[0].control.fault_resets, 1);
  cycle();  // torque follows one cycle after the drive reports operation enabled
  EXPECT_NEAR(emulator::drive_torque_Nm(emu.drives[0]), 4.0, 0.1);
}

TEST_F(CanopenLoop, FrameCountMatchesTheBusLoadModel) {
  // The load model must describe what the code really sends: count one
  // second of operational traffic in both directions.
  for (auto& c : cmd) c.enable = true;
  ASSERT_GE(cycles_until_enabled(500), 0);
  for (int k = 0; k < 50; ++k) cycle();  // let start-up traffic settle
  const std::uint64_t host_before = wire.host.stats.tx_frames, dev_before = wire.device.stats.tx_frames;
  const int cycles = static_cast<int>(1'000'000'000 / kCycle_ns);
  for (int k = 0; k < cycles; ++k) cycle();
  const double measured = static_cast<double>(wire.host.stats.tx_frames - host_before +
                                              wire.device.stats.tx_frames - dev_before);
  BusPlan plan;
  BusConfig bus;
  bus.interface = "can0";
  bus.cycle_rate_hz = 1e9 / kCycle_ns;
  bus.heartbeat_rate_hz = 1000.0 / cfg[0].heartbeat_period_ms;
  plan.buses.push_back(bus);
  for (int i = 0; i < kDrives; ++i) plan.devices.push_back({0, DeviceKind::kCia402Drive, cfg[i].node_id, i});
  const double modelled = compute_bus_load(plan).frames_per_s[0];
  EXPECT_NEAR(measured, modelled, 0.01 * modelled) << "measured " << measured << " modelled " << modelled;
}

TEST_F(CanopenLoop, OperationalCycleDoesNotAllocate) {
  for (auto& c : cmd) c.enable = true;
  ASSERT_GE(cycles_until_enabled(500), 0);
  test::AllocTrap trap;
  for (int k = 0; k < 100; ++k) cycle();
  EXPECT_EQ(trap.count(), 0u);
}

}  // namespace
}  // namespace kuavo::drivers
