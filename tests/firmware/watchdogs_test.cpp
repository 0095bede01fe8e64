// Each watchdog with synthetic inputs: the threshold itself and one past it.
#include <gtest/gtest.h>

#include <cmath>

#include "firmware/watchdogs.h"
#include "tests/firmware/firmware_test_support.h"

namespace kuavo::firmware {
namespace {

using test_support::standing_sensors;

constexpr hal::TimeNs kNow_ns = 10'000'000'000;

hal::SensorFrame fresh() { return standing_sensors(dynamics::JointVector::Zero(), kNow_ns); }

TEST(Watchdogs, QuietWhenEverythingIsFresh) {
  const FirmwareConfig cfg;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), WatchdogInputs{}, kNow_ns).fault, Fault::kNone);
  EXPECT_TRUE(self_check_passed_rt(cfg, fresh(), BusStatus{}, kNow_ns));
}

TEST(Watchdogs, SensorStalenessByStampAge) {
  const FirmwareConfig cfg;
  hal::SensorFrame s = fresh();
  s.joints[17].stamp_ns = kNow_ns - cfg.sensor_max_age_ns;
  s.joints[17].valid = false;  // one lost reply: tolerated while young
  EXPECT_EQ(check_watchdogs_rt(cfg, s, WatchdogInputs{}, kNow_ns).fault, Fault::kNone);
  EXPECT_FALSE(self_check_passed_rt(cfg, s, BusStatus{}, kNow_ns));  // self-check wants all valid
  s.joints[17].stamp_ns -= 1;
  const WatchdogResult r = check_watchdogs_rt(cfg, s, WatchdogInputs{}, kNow_ns);
  EXPECT_EQ(r.fault, Fault::kSensorStale);
  EXPECT_EQ(r.joint, 17);
  s = fresh();
  s.imu.stamp_ns = kNow_ns - cfg.imu_max_age_ns - 1;
  EXPECT_EQ(check_watchdogs_rt(cfg, s, WatchdogInputs{}, kNow_ns).fault, Fault::kImuStale);
  s = fresh();
  s.imu.valid = false;
  EXPECT_EQ(check_watchdogs_rt(cfg, s, WatchdogInputs{}, kNow_ns).fault, Fault::kImuStale);
}

TEST(Watchdogs, BusReportsNameTheirCause) {
  const FirmwareConfig cfg;
  WatchdogInputs in;
  in.bus.silent_motors = 1;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kMotorSilent);
  in.bus.motor_faults = 1;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kMotorFault);
  in.bus.drive_failures = 1;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kDriveFault);
  in.bus.io_failures = 1;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kBusIo);
  in.bus.bus_off = 1;  // the root cause wins over the silence it causes
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kBusOff);
  EXPECT_FALSE(self_check_passed_rt(cfg, fresh(), in.bus, kNow_ns));
}

TEST(Watchdogs, PlanAgeOnlyWithAPlanner) {
  const FirmwareConfig cfg;
  WatchdogInputs in;
  in.plan_stamp_ns = 0;  // ancient, but no planner runs yet
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kNone);
  in.planner_running = true;
  in.plan_stamp_ns = kNow_ns - cfg.plan_max_age_ns;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kNone);
  in.plan_stamp_ns -= 1;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kPlanStale);
}

TEST(Watchdogs, EstimatorDivergence) {
  const FirmwareConfig cfg;
  WatchdogInputs in;
  in.estimator_diverged = true;
  EXPECT_EQ(check_watchdogs_rt(cfg, fresh(), in, kNow_ns).fault, Fault::kEstimatorDiverged);
}

TEST(Watchdogs, TiltBeyond45Degrees) {
  const FirmwareConfig cfg;
  hal::SensorFrame s = fresh();
  for (double deg : {0.0, 20.0, 44.9, 45.1, 90.0, 180.0}) {
    const double half = 0.5 * deg * M_PI / 180.0;
    s.imu.orientation_xyzw = {std::sin(half) * std::sqrt(0.5), std::sin(half) * std::sqrt(0.5), 0.0, std::cos(half)};
    EXPECT_NEAR(tilt_rad(s.imu), deg * M_PI / 180.0, 1e-9);
    EXPECT_EQ(check_watchdogs_rt(cfg, s, WatchdogInputs{}, kNow_ns).fault,
              deg > 45.0 ? Fault::kTiltExceeded : Fault::kNone) << deg;
  }
  s.imu.orientation_xyzw = {0.0, 0.0, 0.0, 0.0};  // garbage counts as fallen
  EXPECT_EQ(check_watchdogs_rt(cfg, s, WatchdogInputs{}, kNow_ns).fault, Fault::kTiltExceeded);
}

TEST(Watchdogs, ImplausibleJointReadings) {
  const model::Model& m = test_support::test_model();
  hal::SensorFrame s = fresh();
  for (int j = 0; j < model::kNumJoints; ++j) s.joints[j].position_rad = 0.5 * (m.limits.position_min_rad[j] + m.limits.position_max_rad[j]);
  EXPECT_EQ(check_samples_plausible_rt(m, s).fault, Fault::kNone);
  s.joints[5].position_rad = m.limits.position_max_rad[5] + kImplausibleMargin_rad;  // at the margin: still plausible
  EXPECT_EQ(check_samples_plausible_rt(m, s).fault, Fault::kNone);
  s.joints[5].position_rad += 1e-6;
  WatchdogResult r = check_samples_plausible_rt(m, s);
  EXPECT_EQ(r.fault, Fault::kSensorImplausible);
  EXPECT_EQ(r.joint, 5);
  s.joints[5].valid = false;  // an invalid sample is not read
  EXPECT_EQ(check_samples_plausible_rt(m, s).fault, Fault::kNone);
  s.joints[5].valid = true;
  s.joints[5].position_rad = 0.0;
  s.joints[9].velocity_rad_s = std::nan("");
  r = check_samples_plausible_rt(m, s);
  EXPECT_EQ(r.fault, Fault::kSensorImplausible);
  EXPECT_EQ(r.joint, 9);
}

TEST(FirmwareConfig, DefaultsValidAndBadValuesNamed) {
  std::string msg;
  FirmwareConfig c;
  EXPECT_TRUE(validate_firmware_config(c, msg)) << msg;
  c.sensor_max_age_ns = 25'000'000;  // beyond the 20 ms damping budget
  EXPECT_FALSE(validate_firmware_config(c, msg));
  EXPECT_NE(msg.find("sensor_max_age_ns"), std::string::npos) << msg;
  c = FirmwareConfig{};
  c.damping_kd_Nm_s_per_rad = 0.0;
  EXPECT_FALSE(validate_firmware_config(c, msg));
  EXPECT_NE(msg.find("damping_kd"), std::string::npos) << msg;
  c = FirmwareConfig{};
  c.max_tilt_rad = 2.0;
  EXPECT_FALSE(validate_firmware_config(c, msg));
}

}  // namespace
}  // namespace kuavo::firmware
