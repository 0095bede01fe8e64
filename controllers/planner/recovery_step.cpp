#include "controllers/planner/recovery_step.h"

#include <algorithm>
#include <cmath>

#include "controllers/planner/leg_ik.h"
#include "controllers/planner/support_polygon.h"

namespace kuavo::planner {
namespace {

using Vec2 = Eigen::Vector2d;

// 0 → 1 with zero slope at both ends (the swing foot leaves and lands at rest).
double smooth(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * (3.0 - 2.0 * s);
}

double fraction(hal::TimeNs t, hal::TimeNs a, hal::TimeNs b) {
  if (b <= a) return t >= b ? 1.0 : 0.0;
  return static_cast<double>(t - a) / static_cast<double>(b - a);
}

// The foot's displacement at time t, and the height its swing arc adds.
Vec2 displacement_at(const FootDisplacement& d, hal::TimeNs t, double lift_height_m, double& lift_m) {
  lift_m = 0.0;
  if (!d.active) return Vec2::Zero();
  Vec2 out = d.to;
  if (t < d.land_ns) {
    const double s = fraction(t, d.lift_ns, d.land_ns);
    out = d.from + smooth(s) * (d.to - d.from);
    // sin²: up and down at rest, apex mid-swing.
    if (s > 0.0 && s < 1.0) lift_m = lift_height_m * std::sin(M_PI * s) * std::sin(M_PI * s);
  }
  if (d.return_known && t >= d.return_lift_ns) out *= 1.0 - smooth(fraction(t, d.return_lift_ns, d.return_land_ns));
  return out;
}

bool in_recovery_swing(const FootDisplacement& d, hal::TimeNs t) {
  return d.active && !d.early && t >= d.lift_ns && t < d.land_ns;
}

// Between an early touchdown's trigger and the motion's touchdown: the sole's corners are
// rewritten towards (and then held at) its landing.
bool in_early_touchdown(const FootDisplacement& d, hal::TimeNs t) {
  return d.active && d.early && t >= d.lift_ns && t < d.land_ns;
}

// The motion's next swing of `foot` after `after_ns`, its lift-off searched up to `until_ns`
// (the window's end): fills the return interval once a lift-off is found (touchdown: the
// first frame back in contact; a motion that ends with that foot up keeps the displacement).
void find_return(const MotionPlan& motion, int foot, hal::TimeNs after_ns, hal::TimeNs until_ns, FootDisplacement& d) {
  if (d.return_known) return;
  const int first = motion_plan_frame_at(motion, after_ns);
  const int last = motion_plan_frame_at(motion, until_ns);
  int lift = -1;
  for (int i = first; i <= last; ++i) {
    if (!motion.foot_contact[i][foot]) {
      lift = i;
      break;
    }
  }
  if (lift < 0) return;
  int land = lift;
  while (land < motion.frame_count - 1 && !motion.foot_contact[land][foot]) ++land;
  if (motion.foot_contact[land][foot]) {
    d.return_known = true;
    d.return_lift_ns = motion_plan_frame_time(motion, lift);
    d.return_land_ns = motion_plan_frame_time(motion, land);
  }
}

Vec2 foot_centre(const PlanKnot& knot, int foot) {
  Vec2 c = Vec2::Zero();
  for (int i = 0; i < kCornersPerFoot; ++i) c += knot.point_position_m.segment<2>(3 * (foot * kCornersPerFoot + i));
  return c / kCornersPerFoot;
}

// Unit vector from the heel corners' midpoint to the toe corners' (corners 0, 1 toes; 2, 3 heels).
Vec2 foot_forward(const PlanKnot& knot, int foot) {
  const int c = foot * kCornersPerFoot;
  const Vec2 toe = 0.5 * (knot.point_position_m.segment<2>(3 * c) + knot.point_position_m.segment<2>(3 * (c + 1)));
  const Vec2 heel = 0.5 * (knot.point_position_m.segment<2>(3 * (c + 2)) + knot.point_position_m.segment<2>(3 * (c + 3)));
  const Vec2 d = toe - heel;
  return d.norm() > 1e-6 ? Vec2(d / d.norm()) : Vec2(1.0, 0.0);
}

// The soles cut to where each ankle holds the centre of pressure (issue 20; see
// RecoveryStepConfig::ankle_pitch_capacity_Nm): along the foot's axis, from the ankle, at most
// P / F ahead and behind, never beyond the toes and heels. F, the foot's share of the robot's
// weight, by the lever rule: the CoM's place on the line between the two ankles (all of it on
// the nearer foot beyond either). corners: knot m's soles, world x-y, cut in place.
void cut_to_holdable(const model::Model& model, double capacity_Nm, const PlanKnot& m, std::array<Vec2, kNumPoints>& corners) {
  const Vec2 com = m.com_position_m.head<2>();
  std::array<Vec2, 2> ankle, axis;
  for (int f = 0; f < 2; ++f) {
    const int c0 = f * kCornersPerFoot;
    axis[f] = foot_forward(m, f);
    const Vec2 heel = 0.5 * (corners[c0 + 2] + corners[c0 + 3]);
    ankle[f] = heel - model.frames[c0 + 2].position_m.x() * axis[f];  // the heels sit behind the ankle axis
  }
  const Vec2 lr = ankle[0] - ankle[1];
  const double w_left = lr.squaredNorm() > 1e-9 ? std::clamp((com - ankle[1]).dot(lr) / lr.squaredNorm(), 0.0, 1.0) : 0.5;
  const double weight_N = model.total_mass_kg * model::kGravity_m_s2;
  for (int f = 0; f < 2; ++f) {
    const int c0 = f * kCornersPerFoot;
    const double reach = capacity_Nm / std::max((f == 0 ? w_left : 1.0 - w_left) * weight_N, 1.0);
    const double ahead = std::min(model.frames[c0].position_m.x(), reach);
    const double behind = std::min(-model.frames[c0 + 2].position_m.x(), reach);
    for (int i = 0; i < kCornersPerFoot; ++i) {
      const double along = (corners[c0 + i] - ankle[f]).dot(axis[f]);
      corners[c0 + i] += (std::clamp(along, -behind, ahead) - along) * axis[f];
    }
  }
}

bool foot_down(const PlanKnot& knot, int foot) {
  for (int i = 0; i < kCornersPerFoot; ++i) {
    if (!knot.in_contact[foot * kCornersPerFoot + i]) return false;
  }
  return true;
}

// The reach box in the stance foot's axes (measured knot m); the swing foot stays on its own side.
Vec2 within_reach(const RecoveryStepConfig& cfg, const PlanKnot& m, int swing, const Vec2& target) {
  const int stance = 1 - swing;
  const Vec2 stance_centre = foot_centre(m, stance);
  const Vec2 ahead = foot_forward(m, stance);
  const Vec2 left(-ahead.y(), ahead.x());
  const double side = swing == 0 ? 1.0 : -1.0;  // the left foot stands to the stance foot's left
  const Vec2 r = target - stance_centre;
  const double x = std::clamp(r.dot(ahead), -cfg.reach_behind_m, cfg.reach_ahead_m);
  const double y = side * std::clamp(side * r.dot(left), cfg.min_width_m, cfg.max_width_m);
  return stance_centre + x * ahead + y * left;
}

struct StepCandidate {
  bool captures = false;
  int swing = 0;
  double margin_m = 0.0;  // of ξ at touchdown inside the support after the step
  Vec2 current = Vec2::Zero(), step = Vec2::Zero();
};

// The step of foot `swing` (the other stands): the centre of pressure at the point of the
// stance sole nearest ξ until touchdown, ξ propagated there, the sole centre overshoot_m
// beyond it, inside the reach box and max_step_m; it captures if ξ at touchdown is inside
// the support the step makes, by step_capture_margin_m. swing_s: lift-off to touchdown.
StepCandidate plan_step(const RecoveryStepConfig& cfg, const RecoveryStepState& st, const PlanKnot& m,
                        const PlanKnot& k0, const std::array<Vec2, kNumPoints>& corners, const Vec2& xi,
                        double omega, int swing, const Vec2& plan_offset, double swing_s) {
  StepCandidate out;
  out.swing = swing;
  const int stance = 1 - swing;
  std::array<Vec2, kCornersPerFoot> stance_corners;
  for (int i = 0; i < kCornersPerFoot; ++i) stance_corners[i] = corners[stance * kCornersPerFoot + i];
  const Polygon2<kCornersPerFoot> stance_sole = convex_hull<kCornersPerFoot>(stance_corners, kCornersPerFoot);
  const Vec2 p = project_into(stance_sole, xi, 0.0);
  const Vec2 xi_t = p + (xi - p) * std::exp(omega * (cfg.lift_delay_s + swing_s));
  const Vec2 away = xi_t - p;
  Vec2 target = xi_t + (away.norm() > 1e-9 ? Vec2(cfg.overshoot_m * away / away.norm()) : Vec2::Zero());

  target = within_reach(cfg, m, swing, target);

  // Displacement from where the motion (and an earlier recovery step) has the foot, bounded.
  const FootDisplacement& d = st.foot[swing];
  double unused = 0.0;
  out.current = d.active ? displacement_at(d, k0.stamp_ns, 0.0, unused) : Vec2::Zero();
  // The window is moved by plan_offset after this call (plan_anchor.h); target is measured.
  out.step = target - plan_offset - (foot_centre(k0, swing) + out.current);
  if (out.step.norm() > cfg.max_step_m) out.step *= cfg.max_step_m / out.step.norm();

  // The support after touchdown: the stance sole and the swing sole moved to its landing.
  const Vec2 shift = foot_centre(k0, swing) + out.current + out.step + plan_offset - foot_centre(m, swing);
  std::array<Vec2, kNumPoints> after = corners;
  for (int i = 0; i < kCornersPerFoot; ++i) after[swing * kCornersPerFoot + i] += shift;
  out.margin_m = signed_margin(convex_hull<kNumPoints>(after, kNumPoints), xi_t);
  out.captures = out.margin_m >= cfg.step_capture_margin_m;
  return out;
}

// Early touchdown: the motion swings one foot now (the other stands until its touchdown);
// if ξ at that touchdown, propagated from the measured state, misses the support it makes
// by early_trigger_m more than the motion's own ξ does, and no landing within reach on the
// motion's clock captures it, the swing lands early_lead_s from now beyond ξ then, if that
// captures; only where the motion's own ξ at its touchdown lies inside the support it makes
// (early_plan_margin_min_m). In double support it does nothing (the step below is for that).
void maybe_land_early(const RecoveryStepConfig& cfg, RecoveryStepState& st, const MotionPlan& motion,
                      hal::TimeNs motion_lag_ns, const PlanKnot& m, const PlanWindow& window, const Vec2& plan_offset,
                      bool blocked) {
  const PlanKnot& k0 = window.knots[0];
  const bool down0 = foot_down(k0, 0), down1 = foot_down(k0, 1);
  if (down0 == down1) {
    st.early_calls = 0;
    return;
  }
  const int swing = down0 ? 1 : 0, stance = 1 - swing;
  if (blocked || !cfg.early_touchdown || st.foot[swing].active) {
    st.early_calls = 0;
    return;
  }
  // The motion's touchdown in the window, the stance foot down until then.
  int land = -1;
  for (int k = 1; k < window.count; ++k) {
    if (!foot_down(window.knots[k], stance)) break;
    if (foot_down(window.knots[k], swing)) {
      land = k;
      break;
    }
  }
  const hal::TimeNs now = k0.stamp_ns;
  const hal::TimeNs early_land = now + static_cast<hal::TimeNs>(std::llround(cfg.early_lead_s * 1e9));
  const hal::TimeNs gain = static_cast<hal::TimeNs>(std::llround(cfg.early_min_gain_s * 1e9));
  if (land < 0 || window.knots[land].stamp_ns - early_land < gain) {
    st.early_calls = 0;
    return;
  }
  const PlanKnot& touchdown = window.knots[land];
  // Only in a long swing: from the motion's lift-off of this foot (its frames, motion_lag_ns
  // behind the knots) to the knot it lands on lasts early_min_swing_s. The frame at knot 0 is in
  // that swing (the window is sampled from it with the same lag); if it is not, nothing is
  // measured and nothing lands early. The scan reads at most the swing's frames.
  if (cfg.early_min_swing_s > 0.0) {
    int lift = motion_plan_frame_at(motion, now - motion_lag_ns);
    if (motion.foot_contact[lift][swing]) {
      st.early_calls = 0;
      return;
    }
    while (lift > 0 && !motion.foot_contact[lift - 1][swing]) --lift;
    const hal::TimeNs lift_ns = motion_plan_frame_time(motion, lift) + motion_lag_ns;
    if (1e-9 * static_cast<double>(touchdown.stamp_ns - lift_ns) < cfg.early_min_swing_s) {
      st.early_calls = 0;
      return;
    }
  }
  const double t_motion = 1e-9 * static_cast<double>(touchdown.stamp_ns - now);

  // The measured state's ξ at the motion's touchdown, and the motion's own (its first knot, as
  // the motion has it: not moved by a displacement held on the stance foot, which moves the
  // support but not the dance's CoM): the pendulum over the stance sole, measured coordinates
  // (the window's plus plan_offset).
  std::array<Vec2, kNumPoints> corners;  // stance sole, then the swing sole at its landing
  std::array<Vec2, kNumPoints> planned;
  double stance_z = 0.0, planned_z = 0.0;
  for (int i = 0; i < kCornersPerFoot; ++i) {
    const int c = stance * kCornersPerFoot + i;
    corners[i] = m.point_position_m.segment<2>(3 * c);
    planned[i] = k0.point_position_m.segment<2>(3 * c) + plan_offset;
    stance_z += m.point_position_m[3 * c + 2] / kCornersPerFoot;
    planned_z += k0.point_position_m[3 * c + 2] / kCornersPerFoot;
    corners[kCornersPerFoot + i] = touchdown.point_position_m.segment<2>(3 * (swing * kCornersPerFoot + i)) + plan_offset;
    planned[kCornersPerFoot + i] = corners[kCornersPerFoot + i];
  }
  std::array<Vec2, kCornersPerFoot> stance_corners, planned_stance;
  for (int i = 0; i < kCornersPerFoot; ++i) stance_corners[i] = corners[i], planned_stance[i] = planned[i];
  const Polygon2<kCornersPerFoot> stance_sole = convex_hull<kCornersPerFoot>(stance_corners, kCornersPerFoot);
  const CapturePoint cp = capture_point(m, stance_z, cfg.min_pendulum_height_m);
  const Vec2 p = project_into(stance_sole, cp.xi, 0.0);
  const Vec2 xi_motion = p + (cp.xi - p) * std::exp(cp.omega * t_motion);
  const double margin_motion = signed_margin(convex_hull<kNumPoints>(corners, kNumPoints), xi_motion);
  CapturePoint plan_cp = capture_point(k0, planned_z, cfg.min_pendulum_height_m);
  plan_cp.xi += plan_offset;
  const Vec2 plan_p = project_into(convex_hull<kCornersPerFoot>(planned_stance, kCornersPerFoot), plan_cp.xi, 0.0);
  const Vec2 plan_xi_motion = plan_p + (plan_cp.xi - plan_p) * std::exp(plan_cp.omega * t_motion);
  const double plan_margin = signed_margin(convex_hull<kNumPoints>(planned, kNumPoints), plan_xi_motion);
  // Only where the motion's own touchdown holds its ξ (early_plan_margin_min_m).
  if (!(plan_margin >= cfg.early_plan_margin_min_m)) {
    st.early_calls = 0;
    return;
  }
  // Beyond the motion's own (a dance's swing may plan ξ outside: the next double support
  // brings it back). A non-finite state fails the comparison: no early touchdown from it.
  if (!(margin_motion < std::min(plan_margin, 0.0) - cfg.early_trigger_m)) {
    st.early_calls = 0;
    return;
  }

  // A landing beyond ξ at time t from now, within reach: its step from the motion's landing
  // (window coordinates) and the margin of ξ then inside the support it makes.
  Vec2 centre = Vec2::Zero();  // of the motion's landing, window coordinates
  for (int i = 0; i < kCornersPerFoot; ++i) {
    centre += touchdown.point_position_m.segment<2>(3 * (swing * kCornersPerFoot + i)) / kCornersPerFoot;
  }
  const auto landing = [&](double t, Vec2& step) {
    const Vec2 xi_t = p + (cp.xi - p) * std::exp(cp.omega * t);
    const Vec2 away = xi_t - p;
    const Vec2 beyond = away.norm() > 1e-9 ? Vec2(cfg.overshoot_m * away / away.norm()) : Vec2::Zero();
    const Vec2 target = within_reach(cfg, m, swing, xi_t + beyond);
    step = target - plan_offset - centre;
    if (step.norm() > cfg.max_step_m) step *= cfg.max_step_m / step.norm();
    std::array<Vec2, kNumPoints> after = corners;
    for (int i = 0; i < kCornersPerFoot; ++i) after[kCornersPerFoot + i] += step;
    return signed_margin(convex_hull<kNumPoints>(after, kNumPoints), xi_t);
  };
  // A landing on the motion's clock that captures is the MPC's to find (it adapts the spot).
  Vec2 step = Vec2::Zero();
  if (landing(t_motion, step) >= cfg.capture_margin_m) {
    st.early_calls = 0;
    return;
  }
  if (++st.early_calls < cfg.trigger_calls) return;
  // Landing early_lead_s from now must capture.
  const double margin = landing(cfg.early_lead_s, step);
  if (!(margin >= cfg.capture_margin_m)) {
    ++st.declined;
    st.early_calls = 0;
    return;
  }
  FootDisplacement& d = st.foot[swing];
  d = FootDisplacement{};
  d.active = true;
  d.early = true;
  d.from = step;
  d.to = step;
  d.lift_ns = now;
  d.early_land_ns = early_land;
  d.land_ns = touchdown.stamp_ns;
  for (int i = 0; i < kCornersPerFoot; ++i) {
    d.landing[i] = touchdown.point_position_m.segment<3>(3 * (swing * kCornersPerFoot + i));
  }
  st.early_calls = 0;
  ++st.early_touchdowns;
  return;
}

// Decides and starts a recovery step if the measured state calls for one.
void maybe_trigger(const model::Model& model, const RecoveryStepConfig& cfg, RecoveryStepState& st, const MotionPlan& motion,
                   hal::TimeNs motion_lag_ns, const PlanKnot& m, const PlanWindow& window, const Vec2& plan_offset) {
  const PlanKnot& k0 = window.knots[0];
  const hal::TimeNs now = k0.stamp_ns;

  std::array<Vec2, kNumPoints> corners;
  double sole_z = 0.0;
  for (int c = 0; c < kNumPoints; ++c) {
    corners[c] = m.point_position_m.segment<2>(3 * c);
    sole_z += m.point_position_m[3 * c + 2] / kNumPoints;
  }
  const CapturePoint cp = capture_point(m, sole_z, cfg.min_pendulum_height_m);
  // The trigger's polygon: the soles, or the part of them the ankles hold. The step itself is
  // planned on the soles (plan_step), as before.
  std::array<Vec2, kNumPoints> held = corners;
  if (cfg.ankle_pitch_capacity_Nm > 0.0) cut_to_holdable(model, cfg.ankle_pitch_capacity_Nm, m, held);
  const Polygon2<kNumPoints> support = convex_hull<kNumPoints>(held, kNumPoints);
  const double omega = cp.omega;
  const Vec2 xi = cp.xi;
  st.last_outside_m = -signed_margin(support, xi);

  if (!st.started) {
    st.started = true;
    st.start_ns = now;
  }
  const bool settling = now - st.start_ns < static_cast<hal::TimeNs>(std::llround(cfg.settle_s * 1e9));
  const bool swinging = (st.foot[0].active && now < st.foot[0].land_ns) || (st.foot[1].active && now < st.foot[1].land_ns);
  maybe_land_early(cfg, st, motion, motion_lag_ns, m, window, plan_offset, settling || swinging);
  // A non-finite state fails the comparisons below: no step from it (the MPC refuses it too).
  // creep_outside_m <= trigger_outside_m (validated): a ξ short of the first is short of both.
  if (settling || swinging || !(st.last_outside_m > cfg.creep_outside_m)) {
    st.outside_calls = 0;
    st.creep_calls = 0;
    return;
  }
  st.outside_calls = st.last_outside_m > cfg.trigger_outside_m ? st.outside_calls + 1 : 0;
  ++st.creep_calls;
  if (st.outside_calls < cfg.trigger_calls && st.creep_calls < cfg.creep_calls) return;

  // The motion must keep both feet down until the step has landed and settled.
  const hal::TimeNs lift = now + static_cast<hal::TimeNs>(std::llround(cfg.lift_delay_s * 1e9));
  const hal::TimeNs land = lift + static_cast<hal::TimeNs>(std::llround(cfg.swing_s * 1e9));
  const hal::TimeNs quiet_end = land + static_cast<hal::TimeNs>(std::llround(cfg.quiet_s * 1e9));
  if (window.count < 1 || window.knots[window.count - 1].stamp_ns < quiet_end) return;
  for (int k = 0; k < window.count && window.knots[k].stamp_ns <= quiet_end; ++k) {
    if (!foot_down(window.knots[k], 0) || !foot_down(window.knots[k], 1)) return;
  }

  // Each foot as the swing foot: where it must land, and whether that captures.
  // The motion keeps both feet down until the swing_s step's touchdown and quiet_s (above), so
  // a fast_swing_s step, which lands sooner, fits as well.
  const auto best_step = [&](double swing_s) {
    StepCandidate best;
    for (int swing = 0; swing < 2; ++swing) {
      const StepCandidate c = plan_step(cfg, st, m, k0, corners, xi, omega, swing, plan_offset, swing_s);
      if (c.captures && (!best.captures || c.margin_m > best.margin_m)) best = c;
    }
    return best;
  };
  double swing_s = cfg.swing_s;
  StepCandidate best = best_step(swing_s);
  if (!best.captures && cfg.fast_swing_s > 0.0) {
    swing_s = cfg.fast_swing_s;
    best = best_step(swing_s);
  }
  if (!best.captures) {
    ++st.declined;
    return;
  }
  FootDisplacement& d = st.foot[best.swing];
  d.active = true;
  d.early = false;  // the foot may still hold an early touchdown's displacement: `from` carries it
  d.from = best.current;
  d.to = best.current + best.step;
  d.lift_ns = lift;
  d.land_ns = lift + static_cast<hal::TimeNs>(std::llround(swing_s * 1e9));
  d.return_known = false;
  st.outside_calls = 0;
  st.creep_calls = 0;
  ++st.steps;
  if (swing_s != cfg.swing_s) ++st.fast_steps;
}

}  // namespace

const char* recovery_step_validate(const RecoveryStepConfig& c) {
  const double values[] = {c.trigger_outside_m, c.creep_outside_m, c.lift_delay_s,   c.swing_s,
                           c.lift_height_m,     c.quiet_s,         c.overshoot_m,    c.max_step_m,
                           c.reach_ahead_m,     c.reach_behind_m,  c.min_width_m,    c.max_width_m,
                           c.min_pendulum_height_m, c.settle_s,    c.capture_margin_m, c.step_capture_margin_m,
                           c.early_trigger_m,   c.early_lead_s,    c.early_min_gain_s, c.early_min_swing_s,
                           c.early_plan_margin_min_m, c.ankle_pitch_capacity_Nm, c.fast_swing_s};
  for (double x : values) {
    if (!std::isfinite(x)) return "recovery step: every value must be finite";
  }
  if (c.trigger_calls < 1 || c.creep_calls < 1) return "recovery step: trigger_calls and creep_calls must be at least 1";
  if (c.creep_outside_m > c.trigger_outside_m) return "recovery step: creep_outside_m must not exceed trigger_outside_m";
  if (c.lift_delay_s < 0.0 || c.swing_s < 0.1 || c.quiet_s < 0.0) return "recovery step: lift_delay_s >= 0, swing_s >= 0.1, quiet_s >= 0";
  if (c.lift_height_m < 0.0 || c.lift_height_m > 0.15) return "recovery step: lift_height_m must be in [0, 0.15]";
  if (c.max_step_m <= 0.0 || c.max_step_m > 0.5) return "recovery step: max_step_m must be in (0, 0.5]";
  if (c.min_width_m <= 0.0 || c.max_width_m < c.min_width_m) return "recovery step: need 0 < min_width_m <= max_width_m";
  if (c.reach_ahead_m < 0.0 || c.reach_behind_m < 0.0) return "recovery step: reach must be >= 0";
  if (c.settle_s < 0.0) return "recovery step: settle_s must be >= 0";
  if (c.capture_margin_m < 0.0 || c.step_capture_margin_m < 0.0) {
    return "recovery step: capture_margin_m and step_capture_margin_m must be >= 0";
  }
  if (c.fast_swing_s != 0.0 && !(c.fast_swing_s >= 0.1 && c.fast_swing_s <= c.swing_s)) {
    return "recovery step: fast_swing_s must be 0 (off) or in [0.1, swing_s]";
  }
  if (c.ankle_pitch_capacity_Nm < 0.0) return "recovery step: ankle_pitch_capacity_Nm must be >= 0 (0: off)";
  if (c.min_pendulum_height_m <= 0.0) return "recovery step: min_pendulum_height_m must be > 0";
  if (c.early_trigger_m < 0.0 || c.early_lead_s < 0.05 || c.early_min_gain_s < 0.0 || c.early_min_swing_s < 0.0) {
    return "recovery step: early_trigger_m >= 0, early_lead_s >= 0.05, early_min_gain_s >= 0, early_min_swing_s >= 0";
  }
  return nullptr;
}

void recovery_step_reset(RecoveryStepState& state) {
  state.outside_calls = 0;
  state.creep_calls = 0;
  state.started = false;
  state.foot = {};
  state.steps = 0;
  state.fast_steps = 0;
  state.declined = 0;
  state.early_touchdowns = 0;
  state.early_calls = 0;
  state.last_outside_m = 0.0;
  state.cache_count = 0;
  state.cache_valid = {};
}

void recovery_step_rt(const model::Model& model, const RecoveryStepConfig& cfg, RecoveryStepState& st,
                      const MotionPlan& motion, const PlanKnot& measured, PlanWindow& window,
                      hal::TimeNs motion_lag_ns, const Eigen::Vector2d& plan_offset) {
  if (!cfg.enabled || window.count < 2 || motion.frame_count < 1) return;
  const hal::TimeNs now = window.knots[0].stamp_ns;
  const hal::TimeNs end = window.knots[window.count - 1].stamp_ns;

  // Displacements whose return swing is over are done.
  for (FootDisplacement& d : st.foot) {
    if (d.active && d.return_known && now >= d.return_land_ns) d = FootDisplacement{};
  }
  maybe_trigger(model, cfg, st, motion, motion_lag_ns, measured, window, plan_offset);
  for (int foot = 0; foot < 2; ++foot) {
    FootDisplacement& d = st.foot[foot];
    if (d.active && end > d.land_ns && !d.return_known) {
      // The motion's times are the knots' minus the lag.
      find_return(motion, foot, std::max(now, d.land_ns) - motion_lag_ns, end - motion_lag_ns, d);
      if (d.return_known) d.return_lift_ns += motion_lag_ns, d.return_land_ns += motion_lag_ns;
    }
  }
  if (!st.foot[0].active && !st.foot[1].active) return;

  // Re-solve every knot a displacement touches (or take it from the previous call's).
  const double dt = window.dt_s;
  const int old_count = st.cache_count;
  const hal::TimeNs step_ns = static_cast<hal::TimeNs>(std::llround(dt * 1e9));
  const hal::TimeNs shift_ns = old_count > 0 ? now - st.cache[0].stamp_ns : -1;
  const int shift = shift_ns >= 0 && step_ns > 0 && shift_ns % step_ns == 0 ? static_cast<int>(shift_ns / step_ns) : -1;
  for (int k = 0; k < window.count; ++k) {
    PlanKnot& knot = window.knots[k];
    KnotRewrite rw;
    st.q[k] = knot.q;
    st.changed[k] = false;
    st.hit[k] = -1;
    std::array<Vec3, kNumPoints> targets;
    for (int c = 0; c < kNumPoints; ++c) targets[c] = knot.point_position_m.segment<3>(3 * c);
    for (int foot = 0; foot < 2; ++foot) {
      const FootDisplacement& fd = st.foot[foot];
      if (in_early_touchdown(fd, knot.stamp_ns)) {
        // Towards the landing (moved by `to`) until early_land_ns, then down on it.
        const bool down = knot.stamp_ns >= fd.early_land_ns;
        const double s = down ? 1.0 : smooth(fraction(knot.stamp_ns, fd.lift_ns, fd.early_land_ns));
        rw.d[foot] = fd.to;
        rw.early[foot] = s;
        st.changed[k] = true;
        for (int i = 0; i < kCornersPerFoot; ++i) {
          Vec3 landing = fd.landing[i];
          landing.head<2>() += fd.to;
          Vec3& t = targets[foot * kCornersPerFoot + i];
          t = (1.0 - s) * t + s * landing;
          if (down) knot.in_contact[foot * kCornersPerFoot + i] = true;
        }
        continue;
      }
      double lift = 0.0;
      const Vec2 d = displacement_at(fd, knot.stamp_ns, cfg.lift_height_m, lift);
      rw.d[foot] = d;
      rw.lift[foot] = lift;
      rw.swing[foot] = in_recovery_swing(st.foot[foot], knot.stamp_ns);
      if (rw.swing[foot]) {
        for (int i = 0; i < kCornersPerFoot; ++i) knot.in_contact[foot * kCornersPerFoot + i] = false;
        st.changed[k] = true;
      }
      if (d.squaredNorm() == 0.0 && lift == 0.0) continue;
      st.changed[k] = true;
      for (int i = 0; i < kCornersPerFoot; ++i) {
        Vec3& t = targets[foot * kCornersPerFoot + i];
        t.head<2>() += d;
        t.z() += lift;
      }
    }
    // Entry j = k + shift is read before this call overwrites it (entries ≤ k are written).
    const int j = shift >= 0 ? k + shift : -1;
    if (st.changed[k] && j >= 0 && j < old_count && st.cache_valid[j]) {
      const RecoveryStepState::CachedKnot& e = st.cache[j];
      if (e.stamp_ns == knot.stamp_ns && e.motion_q == knot.q && e.motion_v == knot.v && e.rewrite == rw) {
        st.q[k] = e.q;
        st.hit[k] = j;
      }
    }
    if (st.changed[k] && st.hit[k] < 0) solve_leg_ik(model, st.data, targets, st.q[k]);
    RecoveryStepState::CachedKnot& entry = st.cache[k];  // its .out is written below
    entry.stamp_ns = knot.stamp_ns;
    entry.motion_q = knot.q;
    entry.motion_v = knot.v;
    entry.rewrite = rw;
    entry.q = st.q[k];
    st.cache_valid[k] = st.changed[k];
  }
  // Leg velocities: the motion's plus the rate of the re-solve's change (central differences).
  for (int k = 0; k < window.count; ++k) {
    st.leg_delta[k] = st.q[k].segment<12>(7 + model::kLeftLegFirst) - window.knots[k].q.segment<12>(7 + model::kLeftLegFirst);
  }
  for (int k = 0; k < window.count; ++k) {
    const int a = std::max(k - 1, 0), b = std::min(k + 1, window.count - 1);
    if (!st.changed[a] && !st.changed[k] && !st.changed[b]) continue;
    PlanKnot& knot = window.knots[k];
    // The same knot and neighbours as last call's (interior there and here): its rewrite.
    const int j = st.hit[k];
    if (j > 0 && j + 1 < old_count && k > 0 && k + 1 < window.count && st.hit[k - 1] == j - 1 &&
        st.hit[k + 1] == j + 1) {
      knot = st.cache[j].out;
    } else {
      dynamics::VelocityVector vk = knot.v;
      vk.segment<12>(6 + model::kLeftLegFirst) += (st.leg_delta[b] - st.leg_delta[a]) / (dt * (b - a));
      const ContactFlags flags = knot.in_contact;
      plan_knot_from_state(model, st.data, st.q[k], vk, flags, knot.stamp_ns, knot);
    }
    st.cache[k].out = knot;
  }
  st.cache_count = window.count;
}

}  // namespace kuavo::planner
