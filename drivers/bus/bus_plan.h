// Which device sits on which CAN interface, at which cycle rate, and the
// worst-case load that results. Checked once at start-up: a plan with any bus
// at or above kMaxBusLoad, a duplicate ID on a bus, or an actuator slot used
// twice is refused with a message naming the culprit.
//
// Actuator slots use the controller's 28-joint order; for a leg the slots of
// ankle pitch / ankle roll stand for ankle motors A / B (the transmission maps
// them to the joints).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "drivers/driver_error.h"

namespace kuavo::drivers {

enum class DeviceKind : std::uint8_t {
  kRuiwoMotor = 0,   // request/response, 2 x 8-byte frames per cycle
  kCia402Drive = 1,  // RPDO1 (8) + TPDO1 (8) + TPDO2 (7) per cycle, heartbeat
};

struct BusConfig {
  std::string interface;         // "can0"
  double bitrate_bps = 1e6;      // nominal bitrate (ip link ... bitrate)
  bool fd = false;               // open with CAN_RAW_FD_FRAMES
  double data_bitrate_bps = 0;   // FD data phase; 0 for classic
  double cycle_rate_hz = 500.0;  // how often each device on this bus is served
  double heartbeat_rate_hz = 50.0;  // CANopen producers (20 ms)
};

struct DeviceConfig {
  int bus = 0;
  DeviceKind kind = DeviceKind::kRuiwoMotor;
  std::uint8_t id = 0;  // Ruiwo motor ID or CANopen node ID
  int slot = -1;        // actuator slot, controller joint order
};

struct BusPlan {
  std::vector<BusConfig> buses;
  std::vector<DeviceConfig> devices;
};

struct BusLoadReport {
  std::vector<double> load;            // fraction of the bus time, per bus
  std::vector<double> frames_per_s;    // per bus
};

// Load of every bus, no validation.
BusLoadReport compute_bus_load(const BusPlan& plan);

// Validates and computes; kBusOverloaded / kDuplicateId / kBadConfig with a
// message such as "can5 (Ruiwo arms+head): load 94.5 % >= 70 % at 250 Hz".
DriverError check_bus_plan(const BusPlan& plan, BusLoadReport& report, std::string& message);

// Our default: legs and shoulder pitch as CiA 402 drives at 500 Hz (the WBC
// rate, FACTS.md §4.1), three drives per 1 Mbit/s bus; the Ruiwo motors at
// 250 Hz split over two buses (left arm + head, right arm) because Leju's
// single-bus wiring would need 94.5 % of 1 Mbit/s.
BusPlan default_bus_plan();

// Leju's wiring of the Ruiwo motors: all 14 on one bus at `rate_hz`.
BusPlan single_ruiwo_bus_plan(double rate_hz);

}  // namespace kuavo::drivers
