// The last check before the drivers: a command that is not finite or outside
// the robot's limits is refused as a whole -- never clamped -- and the caller
// latches the fault and sends the damping command instead. (The drivers clamp
// too, as a last line; the firmware must never rely on it, and the tests check
// that the drivers' clamp counters stay at zero.)
#pragma once

#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "firmware/fault.h"
#include "firmware/firmware_config.h"

namespace kuavo::firmware {

struct FilterResult {
  Fault fault = Fault::kNone;
  int joint = -1;  // first offending joint
};

// Checks every joint: mode known; all fields finite; in kPdTorque q_ref within
// the model's position limits; |tau_ff| <= peak torque; 0 <= kp <= kp_max,
// 0 <= kd <= kd_max. Real-time safe.
[[nodiscard]] FilterResult check_command_rt(const model::Model& model, const FirmwareConfig& config,
                                            const hal::CommandFrame& command) noexcept;

// The safe mode: tau = -kd v on every joint (kd from the configuration).
void damping_command_rt(const FirmwareConfig& config, hal::TimeNs now_ns, hal::CommandFrame& out) noexcept;

// Motors unpowered (boot, self-check).
void disabled_command_rt(hal::TimeNs now_ns, hal::CommandFrame& out) noexcept;

}  // namespace kuavo::firmware
