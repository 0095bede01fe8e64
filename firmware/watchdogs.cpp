#include "firmware/watchdogs.h"

#include <algorithm>
#include <cmath>

#include "controllers/model/model_tables.h"

namespace kuavo::firmware {

double tilt_rad(const hal::ImuSample& imu) noexcept {
  const double x = imu.orientation_xyzw[0], y = imu.orientation_xyzw[1];
  const double z = imu.orientation_xyzw[2], w = imu.orientation_xyzw[3];
  const double n2 = x * x + y * y + z * z + w * w;
  if (!(n2 > 0.0) || !std::isfinite(n2)) return M_PI;  // garbage orientation counts as fallen
  // World z of the sensor's z axis: R(2,2) = 1 - 2(x^2 + y^2) for a unit quaternion.
  const double cos_tilt = 1.0 - 2.0 * (x * x + y * y) / n2;
  return std::acos(std::clamp(cos_tilt, -1.0, 1.0));
}

namespace {
bool fresh(bool valid, hal::TimeNs stamp_ns, hal::TimeNs now_ns, hal::TimeNs max_age_ns) noexcept {
  return valid && now_ns - stamp_ns <= max_age_ns;
}
}  // namespace

WatchdogResult check_watchdogs_rt(const FirmwareConfig& c, const hal::SensorFrame& sensors,
                                  const WatchdogInputs& in, hal::TimeNs now_ns) noexcept {
  if (in.bus.bus_off > 0) return {Fault::kBusOff, -1};
  if (in.bus.io_failures > 0) return {Fault::kBusIo, -1};
  if (in.bus.drive_failures > 0) return {Fault::kDriveFault, -1};
  if (in.bus.motor_faults > 0) return {Fault::kMotorFault, -1};
  if (in.bus.silent_motors > 0) return {Fault::kMotorSilent, -1};
  // Staleness by stamp age, not by `valid`: one lost reply is normal at 1 %
  // frame loss; the age bound is what keeps us inside the damping budget.
  for (int j = 0; j < model::kNumJoints; ++j) {
    const hal::JointSample& s = sensors.joints[j];
    if (now_ns - s.stamp_ns > c.sensor_max_age_ns) return {Fault::kSensorStale, j};
  }
  if (!fresh(sensors.imu.valid, sensors.imu.stamp_ns, now_ns, c.imu_max_age_ns)) return {Fault::kImuStale, -1};
  if (in.planner_running && now_ns - in.plan_stamp_ns > c.plan_max_age_ns) return {Fault::kPlanStale, -1};
  if (in.estimator_diverged) return {Fault::kEstimatorDiverged, -1};
  if (tilt_rad(sensors.imu) > c.max_tilt_rad) return {Fault::kTiltExceeded, -1};
  return {};
}

WatchdogResult check_samples_plausible_rt(const model::Model& model, const hal::SensorFrame& sensors) noexcept {
  for (int j = 0; j < model::kNumJoints; ++j) {
    const hal::JointSample& s = sensors.joints[j];
    if (!s.valid) continue;  // invalid samples are the staleness watchdog's business
    if (!std::isfinite(s.position_rad) || !std::isfinite(s.velocity_rad_s) || !std::isfinite(s.torque_Nm) ||
        s.position_rad < model.limits.position_min_rad[j] - kImplausibleMargin_rad ||
        s.position_rad > model.limits.position_max_rad[j] + kImplausibleMargin_rad) {
      return {Fault::kSensorImplausible, j};
    }
  }
  return {};
}

bool self_check_passed_rt(const FirmwareConfig& c, const hal::SensorFrame& sensors, const BusStatus& bus,
                          hal::TimeNs now_ns) noexcept {
  if (bus.bus_off + bus.io_failures + bus.drive_failures + bus.motor_faults + bus.silent_motors > 0) return false;
  for (const hal::JointSample& s : sensors.joints) {
    if (!fresh(s.valid, s.stamp_ns, now_ns, c.sensor_max_age_ns)) return false;
  }
  return fresh(sensors.imu.valid, sensors.imu.stamp_ns, now_ns, c.imu_max_age_ns);
}

}  // namespace kuavo::firmware
