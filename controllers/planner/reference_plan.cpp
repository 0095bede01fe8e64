#include "controllers/planner/reference_plan.h"

#include <cmath>

#include "controllers/planner/wbc_from_plan.h"

namespace kuavo::planner {

bool reference_plan_at_rt(const ReferencePlan& plan, hal::TimeNs now_ns, wbc::WbcReference& out) {
  if (plan.count <= 0) return false;
  const double s = static_cast<double>(now_ns - plan.stamp_ns) * 1e-9 / plan.dt_s;
  if (plan.count == 1 || !(s > 0.0)) {
    out = plan.knots[0];
    return true;
  }
  if (s >= plan.count - 1) {
    out = plan.knots[plan.count - 1];
    return true;
  }
  const int k = static_cast<int>(s);
  wbc::wbc_interpolate_reference(plan.knots[k], plan.knots[k + 1], s - k, out);
  return true;
}

void kinematic_reference_plan_rt(const model::Model& model, dynamics::Data& data, const MotionPlan& motion,
                                 hal::TimeNs t0_ns, double dt_s, PlanWindow& scratch, ReferencePlan& out) {
  motion_plan_window_rt(model, data, motion, t0_ns, dt_s, kReferencePlanKnots + 1, scratch);
  out.stamp_ns = t0_ns;
  out.dt_s = dt_s;
  out.count = kReferencePlanKnots;
  for (int k = 0; k < kReferencePlanKnots; ++k) {
    wbc_reference_from_knots(model, scratch.knots[k], scratch.knots[k + 1], dt_s, out.knots[k]);
  }
}

}  // namespace kuavo::planner
