// Watchdogs: each turns one kind of stale or implausible input into a Fault.
// Checked every cycle while the motors are powered (is_active); the first
// fault in the order below is reported (buses before samples: a bus-off also
// makes samples stale, and the log should name the cause).
#pragma once

#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "firmware/fault.h"
#include "firmware/firmware_config.h"

namespace kuavo::firmware {

// What the drivers saw this cycle, summed over all buses.
struct BusStatus {
  int silent_motors = 0;  // Ruiwo motors past the reply timeout, drives without TPDOs
  int bus_off = 0;        // ports with the bus-off latch set
  int drive_failures = 0; // CiA 402 supervisors in kFailed
  int motor_faults = 0;   // Ruiwo replies with a fault byte
  int io_failures = 0;    // send failures, closed peers
};

struct WatchdogInputs {
  BusStatus bus{};
  bool estimator_diverged = false;
  bool planner_running = false;  // false until an MPC exists
  hal::TimeNs plan_stamp_ns = 0; // stamp of the MPC result in use
};

struct WatchdogResult {
  Fault fault = Fault::kNone;
  int joint = -1;  // the offending joint for kSensorStale
};

// Torso tilt from the IMU orientation (sensor -> world): the angle between the
// sensor's z axis and world up, assuming the IMU is mounted level in the torso.
[[nodiscard]] double tilt_rad(const hal::ImuSample& imu) noexcept;

[[nodiscard]] WatchdogResult check_watchdogs_rt(const FirmwareConfig& config, const hal::SensorFrame& sensors,
                                                const WatchdogInputs& in, hal::TimeNs now_ns) noexcept;

// A valid joint reading must be finite and inside the joint's stops widened by
// kImplausibleMargin_rad (encoder slack and the stops' compliance; a reading
// further out is a broken sample, e.g. a flipped high bit). Returns the first
// offending joint's fault. Checked before the controller uses the frame.
inline constexpr double kImplausibleMargin_rad = 0.2;
[[nodiscard]] WatchdogResult check_samples_plausible_rt(const model::Model& model,
                                                        const hal::SensorFrame& sensors) noexcept;

// Self-check: every joint and the IMU valid and fresh, no bus fault.
[[nodiscard]] bool self_check_passed_rt(const FirmwareConfig& config, const hal::SensorFrame& sensors,
                                        const BusStatus& bus, hal::TimeNs now_ns) noexcept;

}  // namespace kuavo::firmware
