// The robot's drivers configuration file (JSON), overlaid on the defaults.
// Every key is optional; unknown keys are errors (a typo must not silently
// leave a default in place). Start-up only.
//
// {
//   "buses":   [{"interface": "can0", "bitrate_bps": 1e6, "fd": false, "data_bitrate_bps": 0,
//                "cycle_rate_hz": 500, "heartbeat_rate_hz": 50}, ...],     // replaces the plan's buses
//   "devices": [{"bus": 0, "kind": "cia402" | "ruiwo", "id": 1, "slot": 0}, ...],  // replaces its devices
//   "ruiwo_motors": [{"id": 5, "sign": -1, "zero_offset_rad": 0.02}],    // per-motor overrides
//   "drives": [{"slot": 4, "counts_per_rev": 4718592, "rated_torque_Nm": 18.9,
//               "torque_limit_Nm": 27}],                                  // per-slot overrides
//   "knee_ratio_motor_per_joint": -1.0,
//   "ankle_motor_offset_rad": [0.0, 0.0],       // crank zero in motor readings, both legs
//   "imu": {"device": "/dev/ttyUSB0", "baud": 2000000}
// }
#pragma once

#include <string>

#include "drivers/config/drivers_config.h"

namespace kuavo::drivers {

// Applies the overrides in `json_text`; kBadConfig with a message naming the
// key on malformed JSON, wrong types, unknown keys or unknown IDs/slots.
DriverError apply_drivers_json(const std::string& json_text, DriversConfig& config, std::string& message);

// Defaults + file + validation. kDeviceMissing if the file cannot be read.
DriverError load_drivers_config(const std::string& path, const model::Model& model, DriversConfig& out,
                                BusLoadReport& report, std::string& message);

}  // namespace kuavo::drivers
