// Shared fixtures of the firmware tests: the model, a valid standing sensor
// frame, and a Firmware object in static storage (it holds the controller's
// dynamics workspace, too big for a stack).
#pragma once

#include <gtest/gtest.h>

#include "controllers/model/model.h"
#include "firmware/control_cycle.h"

namespace kuavo::firmware::test_support {

inline const model::Model& test_model() {
  static model::Model m;
  static const bool built = [] {
    return model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, m) == model::ModelError::kOk;
  }();
  EXPECT_TRUE(built);
  return m;
}

// All joints at `pose`, valid and stamped now; IMU level and fresh.
inline hal::SensorFrame standing_sensors(const dynamics::JointVector& pose, hal::TimeNs now_ns) {
  hal::SensorFrame s;
  for (int j = 0; j < model::kNumJoints; ++j) {
    s.joints[j].position_rad = pose[j];
    s.joints[j].stamp_ns = now_ns;
    s.joints[j].valid = true;
  }
  s.imu.valid = true;
  s.imu.stamp_ns = now_ns;
  s.imu.acceleration_m_s2 = {0.0, 0.0, 9.81};
  return s;
}

inline void restamp(hal::SensorFrame& s, hal::TimeNs now_ns) {
  for (hal::JointSample& j : s.joints) j.stamp_ns = now_ns;
  s.imu.stamp_ns = now_ns;
}

using hal::all_damping;

}  // namespace kuavo::firmware::test_support
