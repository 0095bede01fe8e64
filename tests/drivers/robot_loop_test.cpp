// The whole default robot through the configuration path: DriversConfig ->
// seven buses (socketpairs) -> Ruiwo buses and CiA 402 supervisors on the host,
// emulated boards and drives on the far side bound to a static plant pose.
// After bring-up every one of the 28 joint samples must report that pose.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "controllers/model/model.h"
#include "drivers/config/drivers_config.h"
#include "drivers/cycle/canopen_io.h"
#include "drivers/cycle/ruiwo_io.h"
#include "drivers/emulator/plant_binding.h"
#include "tests/drivers/socketpair_wire.h"

namespace kuavo::drivers {
namespace {

struct CanopenBus {
  std::vector<canopen::DriveConfig> cfg;
  std::vector<canopen::DriveState> st;
  std::vector<canopen::DriveCommand> cmd;
  std::vector<int> slot;
  emulator::Cia402Emulator emu;
};

struct RuiwoSide {
  ruiwo::Bus bus;
  emulator::RuiwoEmulator emu;
};

TEST(RobotLoop, DefaultRobotSensesThePlantPoseOnAll28Joints) {
  model::Model model;
  ASSERT_EQ(model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, model), model::ModelError::kOk);
  const DriversConfig config = default_drivers_config(model);
  BusLoadReport report;
  std::string msg;
  ASSERT_EQ(validate_drivers_config(config, report, msg), DriverError::kOk) << msg;

  const int n_buses = static_cast<int>(config.plan.buses.size());
  std::vector<std::unique_ptr<test_support::Wire>> wires;
  std::vector<std::unique_ptr<CanopenBus>> canopen(n_buses);
  std::vector<std::unique_ptr<RuiwoSide>> ruiwo(n_buses);
  for (int b = 0; b < n_buses; ++b) {
    wires.push_back(std::make_unique<test_support::Wire>());
    const std::vector<ruiwo::MotorConfig> motors = ruiwo_motors_on_bus(config, b);
    if (!motors.empty()) {
      ruiwo[b] = std::make_unique<RuiwoSide>();
      ASSERT_EQ(ruiwo::build_bus(motors, ruiwo[b]->bus, msg), DriverError::kOk) << msg;
      std::uint8_t ids[ruiwo::kMaxMotorsPerBus];
      for (int i = 0; i < ruiwo[b]->bus.count; ++i) ids[i] = ruiwo[b]->bus.motors[i].motor_id;
      emulator::init_ruiwo_emulator(ruiwo[b]->emu, ids, ruiwo[b]->bus.count);
      continue;
    }
    canopen[b] = std::make_unique<CanopenBus>();
    for (const DriveEntry& e : config.drives) {
      if (e.bus != b) continue;
      canopen[b]->cfg.push_back(e.config);
      canopen[b]->st.emplace_back();
      canopen[b]->cmd.push_back(canopen::DriveCommand{true, 0.0, 0.0});
      canopen[b]->slot.push_back(e.slot);
      emulator::add_drive(canopen[b]->emu, e.config);
      can_frame f;
      canopen::start_drive(e.config, canopen[b]->st.back(), 0, f);
      ASSERT_EQ(send_rt(wires[b]->host, f), DriverError::kOk);
    }
  }

  // A pose inside every joint's limits.
  emulator::PlantJoints plant;
  for (int j = 0; j < model::kNumJoints; ++j) {
    const double lo = model.limits.position_min_rad[j], hi = model.limits.position_max_rad[j];
    plant.position_rad[j] = lo + (0.3 + 0.02 * (j % 10)) * (hi - lo);
  }
  std::array<emulator::LegWiring, 2> legs;
  for (int side = 0; side < 2; ++side) {
    legs[side].transmission = config.legs[side];
    legs[side].first_joint = side == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    for (const DriveEntry& e : config.drives) {
      const int k = e.slot - legs[side].first_joint;
      if (k >= 0 && k < kLegActuators) legs[side].node_ids[k] = e.config.node_id;
    }
  }

  hal::SensorFrame sensors;
  hal::CommandFrame commands;  // all disabled: sensing only
  hal::TimeNs now = 0;
  for (int cycle = 0; cycle < 300; ++cycle) {
    for (int b = 0; b < n_buses; ++b) {
      test_support::Wire& w = *wires[b];
      if (ruiwo[b]) {
        if (cycle % 2 != 0) continue;  // 250 Hz buses run every other 2 ms cycle
        emulator::write_ruiwo_motors(ruiwo[b]->bus, plant, ruiwo[b]->emu);
        ruiwo_receive_rt(w.host, ruiwo[b]->bus, now, 0, sensors);
        ruiwo_send_rt(w.host, ruiwo[b]->bus, commands, now);
        emulator::serve_rt(ruiwo[b]->emu, w.device);
        continue;
      }
      CanopenBus& c = *canopen[b];
      for (const auto& leg : legs) ASSERT_EQ(emulator::write_leg_drives(leg, plant, c.emu), DriverError::kOk);
      for (int i = 0; i < c.emu.count; ++i) {  // shoulder pitch: 1:1
        const int slot = c.slot[i];
        if (slot == model::kLeftArmFirst || slot == model::kRightArmFirst) {
          c.emu.drives[i].position_rad = plant.position_rad[slot];
        }
      }
      emulator::serve_rt(c.emu, w.device, now);
      canopen_receive_rt(w.host, c.cfg, c.st, now, 0);
      canopen_send_rt(w.host, c.cfg, c.st, c.cmd, now);
    }
    now += 2'000'000;
  }

  // Legs and shoulders: motor samples -> joints.
  for (int side = 0; side < 2; ++side) {
    std::array<canopen::MotorSample, kLegActuators> motors{};
    for (int b = 0; b < n_buses; ++b) {
      if (!canopen[b]) continue;
      for (std::size_t i = 0; i < canopen[b]->cfg.size(); ++i) {
        const int k = canopen[b]->slot[i] - legs[side].first_joint;
        if (k >= 0 && k < kLegActuators) motors[k] = canopen::motor_sample(canopen[b]->cfg[i], canopen[b]->st[i]);
        if (side == 0 && (canopen[b]->slot[i] == model::kLeftArmFirst || canopen[b]->slot[i] == model::kRightArmFirst)) {
          const canopen::MotorSample m = canopen::motor_sample(canopen[b]->cfg[i], canopen[b]->st[i]);
          hal::JointSample& j = sensors.joints[canopen[b]->slot[i]];
          j.position_rad = m.position_rad;
          j.valid = m.valid;
        }
      }
    }
    std::array<hal::JointSample, kLegActuators> joints{};
    ASSERT_EQ(leg_joints_from_motors_rt(legs[side].transmission, motors, joints), DriverError::kOk);
    for (int k = 0; k < kLegActuators; ++k) sensors.joints[legs[side].first_joint + k] = joints[k];
  }
  for (int b = 0; b < n_buses; ++b) {
    if (!canopen[b]) continue;
    for (const canopen::DriveState& s : canopen[b]->st) {
      EXPECT_EQ(s.phase, canopen::DrivePhase::kOperational);
      EXPECT_EQ(s.error, DriverError::kOk) << to_string(s.error);
    }
  }
  for (int j = 0; j < model::kNumJoints; ++j) {
    EXPECT_TRUE(sensors.joints[j].valid) << model::joint_name(model, j);
    // Ruiwo: 16-bit over 25 rad; drives: 2^17 x ratio counts per turn.
    EXPECT_NEAR(sensors.joints[j].position_rad, plant.position_rad[j], 5e-4) << model::joint_name(model, j);
  }
}

}  // namespace
}  // namespace kuavo::drivers
