#include "firmware/firmware_config.h"

#include <cmath>

namespace kuavo::firmware {

namespace {
bool fail(std::string& message, const char* text) {
  message = text;
  return false;
}
}  // namespace

bool validate_firmware_config(const FirmwareConfig& c, std::string& message) {
  // The 20 ms to damping is the budget; thresholds beyond it could not meet it.
  constexpr hal::TimeNs kDampingBudget_ns = 20'000'000;
  if (c.control_period_ns < 250'000 || c.control_period_ns > 10'000'000)
    return fail(message, "control_period_ns must be in [0.25 ms, 10 ms]");
  if (c.ruiwo_divider < 1 || c.ruiwo_divider > 8) return fail(message, "ruiwo_divider must be in [1, 8]");
  if (c.sensor_max_age_ns <= c.control_period_ns * c.ruiwo_divider || c.sensor_max_age_ns >= kDampingBudget_ns)
    return fail(message, "sensor_max_age_ns must exceed one Ruiwo period and stay below 20 ms");
  if (c.imu_max_age_ns <= c.control_period_ns || c.imu_max_age_ns >= kDampingBudget_ns)
    return fail(message, "imu_max_age_ns must exceed one control period and stay below 20 ms");
  if (c.plan_max_age_ns <= c.control_period_ns) return fail(message, "plan_max_age_ns must exceed one control period");
  if (c.planner_period_ns < c.control_period_ns || c.planner_period_ns > 100'000'000)
    return fail(message, "planner_period_ns must be in [control period, 100 ms]");
  if (c.plan_stale_ns <= c.planner_period_ns || c.plan_stale_ns >= c.plan_max_age_ns)
    return fail(message, "plan_stale_ns must exceed one planner period and stay below plan_max_age_ns");
  if (c.dance_blend_ns < 0 || c.dance_blend_ns > 2'000'000'000) return fail(message, "dance_blend_ns must be in [0, 2 s]");
  if (c.dance_settle_ns < 0) return fail(message, "dance_settle_ns must not be negative");
  if (!(c.max_tilt_rad > 0.0 && c.max_tilt_rad < 1.5707963267948966))
    return fail(message, "max_tilt_rad must be in (0, pi/2)");
  if (c.self_check_timeout_ns <= 0) return fail(message, "self_check_timeout_ns must be positive");
  if (!(c.kp_max_Nm_per_rad > 0.0 && std::isfinite(c.kp_max_Nm_per_rad)))
    return fail(message, "kp_max_Nm_per_rad must be positive and finite");
  if (!(c.kd_max_Nm_s_per_rad > 0.0 && std::isfinite(c.kd_max_Nm_s_per_rad)))
    return fail(message, "kd_max_Nm_s_per_rad must be positive and finite");
  if (!(c.damping_kd_Nm_s_per_rad > 0.0 && c.damping_kd_Nm_s_per_rad <= c.kd_max_Nm_s_per_rad))
    return fail(message, "damping_kd_Nm_s_per_rad must be in (0, kd_max_Nm_s_per_rad]");
  if (c.stand_up_duration_ns <= 0 || c.finish_duration_ns <= 0)
    return fail(message, "stand_up_duration_ns and finish_duration_ns must be positive");
  if (c.fifo_priority < 0 || c.fifo_priority > 99) return fail(message, "fifo_priority must be in [0, 99]");
  if (c.cpu < -1) return fail(message, "cpu must be -1 (no pinning) or a CPU index");
  if (c.planner_fifo_priority < 0 || c.planner_fifo_priority >= c.fifo_priority)
    return fail(message, "planner_fifo_priority must be in [0, fifo_priority)");
  if (c.planner_cpu < -1) return fail(message, "planner_cpu must be -1 (no pinning) or a CPU index");
  if (c.cpu_dma_latency_us < -1) return fail(message, "cpu_dma_latency_us must be -1 (leave alone) or a bound in us");
  return true;
}

}  // namespace kuavo::firmware
