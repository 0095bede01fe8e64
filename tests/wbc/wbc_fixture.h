// Shared set-up for the WBC tests: the model, a bent-knee standing state on the ground and
// the WBC workspace in static storage (as the firmware keeps it).
#pragma once

#include <algorithm>

#include "controllers/wbc/wbc.h"

namespace kuavo::test {

inline const model::Model& wbc_robot() {
  static model::Model m = [] {
    model::Model out;
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, out);
    return out;
  }();
  return m;
}

inline wbc::WbcWorkspace& wbc_workspace() {
  static wbc::WbcWorkspace ws;
  return ws;
}

// Knees bent by 2·bend, feet flat (hip pitch −bend, ankle pitch −bend), elbows slightly bent,
// lowest sole corner on z = 0.
inline dynamics::ConfigVector bent_standing_configuration(double bend_rad = 0.35) {
  const model::Model& m = wbc_robot();
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  for (int leg : {model::kLeftLegFirst, model::kRightLegFirst}) {
    q[7 + leg + 2] = -bend_rad;
    q[7 + leg + 3] = 2.0 * bend_rad;
    q[7 + leg + 4] = -bend_rad;
  }
  q[7 + model::kLeftArmFirst + 3] = -0.116;  // reference.info standing elbow
  q[7 + model::kRightArmFirst + 3] = -0.116;
  static dynamics::Data data;
  dynamics::forward_kinematics(m, data, q);
  double lowest = 1e9;
  for (int c = 0; c < model::kNumContactPoints; ++c) lowest = std::min(lowest, dynamics::frame_position(m, data, c).z());
  q[2] -= lowest;
  return q;
}

}  // namespace kuavo::test
