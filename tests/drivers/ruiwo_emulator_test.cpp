// Firmware-in-the-loop, Ruiwo side: the real driver code on one end of a
// socketpair, emulated Ruiwo boards on the other. Normal cycle, fault injection
// refused while disarmed, a silent motor, 1 % frame loss, corrupted replies,
// bus-off, frame count vs the load model, and no heap in a cycle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "controllers/model/model.h"
#include "drivers/bus/bus_plan.h"
#include "drivers/cycle/ruiwo_io.h"
#include "drivers/emulator/bus_fault.h"
#include "drivers/emulator/ruiwo_emulator.h"
#include "drivers/ruiwo/ruiwo_bus.h"
#include "tests/drivers/socketpair_wire.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers {
namespace {

using test_support::Wire;

class RuiwoLoop : public ::testing::Test {
 protected:
  model::Model model;
  ruiwo::Bus bus;
  emulator::RuiwoEmulator emu;
  Wire wire;
  hal::CommandFrame commands;
  hal::SensorFrame sensors;
  hal::TimeNs now = 0;

  void SetUp() override {
    ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, model), model::ModelError::kOk);
    std::string msg;
    std::vector<ruiwo::MotorConfig> motors = ruiwo::default_motors(model);
    motors[2].zero_offset_rad = 0.3;  // one motor with an offset
    ASSERT_EQ(ruiwo::build_bus(motors, bus, msg), DriverError::kOk) << msg;
    std::uint8_t ids[ruiwo::kMaxMotorsPerBus];
    for (int i = 0; i < bus.count; ++i) ids[i] = bus.motors[i].motor_id;
    emulator::init_ruiwo_emulator(emu, ids, bus.count);
    // Enable every motor (special frame; each answered with a status).
    for (int i = 0; i < bus.count; ++i) {
      can_frame f;
      ruiwo::encode_special_rt(bus.motors[i].motor_id, ruiwo::SpecialCommand::kEnable, f);
      ASSERT_EQ(send_rt(wire.host, f), DriverError::kOk);
    }
    emulator::serve_rt(emu, wire.device);
    drain();
  }
  void drain() {
    RxFrame rx;
    can_frame f;
    while (receive_rt(wire.host, rx) == DriverError::kOk) {
      if (as_classic(rx, f)) (void)ruiwo::handle_reply_rt(bus, f, now, sensors);
    }
  }
  // One 4 ms cycle as the firmware runs it: commands out, the emulated boards
  // answer, and at the next cycle start the replies come in and timeouts are checked.
  int cycle() {
    const RuiwoSendReport sent = ruiwo_send_rt(wire.host, bus, commands, now);
    EXPECT_EQ(sent.sent, bus.count);
    emulator::serve_rt(emu, wire.device);
    now += 4'000'000;
    return ruiwo_receive_rt(wire.host, bus, now, 0, sensors).silent;
  }
};

TEST_F(RuiwoLoop, JointStateAndTorqueFlowThroughTheRealCodec) {
  // Plant: put every joint at a known angle (motor side through sign/offset).
  for (int i = 0; i < bus.count; ++i) {
    const ruiwo::MotorConfig& m = bus.motors[i];
    const double q = 0.1 * (i + 1) * (i % 2 ? -1 : 1);
    emu.motors[i].position_rad = ruiwo::motor_position_rad(m, std::clamp(q, m.position_min_rad, m.position_max_rad));
    emu.motors[i].velocity_rad_s = m.sign * 0.5;
  }
  hal::JointCommand& c = commands.joints[bus.motors[3].joint];
  c.mode = hal::JointMode::kPdTorque;
  c.kp_Nm_per_rad = 20.0;
  c.kd_Nm_s_per_rad = 1.0;
  c.torque_ff_Nm = 2.0;
  c.position_ref_rad = -0.5;
  ASSERT_EQ(cycle(), 0);
  for (int i = 0; i < bus.count; ++i) {
    const ruiwo::MotorConfig& m = bus.motors[i];
    const hal::JointSample& s = sensors.joints[m.joint];
    EXPECT_TRUE(s.valid) << i;
    EXPECT_NEAR(s.position_rad, ruiwo::joint_position_rad(m, emu.motors[i].position_rad), 25.0 / 65535) << i;
    EXPECT_NEAR(s.velocity_rad_s, 0.5, 20.0 / 4095) << i;
  }
  // Motor 3's PD law, evaluated by the board, seen in the joint frame.
  const ruiwo::MotorConfig& m3 = bus.motors[3];
  const double q = ruiwo::joint_position_rad(m3, emu.motors[3].position_rad);
  const double expected_joint_tau = 20.0 * (-0.5 - q) + 1.0 * (0.0 - 0.5) + 2.0;
  EXPECT_NEAR(m3.sign * emulator::motor_torque_Nm(emu.motors[3]), expected_joint_tau, 0.1);
}

TEST_F(RuiwoLoop, FaultInjectionIsRefusedWhileDisarmed) {
  EXPECT_FALSE(emulator::set_silent(emu, 0x05, true));
  EXPECT_FALSE(emulator::set_frame_faults(emu.faults, 0.5, 0.0));
  for (int k = 0; k < 20; ++k) ASSERT_EQ(cycle(), 0);
  EXPECT_EQ(emu.replies_dropped, 0u);
}

TEST_F(RuiwoLoop, SilentMotorIsDetectedWithinFourCycles) {
  emulator::arm_fault_injection(emu.faults, 1);
  ASSERT_TRUE(emulator::set_silent(emu, 0x05, true));
  const int joint = bus.motors[bus.index_of_id[0x05]].joint;
  int cycles = 0;
  while (cycle() == 0 && cycles < 10) ++cycles;
  EXPECT_EQ(cycles, static_cast<int>(ruiwo::kMaxConsecutiveMisses) - 1);  // the fourth reports it: 16 ms < 20 ms
  EXPECT_EQ(ruiwo::kMaxConsecutiveMisses, 4u);
  EXPECT_FALSE(sensors.joints[joint].valid);
  for (int i = 0; i < bus.count; ++i) {
    EXPECT_EQ(bus.state[i].silent, bus.motors[i].motor_id == 0x05) << i;
  }
}

TEST_F(RuiwoLoop, OnePercentFrameLossIsToleratedAndCounted) {
  emulator::arm_fault_injection(emu.faults, 42);
  ASSERT_TRUE(emulator::set_frame_faults(emu.faults, 0.01, 0.0));
  const int cycles = 2000;
  int silent_cycles = 0;
  for (int k = 0; k < cycles; ++k) silent_cycles += cycle() > 0;
  std::uint32_t misses = 0;
  for (int i = 0; i < bus.count; ++i) misses += bus.state[i].total_misses;
  EXPECT_EQ(misses, emu.replies_dropped);
  const double rate = static_cast<double>(misses) / (cycles * bus.count);
  EXPECT_GT(rate, 0.005);
  EXPECT_LT(rate, 0.02);
  EXPECT_EQ(silent_cycles, 0);
}

TEST_F(RuiwoLoop, CorruptedRepliesNeverYieldNonFiniteSamples) {
  emulator::arm_fault_injection(emu.faults, 9);
  ASSERT_TRUE(emulator::set_frame_faults(emu.faults, 0.0, 0.2));
  for (int k = 0; k < 500; ++k) cycle();
  for (const hal::JointSample& s : sensors.joints) {
    EXPECT_TRUE(std::isfinite(s.position_rad) && std::isfinite(s.velocity_rad_s) && std::isfinite(s.torque_Nm));
  }
  EXPECT_GT(bus.unknown_replies, 0u);  // flips in byte 0 give IDs not on the bus
}

TEST_F(RuiwoLoop, BusOffStopsTransmissionUntilCleared) {
  EXPECT_FALSE(emulator::inject_bus_fault(emu.faults, wire.device, emulator::BusFault::kBusOff));
  emulator::arm_fault_injection(emu.faults, 5);
  ASSERT_TRUE(emulator::inject_bus_fault(emu.faults, wire.device, emulator::BusFault::kBusOff));
  RxFrame rx;
  EXPECT_EQ(receive_rt(wire.host, rx), DriverError::kErrorFrame);
  EXPECT_TRUE(wire.host.health.bus_off);
  can_frame f;
  ruiwo::encode_command_rt(bus, 0, commands.joints[bus.motors[0].joint], f);
  EXPECT_EQ(send_rt(wire.host, f), DriverError::kBusOff);
  // No command reaches the motors, so every motor goes silent on schedule.
  int silent = 0;
  for (int k = 0; k < static_cast<int>(ruiwo::kMaxConsecutiveMisses); ++k) {
    for (int i = 0; i < bus.count; ++i) {
      ruiwo::encode_command_rt(bus, i, commands.joints[bus.motors[i].joint], f);
      if (send_rt(wire.host, f) == DriverError::kOk) ADD_FAILURE() << "sent while bus-off";
      ruiwo::note_sent_rt(bus, i, now);
    }
    now += 4'000'000;
    silent = ruiwo::check_timeouts_rt(bus, now, sensors);
  }
  EXPECT_EQ(silent, bus.count);
  ASSERT_TRUE(emulator::inject_bus_fault(emu.faults, wire.device, emulator::BusFault::kRestarted));
  EXPECT_EQ(receive_rt(wire.host, rx), DriverError::kErrorFrame);
  clear_bus_off(wire.host.health);
  EXPECT_EQ(cycle(), 0);  // replies resume
}

TEST_F(RuiwoLoop, FrameCountMatchesTheBusLoadModel) {
  const std::uint64_t host_before = wire.host.stats.tx_frames, dev_before = wire.device.stats.tx_frames;
  for (int k = 0; k < 250; ++k) ASSERT_EQ(cycle(), 0);  // one second at 250 Hz
  const double measured = static_cast<double>(wire.host.stats.tx_frames - host_before +
                                              wire.device.stats.tx_frames - dev_before);
  BusPlan plan;
  BusConfig b;
  b.interface = "can0";
  b.cycle_rate_hz = 250.0;
  plan.buses.push_back(b);
  for (int i = 0; i < bus.count; ++i) plan.devices.push_back({0, DeviceKind::kRuiwoMotor, bus.motors[i].motor_id, bus.motors[i].joint});
  EXPECT_DOUBLE_EQ(measured, compute_bus_load(plan).frames_per_s[0]);
}

TEST_F(RuiwoLoop, CycleWithFrameIoDoesNotAllocate) {
  cycle();
  test::AllocTrap trap;
  for (int k = 0; k < 50; ++k) cycle();
  EXPECT_EQ(trap.count(), 0u) << "first allocation " << trap.first_size_bytes() << " bytes";
}

}  // namespace
}  // namespace kuavo::drivers
