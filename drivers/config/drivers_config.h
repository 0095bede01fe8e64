// Everything the drivers need to know about one robot, as plain structs with
// defaults (FACTS.md, Leju's configuration files), overlaid from the robot's
// JSON file (drivers_config_json.h) and validated once, at start-up, in
// validate_drivers_config. The firmware refuses to start on any error.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "controllers/model/model.h"
#include "drivers/bus/bus_plan.h"
#include "drivers/canopen/cia402_drive.h"
#include "drivers/driver_error.h"
#include "drivers/imu/serial_port.h"
#include "drivers/ruiwo/ruiwo_bus.h"
#include "drivers/transmission/leg_transmission.h"

namespace kuavo::drivers {

struct DriveEntry {
  int slot = -1;  // actuator slot (controller joint order)
  int bus = -1;   // index into plan.buses
  canopen::DriveConfig config{};
};

struct DriversConfig {
  BusPlan plan{};
  std::vector<ruiwo::MotorConfig> ruiwo_motors;  // one per Ruiwo device of the plan
  std::vector<DriveEntry> drives;                // one per CiA 402 device of the plan
  std::array<LegTransmission, 2> legs{};         // left, right
  std::string imu_device = "/dev/ttyUSB0";
  int imu_baud = kMtiDefaultBaud;
};

// Defaults: default_bus_plan(), ruiwo::default_motors(model), drive defaults
// per slot, default_leg_transmission().
DriversConfig default_drivers_config(const model::Model& model);

// Rebuilds `drives` from the plan (node IDs, bus rates) keeping per-slot
// overrides of counts/torques; call after changing the plan.
void sync_drives_with_plan(DriversConfig& config);

// Checks the bus plan (load < 70 %, IDs), that every Ruiwo device has exactly
// one motor configuration with the same ID and joint (and passes
// ruiwo::build_bus), every CiA 402 device a drive entry with positive counts
// and torques, transmissions with non-zero finite ratios, and a reachable
// ankle zero. Fills `report` with the bus loads.
DriverError validate_drivers_config(const DriversConfig& config, BusLoadReport& report, std::string& message);

// Start-up: switches every leg drive to CSP with fixed position-loop gains, from
// joint-space gains (slot order) mapped to motor side: serial joints kp / r^2;
// the two ankle motors share one gain k with k trace(J^T J) = kp_pitch + kp_roll
// at the zero pose (the linkage couples them; the firmware's torque offset makes
// up the difference at each sample, robot_io.h). false + message if the ankle
// has no zero-pose solution or a gain is not representable. The shoulder pitch
// drives: use_csp_shoulder_drives.
bool use_csp_leg_drives(DriversConfig& config, const std::array<double, kLegActuators>& joint_kp,
                        const std::array<double, kLegActuators>& joint_kd, std::string& message);

// Start-up: switches the two shoulder pitch drives (1:1, no transmission) to CSP with the
// fixed position-loop gains kp, kd (the arms' output gains): their CST law, evaluated by the
// firmware at the control rate on a sample a tick old and held for the tick, chatters at the
// drive's limit in a hard move (firmware/README.md). false + message if not representable.
bool use_csp_shoulder_drives(DriversConfig& config, double joint_kp, double joint_kd, std::string& message);

// The Ruiwo motors of one bus, for ruiwo::build_bus.
std::vector<ruiwo::MotorConfig> ruiwo_motors_on_bus(const DriversConfig& config, int bus);

}  // namespace kuavo::drivers
