// Opens every interface of a checked bus plan (start-up). Stops at the first
// failure and closes what it had opened, so the firmware can refuse to start
// with one clear message (on a kernel without CAN: "can0: socket(AF_CAN)
// failed: ...").
#pragma once

#include <string>
#include <vector>

#include "drivers/bus/bus_plan.h"
#include "drivers/can/can_port.h"
#include "drivers/driver_error.h"

namespace kuavo::drivers {

DriverError open_buses(const BusPlan& plan, std::vector<CanPort>& ports, std::string& message);
void close_buses(std::vector<CanPort>& ports);

}  // namespace kuavo::drivers
