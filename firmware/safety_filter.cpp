#include "firmware/safety_filter.h"

#include <cmath>

namespace kuavo::firmware {

FilterResult check_command_rt(const model::Model& model, const FirmwareConfig& c,
                              const hal::CommandFrame& command) noexcept {
  for (int j = 0; j < model::kNumJoints; ++j) {
    const hal::JointCommand& cmd = command.joints[j];
    if (cmd.mode != hal::JointMode::kDisabled && cmd.mode != hal::JointMode::kDamping &&
        cmd.mode != hal::JointMode::kPdTorque) {
      return {Fault::kCommandMode, j};
    }
    if (!std::isfinite(cmd.torque_ff_Nm) || !std::isfinite(cmd.position_ref_rad) ||
        !std::isfinite(cmd.velocity_ref_rad_s) || !std::isfinite(cmd.kp_Nm_per_rad) ||
        !std::isfinite(cmd.kd_Nm_s_per_rad)) {
      return {Fault::kCommandNonFinite, j};
    }
    if (!(cmd.kp_Nm_per_rad >= 0.0 && cmd.kp_Nm_per_rad <= c.kp_max_Nm_per_rad) ||
        !(cmd.kd_Nm_s_per_rad >= 0.0 && cmd.kd_Nm_s_per_rad <= c.kd_max_Nm_s_per_rad)) {
      return {Fault::kCommandGainRange, j};
    }
    if (cmd.mode != hal::JointMode::kPdTorque) continue;  // the drivers ignore the other fields
    if (cmd.position_ref_rad < model.limits.position_min_rad[j] ||
        cmd.position_ref_rad > model.limits.position_max_rad[j]) {
      return {Fault::kCommandPositionLimit, j};
    }
    if (std::abs(cmd.torque_ff_Nm) > model.limits.peak_torque_Nm[j]) return {Fault::kCommandTorqueLimit, j};
  }
  return {};
}

void damping_command_rt(const FirmwareConfig& c, hal::TimeNs now_ns, hal::CommandFrame& out) noexcept {
  for (hal::JointCommand& cmd : out.joints) {
    cmd = hal::JointCommand{};
    cmd.mode = hal::JointMode::kDamping;
    cmd.kd_Nm_s_per_rad = c.damping_kd_Nm_s_per_rad;
  }
  out.stamp_ns = now_ns;
}

void disabled_command_rt(hal::TimeNs now_ns, hal::CommandFrame& out) noexcept {
  for (hal::JointCommand& cmd : out.joints) cmd = hal::JointCommand{};
  out.stamp_ns = now_ns;
}

}  // namespace kuavo::firmware
