// The robot most tests use: the s45 variant at the product-sheet mass, built once, and its
// centred standing configuration with the soles on the ground.
#pragma once

#include <gtest/gtest.h>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"

namespace kuavo::test {

inline const model::Model& s45_robot() {
  static model::Model m;
  static const bool built = model::build_model(model::Variant::kS45, 55.0, m) == model::ModelError::kOk;
  EXPECT_TRUE(built);
  return m;
}

inline dynamics::ConfigVector standing_configuration() {
  static dynamics::Data data;
  dynamics::ConfigVector q = dynamics::neutral_configuration(s45_robot());
  q.tail<model::kNumJoints>() = control::centred_standing_pose(s45_robot(), data, 0.78);
  control::place_on_ground(s45_robot(), data, q);
  return q;
}

}  // namespace kuavo::test
