#include "drivers/bus/bus_plan.h"

#include <cmath>
#include <cstdio>

#include "controllers/model/model_tables.h"
#include "drivers/bus/bus_load.h"

namespace kuavo::drivers {

namespace {

// Bus time per second used by one device, microseconds.
double device_us_per_s(const BusConfig& bus, const DeviceConfig& d) {
  const double r = bus.bitrate_bps;
  switch (d.kind) {
    case DeviceKind::kRuiwoMotor:
      return bus.cycle_rate_hz * 2.0 * classic_frame_time_us(8, false, r);
    case DeviceKind::kCia402Drive:
      return bus.cycle_rate_hz * (2.0 * classic_frame_time_us(8, false, r) +
                                  classic_frame_time_us(7, false, r)) +
             bus.heartbeat_rate_hz * classic_frame_time_us(1, false, r);
  }
  return 0.0;
}

double device_frames_per_s(const BusConfig& bus, const DeviceConfig& d) {
  return d.kind == DeviceKind::kRuiwoMotor ? 2.0 * bus.cycle_rate_hz
                                           : 3.0 * bus.cycle_rate_hz + bus.heartbeat_rate_hz;
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f %%", x * 100.0);
  return buf;
}

}  // namespace

BusLoadReport compute_bus_load(const BusPlan& plan) {
  BusLoadReport rep;
  rep.load.assign(plan.buses.size(), 0.0);
  rep.frames_per_s.assign(plan.buses.size(), 0.0);
  std::vector<bool> has_canopen(plan.buses.size(), false);
  for (const DeviceConfig& d : plan.devices) {
    if (d.bus < 0 || d.bus >= static_cast<int>(plan.buses.size())) continue;
    const BusConfig& bus = plan.buses[d.bus];
    rep.load[d.bus] += device_us_per_s(bus, d) * 1e-6;
    rep.frames_per_s[d.bus] += device_frames_per_s(bus, d);
    if (d.kind == DeviceKind::kCia402Drive) has_canopen[d.bus] = true;
  }
  for (std::size_t b = 0; b < plan.buses.size(); ++b) {
    if (!has_canopen[b]) continue;
    const BusConfig& bus = plan.buses[b];  // one SYNC (0 bytes) per cycle
    rep.load[b] += bus.cycle_rate_hz * classic_frame_time_us(0, false, bus.bitrate_bps) * 1e-6;
    rep.frames_per_s[b] += bus.cycle_rate_hz;
  }
  return rep;
}

namespace {

// Physical ranges of a bus's numbers (outside them a value is a typing error or corruption):
// - nominal bitrate: ISO 11898-1 classic CAN (and FD's arbitration phase) runs 10 kbit/s..1 Mbit/s;
// - FD data phase: 8 Mbit/s is the fastest CAN FD transceivers are specified for;
constexpr double kMinBitrate_bps = 10e3, kMaxBitrate_bps = 1e6, kMaxDataBitrate_bps = 8e6;
// - cycle rate: the 500 Hz control task is the only sender; 1 Hz..1 kHz leaves the load check
//   to refuse a too-fast bus with its figure (the cycle period is a u32 count of µs);
constexpr double kMinCycleRate_hz = 1.0, kMaxCycleRate_hz = 1000.0;
// - heartbeat: the CiA 301 producer time (0x1017) is a u16 count of ms, 1..65535 ms.
constexpr double kMinHeartbeatRate_hz = 1000.0 / 65535.0, kMaxHeartbeatRate_hz = 1000.0;

}  // namespace

DriverError check_bus_plan(const BusPlan& plan, BusLoadReport& report, std::string& message) {
  for (std::size_t b = 0; b < plan.buses.size(); ++b) {
    const BusConfig& bus = plan.buses[b];
    if (bus.interface.empty() || !(bus.bitrate_bps > 0) || !(bus.cycle_rate_hz > 0) ||
        !(bus.heartbeat_rate_hz >= 0) || (bus.fd && !(bus.data_bitrate_bps >= bus.bitrate_bps))) {
      message = "bus " + std::to_string(b) + " '" + bus.interface +
                "': empty name, non-positive bitrate or rate, or FD data rate below nominal";
      return DriverError::kBadConfig;
    }
    if (!(bus.bitrate_bps >= kMinBitrate_bps && bus.bitrate_bps <= kMaxBitrate_bps) ||
        (bus.fd && !(bus.data_bitrate_bps <= kMaxDataBitrate_bps)) ||
        !(bus.cycle_rate_hz >= kMinCycleRate_hz && bus.cycle_rate_hz <= kMaxCycleRate_hz) ||
        !(bus.heartbeat_rate_hz == 0.0 ||
          (bus.heartbeat_rate_hz >= kMinHeartbeatRate_hz && bus.heartbeat_rate_hz <= kMaxHeartbeatRate_hz))) {
      message = bus.interface + ": bitrate must be 10 kbit/s..1 Mbit/s (FD data phase up to 8 Mbit/s), cycle rate "
                                "1..1000 Hz, heartbeat rate 0 (off) or 0.0153..1000 Hz";
      return DriverError::kBadConfig;
    }
    for (std::size_t o = 0; o < b; ++o) {
      if (plan.buses[o].interface == bus.interface) {
        message = bus.interface + ": interface listed twice";
        return DriverError::kDuplicateId;
      }
    }
  }
  std::vector<int> slot_used(model::kNumJoints, 0);
  for (std::size_t i = 0; i < plan.devices.size(); ++i) {
    const DeviceConfig& d = plan.devices[i];
    if (d.bus < 0 || d.bus >= static_cast<int>(plan.buses.size())) {
      message = "device " + std::to_string(i) + ": bus index " + std::to_string(d.bus) + " not in the plan";
      return DriverError::kBadConfig;
    }
    const bool id_ok = d.kind == DeviceKind::kCia402Drive ? (d.id >= 1 && d.id <= 127)
                                                          : (d.id >= 1 && d.id <= 0x7F);
    if (!id_ok) {
      message = plan.buses[d.bus].interface + ": device ID " + std::to_string(d.id) + " outside 1..127";
      return DriverError::kBadConfig;
    }
    if (d.slot < 0 || d.slot >= model::kNumJoints) {
      message = "device " + std::to_string(i) + ": actuator slot " + std::to_string(d.slot) + " outside 0..27";
      return DriverError::kBadConfig;
    }
    if (slot_used[d.slot]++ > 0) {
      message = "actuator slot " + std::to_string(d.slot) + " assigned twice";
      return DriverError::kDuplicateId;
    }
    for (std::size_t o = 0; o < i; ++o) {
      const DeviceConfig& e = plan.devices[o];
      // One ID space per bus keeps the frame dispatch unambiguous.
      if (e.bus == d.bus && e.id == d.id) {
        message = plan.buses[d.bus].interface + ": ID " + std::to_string(d.id) + " used twice";
        return DriverError::kDuplicateId;
      }
    }
  }
  for (std::size_t b = 0; b < plan.buses.size(); ++b) {
    bool ruiwo = false, canopen = false;
    for (const DeviceConfig& d : plan.devices) {
      if (d.bus != static_cast<int>(b)) continue;
      ruiwo = ruiwo || d.kind == DeviceKind::kRuiwoMotor;
      canopen = canopen || d.kind == DeviceKind::kCia402Drive;
    }
    // Ruiwo's zeroing frames (0x600 + ID) are SDO requests on a CANopen bus,
    // and its replies (ID = motor) could answer nobody's request there.
    if (ruiwo && canopen) {
      message = plan.buses[b].interface + ": Ruiwo motors and CiA 402 drives on one bus";
      return DriverError::kBadConfig;
    }
  }
  report = compute_bus_load(plan);
  for (std::size_t b = 0; b < plan.buses.size(); ++b) {
    if (report.load[b] >= kMaxBusLoad) {
      char rate[32];
      std::snprintf(rate, sizeof(rate), "%.0f Hz", plan.buses[b].cycle_rate_hz);
      message = plan.buses[b].interface + ": worst-case load " + percent(report.load[b]) +
                " >= " + percent(kMaxBusLoad) + " at " + rate +
                " - lower the rate or move devices to another bus";
      return DriverError::kBusOverloaded;
    }
  }
  message.clear();
  return DriverError::kOk;
}

BusPlan default_bus_plan() {
  BusPlan plan;
  auto bus = [&](const char* name, double rate_hz) {
    BusConfig b;
    b.interface = name;
    b.cycle_rate_hz = rate_hz;
    plan.buses.push_back(b);
    return static_cast<int>(plan.buses.size()) - 1;
  };
  auto dev = [&](int b, DeviceKind k, int id, int slot) {
    plan.devices.push_back(DeviceConfig{b, k, static_cast<std::uint8_t>(id), slot});
  };
  // Node IDs: leg slot + 1 (L 1..6, R 7..12), shoulder pitch 13 (L) and 14 (R).
  const int leg_l_hip = bus("can0", 500.0), leg_l_low = bus("can1", 500.0);
  const int leg_r_hip = bus("can2", 500.0), leg_r_low = bus("can3", 500.0);
  const int shoulder = bus("can4", 500.0);
  const int arm_l = bus("can5", 250.0), arm_r = bus("can6", 250.0);
  for (int side = 0; side < 2; ++side) {
    const int first = side == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    for (int k = 0; k < 6; ++k) {
      const int b = k < 3 ? (side == 0 ? leg_l_hip : leg_r_hip) : (side == 0 ? leg_l_low : leg_r_low);
      dev(b, DeviceKind::kCia402Drive, first + k + 1, first + k);
    }
  }
  dev(shoulder, DeviceKind::kCia402Drive, 13, model::kLeftArmFirst);
  dev(shoulder, DeviceKind::kCia402Drive, 14, model::kRightArmFirst);
  for (int k = 0; k < 6; ++k) dev(arm_l, DeviceKind::kRuiwoMotor, 0x01 + k, model::kLeftArmFirst + 1 + k);
  dev(arm_l, DeviceKind::kRuiwoMotor, 0x0D, model::kHeadFirst);
  dev(arm_l, DeviceKind::kRuiwoMotor, 0x0E, model::kHeadFirst + 1);
  for (int k = 0; k < 6; ++k) dev(arm_r, DeviceKind::kRuiwoMotor, 0x07 + k, model::kRightArmFirst + 1 + k);
  return plan;
}

BusPlan single_ruiwo_bus_plan(double rate_hz) {
  BusPlan plan;
  BusConfig b;
  b.interface = "can0";
  b.cycle_rate_hz = rate_hz;
  plan.buses.push_back(b);
  for (int k = 0; k < 6; ++k) {
    plan.devices.push_back({0, DeviceKind::kRuiwoMotor, static_cast<std::uint8_t>(0x01 + k), model::kLeftArmFirst + 1 + k});
    plan.devices.push_back({0, DeviceKind::kRuiwoMotor, static_cast<std::uint8_t>(0x07 + k), model::kRightArmFirst + 1 + k});
  }
  plan.devices.push_back({0, DeviceKind::kRuiwoMotor, 0x0D, model::kHeadFirst});
  plan.devices.push_back({0, DeviceKind::kRuiwoMotor, 0x0E, model::kHeadFirst + 1});
  return plan;
}

}  // namespace kuavo::drivers
