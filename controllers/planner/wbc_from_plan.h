// Plan knots as a WBC reference, for tracking the kinematic plan without the MPC
// (the "kinematic" planner mode, and the reference the MPC is compared against).
// Feed-forward accelerations come from the difference to the next knot; planned
// contact forces share the weight (plus the CoM's planned vertical acceleration)
// evenly over the stance corners. Real-time safe.
#pragma once

#include "controllers/planner/plan_knot.h"
#include "controllers/wbc/wbc_reference.h"

namespace kuavo::planner {

void wbc_reference_from_knots(const model::Model& model, const PlanKnot& knot, const PlanKnot& next, double dt_s,
                              wbc::WbcReference& out);

}  // namespace kuavo::planner
