// Closed loop through everything: a toy plant (independent unit-inertia joints)
// bound to the emulated devices, the real drivers on the host side, and a
// joint-space PD controller. If any sign, offset, Jacobian or unit conversion
// disagreed between the firmware path and the wiring, the joints would not
// settle on their targets.
#include <gtest/gtest.h>

#include <cmath>
#include <sys/socket.h>
#include <unistd.h>

#include "controllers/model/model.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/cycle/canopen_io.h"
#include "drivers/cycle/ruiwo_io.h"
#include "drivers/emulator/plant_binding.h"
#include "drivers/ruiwo/ruiwo_bus.h"

namespace kuavo::drivers {
namespace {

constexpr double kInertia_kgm2 = 0.05;
constexpr hal::TimeNs kCycle_ns = 2'000'000;
constexpr double kDt_s = 2e-3;

struct SocketPair {
  int fd[2]{-1, -1};
  SocketPair() { EXPECT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd), 0); }
  ~SocketPair() {
    close(fd[0]);
    close(fd[1]);
  }
};

// A constant load on every joint (a stand-in for gravity). The controller
// cancels it with a feed-forward torque, so the joints reach their targets only
// if that torque arrives at the joint unchanged: a wrong sign, Jacobian or
// transpose leaves a steady error of (load mismatch) / kp.
double load_Nm(int joint) { return -(0.5 + 0.1 * (joint % 7)); }  // below every torque limit

void integrate(emulator::PlantJoints& plant, const std::array<double, model::kNumJoints>& tau, int first, int n) {
  for (int j = first; j < first + n; ++j) {
    plant.velocity_rad_s[j] += (tau[j] + load_Nm(j)) / kInertia_kgm2 * kDt_s;  // semi-implicit Euler
    plant.position_rad[j] += plant.velocity_rad_s[j] * kDt_s;
  }
}

TEST(PlantLoop, LegDrivesSettleOnJointTargetsThroughTheAnkleLinkage) {
  SocketPair sp;
  CanPort host = attach_can_port(sp.fd[0], false), dev = attach_can_port(sp.fd[1], false);
  emulator::LegWiring leg;
  leg.transmission = default_leg_transmission(true);
  leg.first_joint = model::kLeftLegFirst;
  std::array<canopen::DriveConfig, kLegActuators> cfg{};
  std::array<canopen::DriveState, kLegActuators> st{};
  emulator::Cia402Emulator emu;
  hal::TimeNs now = 0;
  for (int k = 0; k < kLegActuators; ++k) {
    leg.node_ids[k] = static_cast<std::uint8_t>(k + 1);
    cfg[k].node_id = leg.node_ids[k];
    cfg[k].counts_per_rev = 131072.0 * 36.0;
    cfg[k].rated_torque_Nm = 18.9;  // CK continuous torque (FACTS.md §2.5), per mille resolution 0.019 Nm
    cfg[k].torque_limit_Nm = 27.0;
    emulator::add_drive(emu, cfg[k]);
    can_frame f;
    canopen::start_drive(cfg[k], st[k], now, f);
    ASSERT_EQ(send_rt(host, f), DriverError::kOk);
  }
  emulator::PlantJoints plant;
  const std::array<double, 6> target{0.1, -0.1, -0.4, 0.8, -0.3, 0.12};
  std::array<hal::JointSample, kLegActuators> joints{};
  std::array<canopen::MotorSample, kLegActuators> motors{};
  std::array<double, kLegActuators> joint_tau{}, motor_tau{};
  hal::JointCommand pd;
  pd.mode = hal::JointMode::kPdTorque;
  pd.kp_Nm_per_rad = 50.0;
  pd.kd_Nm_s_per_rad = 2.0;

  for (int cycle = 0; cycle < 1500; ++cycle) {
    ASSERT_EQ(emulator::write_leg_drives(leg, plant, emu), DriverError::kOk);
    emulator::serve_rt(emu, dev, now);
    canopen_receive_rt(host, cfg, st, now, 0);
    for (int k = 0; k < kLegActuators; ++k) motors[k] = canopen::motor_sample(cfg[k], st[k]);
    (void)leg_joints_from_motors_rt(leg.transmission, motors, joints);
    bool all_valid = true;
    for (int k = 0; k < kLegActuators; ++k) {
      all_valid = all_valid && joints[k].valid;
      pd.position_ref_rad = target[k];
      pd.torque_ff_Nm = -load_Nm(leg.first_joint + k);
      joint_tau[k] = joints[k].valid ? joint_torque_command_Nm(pd, joints[k]) : 0.0;
    }
    if (all_valid) {
      ASSERT_EQ(leg_motor_torques_rt(leg.transmission, joints, joint_tau, motor_tau), DriverError::kOk);
    }
    std::array<canopen::DriveCommand, kLegActuators> cmds{};
    for (int k = 0; k < kLegActuators; ++k) cmds[k] = canopen::DriveCommand{true, all_valid ? motor_tau[k] : 0.0, 0.0};
    const CanopenSendReport sent = canopen_send_rt(host, cfg, st, cmds, now);
    ASSERT_TRUE(sent.sync_sent);
    ASSERT_EQ(sent.dropped + sent.failed, 0);
    std::array<double, model::kNumJoints> tau{};
    ASSERT_EQ(emulator::add_leg_torques(leg, plant, emu, tau), DriverError::kOk);
    integrate(plant, tau, leg.first_joint, kLegActuators);
    now += kCycle_ns;
  }
  for (int k = 0; k < kLegActuators; ++k) {
    EXPECT_EQ(st[k].error, DriverError::kOk) << k << ": " << to_string(st[k].error);
    EXPECT_NEAR(plant.position_rad[leg.first_joint + k], target[k], 2e-3) << "joint " << k;
    EXPECT_NEAR(joints[k].position_rad, plant.position_rad[leg.first_joint + k], 1e-4) << "joint " << k;
  }
}

TEST(PlantLoop, RuiwoArmSettlesOnTargetsWithSignsAndOffsets) {
  model::Model model;
  ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, model), model::ModelError::kOk);
  std::vector<ruiwo::MotorConfig> motors = ruiwo::default_motors(model);
  for (std::size_t i = 0; i < motors.size(); ++i) motors[i].zero_offset_rad = 0.05 * static_cast<double>(i % 3);
  ruiwo::Bus bus;
  std::string msg;
  ASSERT_EQ(ruiwo::build_bus(motors, bus, msg), DriverError::kOk) << msg;
  emulator::RuiwoEmulator emu;
  std::uint8_t ids[ruiwo::kMaxMotorsPerBus];
  for (int i = 0; i < bus.count; ++i) ids[i] = bus.motors[i].motor_id;
  emulator::init_ruiwo_emulator(emu, ids, bus.count);
  for (int i = 0; i < emu.count; ++i) emu.motors[i].enabled = true;
  SocketPair sp;
  CanPort host = attach_can_port(sp.fd[0], false), dev = attach_can_port(sp.fd[1], false);
  emulator::PlantJoints plant;
  hal::CommandFrame commands;
  hal::SensorFrame sensors;
  for (int i = 0; i < bus.count; ++i) {
    const ruiwo::MotorConfig& m = bus.motors[i];
    hal::JointCommand& c = commands.joints[m.joint];
    c.mode = hal::JointMode::kPdTorque;
    c.kp_Nm_per_rad = 20.0;
    c.kd_Nm_s_per_rad = 1.5;
    c.position_ref_rad = 0.5 * (m.position_min_rad + m.position_max_rad);
    c.torque_ff_Nm = -load_Nm(m.joint);
  }
  hal::TimeNs now = 0;
  for (int cycle = 0; cycle < 1500; ++cycle) {
    emulator::write_ruiwo_motors(bus, plant, emu);
    ASSERT_EQ(ruiwo_send_rt(host, bus, commands, now).sent, bus.count);
    emulator::serve_rt(emu, dev);
    ASSERT_EQ(ruiwo_receive_rt(host, bus, now + kCycle_ns, 0, sensors).silent, 0);
    std::array<double, model::kNumJoints> tau{};
    emulator::add_ruiwo_torques(bus, emu, tau);
    integrate(plant, tau, model::kLeftArmFirst, model::kNumJoints - model::kLeftArmFirst);
    now += kCycle_ns;
  }
  for (int i = 0; i < bus.count; ++i) {
    const int j = bus.motors[i].joint;
    EXPECT_NEAR(plant.position_rad[j], commands.joints[j].position_ref_rad, 2e-3) << "motor " << i;
    EXPECT_NEAR(sensors.joints[j].position_rad, plant.position_rad[j], 1e-3) << "motor " << i;
  }
}

}  // namespace
}  // namespace kuavo::drivers
