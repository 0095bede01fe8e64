// What a planner hands the 500 Hz loop: a short run of WBC reference knots starting at
// the state it planned from. The MPC fills one from its solution; the kinematic planner
// straight from the motion. A value type, passed through rtos_shim's LatestValue
// (or the lockstep scheduler's pending slot) from the planning task to the control task.
#pragma once

#include <array>

#include "controllers/planner/motion_plan.h"
#include "controllers/wbc/wbc_reference.h"

namespace kuavo::planner {

inline constexpr int kReferencePlanKnots = 10;  // 0.2 s at 50 Hz: covers latency plus the WBC's staleness limit

struct ReferencePlan {
  hal::TimeNs stamp_ns = 0;  // time of knots[0]
  double dt_s = 0.02;
  int count = 0;
  std::array<wbc::WbcReference, kReferencePlanKnots> knots{};
};

// The reference at now_ns: linear between the knots around it; before the first knot
// the first, after the last the last (its stamp then tells the WBC how stale it is).
// false if the plan has no knots. Real-time safe.
bool reference_plan_at_rt(const ReferencePlan& plan, hal::TimeNs now_ns, wbc::WbcReference& out);

// The kinematic planner: knots straight from the motion at t0_ns, t0 + dt, …
// data and scratch are workspaces. Real-time safe.
void kinematic_reference_plan_rt(const model::Model& model, dynamics::Data& data, const MotionPlan& motion,
                                 hal::TimeNs t0_ns, double dt_s, PlanWindow& scratch, ReferencePlan& out);

}  // namespace kuavo::planner
