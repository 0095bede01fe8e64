// Shared set-up for the MPC tests: the s45 model, a standing pose, plan windows.
#pragma once

#include <memory>

#include "controllers/mpc/mpc.h"
#include "controllers/standing/standing_controller.h"

namespace kuavo::test {

struct MpcFixture {
  model::Model model;
  dynamics::Data data;
  mpc::MpcConfig config;
  mpc::MpcWorkspace ws;
  planner::PlanWindow window;
  mpc::MpcPlan plan;
  dynamics::ConfigVector q0 = dynamics::ConfigVector::Zero();
};

// One static fixture (the workspace is ~15 MB): built once, re-initialized per call.
inline MpcFixture& mpc_fixture(const mpc::MpcConfig& config = {}) {
  static auto f = std::make_unique<MpcFixture>();
  if (f->model.tables == nullptr) {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, f->model);
    f->q0 = dynamics::neutral_configuration(f->model);
    f->q0.tail<model::kNumJoints>() = control::centred_standing_pose(f->model, f->data, 0.78);
    control::place_on_ground(f->model, f->data, f->q0);
  }
  f->config = config;
  mpc::mpc_init(f->model, f->config, f->ws);
  return *f;
}

inline planner::ContactFlags all_contacts() {
  planner::ContactFlags c{};
  c.fill(true);
  return c;
}

// Standing: the same knot repeated, stamps advancing from t0.
inline void standing_window(MpcFixture& f, hal::TimeNs t0_ns, int count = planner::kMaxWindowKnots) {
  f.window.count = count;
  f.window.dt_s = f.config.dt_s;
  planner::plan_knot_from_state(f.model, f.data, f.q0, dynamics::VelocityVector::Zero(), all_contacts(), t0_ns,
                                f.window.knots[0]);
  for (int k = 1; k < count; ++k) {
    f.window.knots[k] = f.window.knots[0];
    f.window.knots[k].stamp_ns = t0_ns + static_cast<hal::TimeNs>(k) * static_cast<hal::TimeNs>(f.config.dt_s * 1e9);
  }
}

}  // namespace kuavo::test
