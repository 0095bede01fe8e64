#include "controllers/planner/plan_anchor.h"

#include <algorithm>
#include <cmath>

namespace kuavo::planner {
namespace {

constexpr int kCornersPerFoot = kNumPoints / 2;

bool foot_down(const PlanKnot& knot, int foot) {
  for (int i = 0; i < kCornersPerFoot; ++i) {
    if (knot.in_contact[foot * kCornersPerFoot + i]) return true;
  }
  return false;
}

// The foot of the window's first single support: 0 or 1; 2 for none (both down throughout,
// or flight).
int anchor_foot(const PlanWindow& window) {
  for (int k = 0; k < window.count; ++k) {
    const bool l = foot_down(window.knots[k], 0), r = foot_down(window.knots[k], 1);
    if (l != r) return l ? 0 : 1;
  }
  return 2;
}

// Adds measured − planned (horizontal) of the foot's corners in contact at knot 0 to sum, their count to n.
void foot_error(const PlanKnot& planned, const PlanKnot& measured, int foot, Eigen::Vector2d& sum, int& n) {
  for (int i = 0; i < kCornersPerFoot; ++i) {
    const int c = foot * kCornersPerFoot + i;
    if (!planned.in_contact[c]) continue;
    sum += measured.point_position_m.segment<2>(3 * c) - planned.point_position_m.segment<2>(3 * c);
    ++n;
  }
}

}  // namespace

const char* plan_anchor_validate(const PlanAnchorConfig& c) {
  const double values[] = {c.settle_s, c.deadband_m, c.ramp_s, c.max_offset_m, c.home_share};
  for (double x : values) {
    if (!std::isfinite(x)) return "plan anchor: every value must be finite";
  }
  if (c.settle_s < 0.0 || c.settle_s > 0.5) return "plan anchor: settle_s must be in [0, 0.5]";
  if (c.deadband_m < 0.0) return "plan anchor: deadband_m must be >= 0";
  if (c.ramp_s < 0.0 || c.ramp_s > 2.0) return "plan anchor: ramp_s must be in [0, 2]";
  if (c.max_offset_m <= 0.0) return "plan anchor: max_offset_m must be > 0";
  if (c.home_share < 0.0 || c.home_share > 0.5) return "plan anchor: home_share must be in [0, 0.5]";
  return nullptr;
}

void plan_anchor_reset(PlanAnchorState& s) {
  s.started = false;
  s.last_call_ns = 0;
  s.down_s.fill(0.0);
  s.offset.setZero();
  s.from.setZero();
  s.to.setZero();
  s.ramp_start_ns = 0;
  s.reanchors = 0;
  s.refused = 0;
  s.offset_max_m = 0.0;
}

void plan_anchor_rt(const PlanAnchorConfig& cfg, PlanAnchorState& s, const PlanKnot& measured, hal::TimeNs t_ns,
                    PlanWindow& window) {
  if (!cfg.enabled || window.count <= 0) return;
  const double step_s = s.started && t_ns > s.last_call_ns ? static_cast<double>(t_ns - s.last_call_ns) * 1e-9 : 0.0;
  s.started = true;
  s.last_call_ns = t_ns;
  const PlanKnot& now = window.knots[0];
  for (int f = 0; f < 2; ++f) s.down_s[f] = foot_down(now, f) ? s.down_s[f] + step_s : 0.0;

  const int anchor = anchor_foot(window);
  const int first = anchor == 2 ? 0 : anchor, last = anchor == 2 ? 1 : anchor;
  bool settled = true;
  for (int f = first; f <= last; ++f) settled = settled && foot_down(now, f) && s.down_s[f] >= cfg.settle_s;
  if (settled) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int n = 0;
    for (int f = first; f <= last; ++f) foot_error(now, measured, f, sum, n);
    if (n > 0) {
      const Eigen::Vector2d target = (1.0 - cfg.home_share) * sum / n;
      // A non-finite state gives a non-finite target: neither taken nor counted (the MPC
      // refuses the state itself).
      if (target.allFinite() && (target - s.to).norm() > cfg.deadband_m) {
        if (target.norm() <= cfg.max_offset_m) {
          s.from = s.offset;
          s.to = target;
          s.ramp_start_ns = t_ns;
          ++s.reanchors;
        } else {
          ++s.refused;
        }
      }
    }
  }
  const double ramp = cfg.ramp_s > 0.0 ? static_cast<double>(t_ns - s.ramp_start_ns) * 1e-9 / cfg.ramp_s : 1.0;
  s.offset = ramp >= 1.0 ? s.to : Eigen::Vector2d(s.from + (s.to - s.from) * std::max(ramp, 0.0));
  s.offset_max_m = std::max(s.offset_max_m, s.offset.norm());
  if (s.offset.isZero(0.0)) return;
  for (int k = 0; k < window.count; ++k) {
    PlanKnot& knot = window.knots[k];
    knot.q.head<2>() += s.offset;
    knot.com_position_m.head<2>() += s.offset;
    for (int c = 0; c < kNumPoints; ++c) knot.point_position_m.segment<2>(3 * c) += s.offset;
  }
}

}  // namespace kuavo::planner
