#include "controllers/planner/liftoff_hold.h"

#include <algorithm>
#include <cmath>

#include "controllers/planner/support_polygon.h"

namespace kuavo::planner {
namespace {

using Vec2 = Eigen::Vector2d;
constexpr int kCornersPerFoot = kNumPoints / 2;

hal::TimeNs to_ns(double s) { return static_cast<hal::TimeNs>(std::llround(s * 1e9)); }

// Signed margin of the knot's capture point inside the hull of its sole corners
// [first, first + N) (positive inside), over those corners' mean height.
template <int N>
double capture_point_margin(const LiftoffHoldConfig& cfg, const PlanKnot& knot, int first) {
  std::array<Vec2, N> corners;
  double sole_z = 0.0;
  for (int i = 0; i < N; ++i) {
    corners[i] = knot.point_position_m.segment<2>(3 * (first + i));
    sole_z += knot.point_position_m[3 * (first + i) + 2] / N;
  }
  const Vec2 xi = capture_point(knot, sole_z, cfg.min_pendulum_height_m).xi;
  return signed_margin(convex_hull<N>(corners, N), xi);
}

// Distance of the knot's capture point outside the sole of `foot` (negative: inside).
double capture_point_outside(const LiftoffHoldConfig& cfg, const PlanKnot& knot, int foot) {
  return -capture_point_margin<kCornersPerFoot>(cfg, knot, foot * kCornersPerFoot);
}

// The knot's capture point inside the convex hull of both soles.
bool capture_point_inside_both(const LiftoffHoldConfig& cfg, const PlanKnot& knot) {
  return capture_point_margin<kNumPoints>(cfg, knot, 0) > 0.0;
}

// The motion's first lift-off of a foot in (tau, tau + ahead] with the other foot down until
// then: its frame, and the foot in `foot`; −1 if none.
int next_liftoff(const MotionPlan& motion, hal::TimeNs tau, hal::TimeNs ahead, int& foot) {
  const int first = motion_plan_frame_at(motion, tau);
  const int last = motion_plan_frame_at(motion, tau + ahead);
  for (int f = 0; f < 2; ++f) {
    if (!motion.foot_contact[first][f]) continue;
    for (int i = first + 1; i <= last; ++i) {
      if (!motion.foot_contact[i][1 - f]) break;  // not a single support of the other foot
      if (!motion.foot_contact[i][f]) {
        foot = f;
        return i;
      }
    }
  }
  return -1;
}

// Both feet down in the motion over [tau, tau + span].
bool both_down(const MotionPlan& motion, hal::TimeNs tau, hal::TimeNs span) {
  const int first = motion_plan_frame_at(motion, tau);
  const int last = motion_plan_frame_at(motion, tau + span);
  for (int i = first; i <= last; ++i) {
    if (!motion.foot_contact[i][0] || !motion.foot_contact[i][1]) return false;
  }
  return true;
}

}  // namespace

const char* liftoff_hold_validate(const LiftoffHoldConfig& c) {
  const double values[] = {c.look_ahead_s, c.tolerance_m, c.max_hold_s, c.catch_up_rate, c.catch_up_quiet_s,
                           c.min_pendulum_height_m};
  for (double x : values) {
    if (!std::isfinite(x)) return "lift-off hold: every value must be finite";
  }
  if (c.look_ahead_s < 0.0 || c.look_ahead_s > 0.2) return "lift-off hold: look_ahead_s must be in [0, 0.2]";
  if (c.tolerance_m < 0.0) return "lift-off hold: tolerance_m must be >= 0";
  if (c.max_hold_s < 0.0 || c.max_hold_s > 1.0) return "lift-off hold: max_hold_s must be in [0, 1]";
  if (c.catch_up_rate < 0.0 || c.catch_up_rate > 1.0) return "lift-off hold: catch_up_rate must be in [0, 1]";
  if (c.catch_up_quiet_s < 0.0) return "lift-off hold: catch_up_quiet_s must be >= 0";
  if (c.min_pendulum_height_m <= 0.0) return "lift-off hold: min_pendulum_height_m must be > 0";
  return nullptr;
}

void liftoff_hold_reset(LiftoffHoldState& s) {
  s.started = false;
  s.last_call_ns = 0;
  s.lag_ns = 0;
  s.held_ns = 0;
  s.released_frame = -1;
  s.holds = 0;
  s.held_calls = 0;
  s.released = 0;
  s.lag_max_ns = 0;
  s.last_excess_m = 0.0;
}

void liftoff_hold_window_rt(const model::Model& model, const LiftoffHoldConfig& cfg, LiftoffHoldState& s,
                            const MotionPlan& motion, const PlanKnot& measured, hal::TimeNs t_ns, double dt_s,
                            int count, bool gate, PlanWindow& window) {
  const hal::TimeNs step = s.started && t_ns > s.last_call_ns ? t_ns - s.last_call_ns : 0;
  s.started = true;
  s.last_call_ns = t_ns;
  if (cfg.enabled && gate && motion.frame_count > 1 && step > 0) {
    const hal::TimeNs tau = t_ns - s.lag_ns;
    int foot = 0;
    const int lift = next_liftoff(motion, tau, to_ns(cfg.look_ahead_s), foot);
    bool hold = false;
    if (lift >= 0 && lift != s.released_frame) {
      const int stance = 1 - foot;
      motion_plan_sample_rt(model, s.data, motion, motion_plan_frame_time(motion, lift), s.at_lift);
      // A non-finite state fails the comparison: no hold from it (the MPC refuses it).
      s.last_excess_m = capture_point_outside(cfg, measured, stance) -
                        std::max(capture_point_outside(cfg, s.at_lift, stance), 0.0);
      // Only while both feet still hold ξ: outside them, towards the swing foot's side (a
      // push), the step the motion is about to take is what catches it.
      if (s.last_excess_m > cfg.tolerance_m && capture_point_inside_both(cfg, measured)) {
        if (s.held_ns + step <= to_ns(cfg.max_hold_s)) {
          if (s.held_ns == 0) ++s.holds;
          s.held_ns += step;
          s.lag_ns += step;
          ++s.held_calls;
          hold = true;
        } else if (s.held_ns > 0) {
          ++s.released;
          s.released_frame = lift;
          s.held_ns = 0;
        }
      } else {
        s.held_ns = 0;
      }
    } else {
      s.held_ns = 0;
    }
    if (!hold && s.held_ns == 0 && s.lag_ns > 0 && both_down(motion, tau, to_ns(cfg.catch_up_quiet_s))) {
      s.lag_ns -= std::min(s.lag_ns, static_cast<hal::TimeNs>(std::llround(cfg.catch_up_rate * static_cast<double>(step))));
    }
    s.lag_max_ns = std::max(s.lag_max_ns, s.lag_ns);
  }
  motion_plan_window_rt(model, s.data, motion, t_ns - s.lag_ns, dt_s, count, window);
  if (s.lag_ns != 0) {
    for (int k = 0; k < window.count; ++k) window.knots[k].stamp_ns += s.lag_ns;
  }
}

}  // namespace kuavo::planner
