// Shared set-up for the MPC tests: the s45 model, a standing pose, plan windows.
#pragma once

#include <cmath>
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

// The first stage starting at or after reference window knot `knot` (MpcConfig::tail_stride).
inline int first_stage_from(const MpcFixture& f, int knot) {
  int k = 0;
  while (k < f.ws.horizon && f.ws.stage_knot[k] < knot) ++k;
  return k;
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

namespace kuavo::test {

// Stepping in place: double support `stance_s`, then one foot swings for `swing_s` (apex
// `height_m`, z = h sin(π s), no x-y motion), alternating left, right, … from t = 0. The
// whole-body reference stays the standing pose: the MPC has to shift the CoM itself.
struct SteppingPlan {
  double stance_s = 0.3;
  double swing_s = 0.4;
  double height_m = 0.05;
  double heel_off_s = 0.0;  // the swing foot's heel corners leave the ground this long before lift-off
};

inline void stepping_window(MpcFixture& f, hal::TimeNs t0_ns, const SteppingPlan& plan,
                            int count = planner::kMaxWindowKnots) {
  standing_window(f, t0_ns, count);
  const double period = plan.stance_s + plan.swing_s;
  for (int k = 0; k < count; ++k) {
    planner::PlanKnot& knot = f.window.knots[k];
    const double t = static_cast<double>(knot.stamp_ns) * 1e-9;
    const int cycle = static_cast<int>(std::floor(t / period));
    const double in_cycle = t - cycle * period;
    const int first = (cycle % 2 == 0) ? 0 : 4;  // left first
    if (in_cycle < plan.stance_s) {
      if (in_cycle >= plan.stance_s - plan.heel_off_s) {  // toe-only contact (corners 0, 1 are the toes)
        knot.in_contact[first + 2] = false;
        knot.in_contact[first + 3] = false;
      }
      continue;
    }
    const double s = (in_cycle - plan.stance_s) / plan.swing_s;
    for (int c = first; c < first + 4; ++c) {
      knot.in_contact[c] = false;
      knot.point_position_m[3 * c + 2] += plan.height_m * std::sin(M_PI * s);
      knot.point_velocity_m_s[3 * c + 2] = plan.height_m * M_PI / plan.swing_s * std::cos(M_PI * s);
    }
  }
}

}  // namespace kuavo::test
