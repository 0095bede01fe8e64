// Per-slot parameters of the CiA 402 drives (legs, shoulder pitch) from
// Leju's kuavo.json (v45) and FACTS.md §5.1: encoder counts per output turn
// (2^17 x the motor type's multiplier), continuous torque (used as the drive's
// rated torque, so 1000 per mille = the continuous limit) and peak torque (the
// clamp before packing). All motor side.
#pragma once

#include <cstdint>

#include "drivers/canopen/cia402_drive.h"

namespace kuavo::drivers {

// slot: controller joint index of a leg joint (0..11) or a shoulder pitch
// (model::kLeftArmFirst / kRightArmFirst). Other slots get a neutral config
// with torque_limit_Nm = 0 (the plan check refuses them).
canopen::DriveConfig default_drive_config(int slot, std::uint8_t node_id, double cycle_rate_hz,
                                          double heartbeat_rate_hz);

}  // namespace kuavo::drivers
