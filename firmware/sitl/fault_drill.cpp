#include "firmware/sitl/fault_drill.h"

#include <cstring>

#include "drivers/emulator/bus_fault.h"
#include "drivers/emulator/fault_injection.h"
#include "rtos_shim/args.h"

namespace kuavo::firmware::sitl {
namespace {

namespace emu = drivers::emulator;

constexpr const char* kNames[kFaultDrillCount] = {"silent-leg-drive", "silent-arm-motor", "bus-off",
                                                  "frame-loss-1pct",  "imu-dropout",      "starved-planner"};
// The drills' targets, by joint (model order): the left knee (leg slot 3) and the left elbow
// (zarm_l4). Looked up in the drivers configuration, so another bus plan moves them along.
constexpr int kLeftKnee = 3;
constexpr int kLeftElbow = model::kLeftArmFirst + 3;
constexpr double kFrameLossProbability = 0.01;

// The CANopen bus and drive index driving `slot`; false if none does.
bool find_drive(FirmwareLoop& loop, int slot, std::size_t& bus, int& index) {
  for (std::size_t b = 0; b < loop.buses(); ++b) {
    if (loop.drives(b) == nullptr) continue;
    const std::vector<int>& slots = loop.io().canopen[b].slot;
    for (std::size_t i = 0; i < slots.size(); ++i) {
      if (slots[i] == slot) return bus = b, index = static_cast<int>(i), true;
    }
  }
  return false;
}

emu::FaultInjection& faults_of(FirmwareLoop& loop, std::size_t b) {
  return loop.ruiwo(b) != nullptr ? loop.ruiwo(b)->faults : loop.drives(b)->faults;
}

}  // namespace

const char* to_string(FaultDrill d) {
  const auto i = static_cast<int>(d);
  return i >= 0 && i < kFaultDrillCount ? kNames[i] : "?";
}

bool parse_fault_drill(const char* text, FaultDrill& out) {
  for (int i = 0; i < kFaultDrillCount; ++i) {
    if (std::strcmp(text, kNames[i]) == 0) return out = static_cast<FaultDrill>(i), true;
  }
  return false;
}

bool parse_injection(const char* text, Injection& out) {
  if (text == nullptr) return false;
  const char* at = std::strchr(text, '@');
  if (at == nullptr || std::strchr(at + 1, '@') != nullptr) return false;
  Injection in;
  if (!parse_fault_drill(std::string(text, at).c_str(), in.kind)) return false;
  if (!args::parse_number(at + 1, 0.0, kMaxInjectAt_s, in.at_s)) return false;  // refuses nan, inf, "-1", ""
  out = in;
  return true;
}

bool arm_fault_drill(FirmwareLoop& loop, FaultDrill d, std::string& target, std::string& message) {
  const model::Model& m = loop.model();
  std::size_t bus = 0;
  int index = 0;
  switch (d) {
    case FaultDrill::kSilentLegDrive:
    case FaultDrill::kBusOff: {
      if (!find_drive(loop, kLeftKnee, bus, index)) return message = "no drive on the left knee", false;
      const std::string& interface = loop.drivers_config().plan.buses[bus].interface;
      if (d == FaultDrill::kBusOff) {
        target = interface + " (" + model::joint_name(m, kLeftKnee) + "'s bus)";
        if (!emu::inject_bus_fault(faults_of(loop, bus), loop.device_port(bus), emu::BusFault::kBusOff)) {
          return message = "the emulator of " + interface + " refused the bus-off", false;
        }
        return true;
      }
      const std::uint8_t node = loop.drives(bus)->drives[index].config.node_id;
      target = std::string(model::joint_name(m, kLeftKnee)) + " drive, node " + std::to_string(node) + " on " + interface;
      if (!emu::set_drive_silent(*loop.drives(bus), node, true)) return message = "the emulator refused to silence " + target, false;
      return true;
    }
    case FaultDrill::kSilentArmMotor:
      for (std::size_t b = 0; b < loop.buses(); ++b) {
        if (loop.ruiwo(b) == nullptr) continue;
        for (int i = 0; i < loop.ruiwo(b)->count; ++i) {
          const drivers::ruiwo::MotorConfig& mc = loop.io().ruiwo[b].motors[i];
          if (mc.joint != kLeftElbow) continue;
          target = std::string(model::joint_name(m, kLeftElbow)) + " Ruiwo motor, id " + std::to_string(mc.motor_id) + " on " +
                   loop.drivers_config().plan.buses[b].interface;
          if (!emu::set_silent(*loop.ruiwo(b), mc.motor_id, true)) return message = "the emulator refused to silence " + target, false;
          return true;
        }
      }
      return message = "no Ruiwo motor on the left elbow", false;
    case FaultDrill::kFrameLoss1Pct:
      target = "every bus";
      for (std::size_t b = 0; b < loop.buses(); ++b) {
        if (!emu::set_frame_faults(faults_of(loop, b), kFrameLossProbability, 0.0)) {
          return message = "the emulator of " + loop.drivers_config().plan.buses[b].interface + " refused frame loss", false;
        }
      }
      return true;
    case FaultDrill::kImuDropout:
      target = "IMU";
      loop.stop_imu();
      return true;
    case FaultDrill::kStarvedPlanner:
      target = "planning task";
      loop.stop_planner();
      return true;
  }
  return message = "unknown fault drill", false;
}

}  // namespace kuavo::firmware::sitl
