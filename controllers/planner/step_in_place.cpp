#include "controllers/planner/step_in_place.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/planner/leg_ik.h"

namespace kuavo::planner {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kIkTolerance_m = 1e-3;

// Minimum-jerk 0 → 1 (zero velocity and acceleration at both ends).
double smooth_step(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
}

}  // namespace

const char* make_step_in_place(const model::Model& model, const dynamics::ConfigVector& q_stand,
                               const StepInPlaceConfig& config, MotionPlan& plan) {
  if (config.steps < 0 || !(config.rate_hz > 0.0) || !(config.lead_in_s >= 0.0) || !(config.shift_s > 0.0) ||
      !(config.swing_s > 0.0) || !(config.lift_m >= 0.0 && config.lift_m < 0.3) || !(config.tail_s >= 0.0) ||
      !(config.shift_fraction >= 0.0 && config.shift_fraction <= 1.2)) {
    return "step-in-place configuration out of range";
  }
  const double cycle_s = config.shift_s + config.swing_s;
  const double duration_s = config.lead_in_s + config.steps * cycle_s + config.shift_s + config.tail_s;
  const int frames = static_cast<int>(std::floor(duration_s * config.rate_hz)) + 1;
  if (frames > kMaxMotionFrames) return "step-in-place motion longer than kMaxMotionFrames";

  auto data = std::make_unique<dynamics::Data>();
  dynamics::forward_kinematics(model, *data, q_stand);
  std::array<Vec3, kNumPoints> home{};
  for (int c = 0; c < kNumPoints; ++c) home[c] = dynamics::frame_position(model, *data, c);
  // Lateral offset of each foot's centre from the base.
  double foot_y[2];
  for (int foot = 0; foot < 2; ++foot) {
    double y = 0.0;
    for (int c = 0; c < kCornersPerFoot; ++c) y += home[foot * kCornersPerFoot + c].y();
    foot_y[foot] = y / kCornersPerFoot - q_stand[1];
  }

  plan.rate_hz = config.rate_hz;
  plan.frame_count = frames;
  plan.start_ns = 0;
  dynamics::ConfigVector q = q_stand;
  for (int i = 0; i < frames; ++i) {
    const double t = i / config.rate_hz;
    // Which step and where in it; the stance foot of step k is the right one for even k
    // (the left foot swings first).
    double base_y = 0.0;
    std::array<bool, 2> contact{true, true};
    std::array<Vec3, kNumPoints> targets = home;
    const double u = t - config.lead_in_s;
    auto side = [&](int k) { return config.shift_fraction * foot_y[k % 2 == 0 ? kRightFoot : kLeftFoot]; };
    if (u > 0.0) {
      const int k = std::min(static_cast<int>(u / cycle_s), config.steps);
      const double w = u - k * cycle_s;
      const double from = k == 0 ? 0.0 : side(k - 1);
      const double to = k < config.steps ? side(k) : 0.0;
      base_y = from + (to - from) * smooth_step(w / config.shift_s);
      if (k < config.steps && w > config.shift_s) {
        const double s = (w - config.shift_s) / config.swing_s;
        const int swing = k % 2 == 0 ? kLeftFoot : kRightFoot;
        if (s < 1.0) {
          contact[swing] = false;
          const double lift = config.lift_m * 0.5 * (1.0 - std::cos(2.0 * kPi * s));
          for (int c = 0; c < kCornersPerFoot; ++c) targets[swing * kCornersPerFoot + c].z() += lift;
        }
      }
    }
    q[1] = q_stand[1] + base_y;
    if (solve_leg_ik(model, *data, targets, q) > kIkTolerance_m) return "step-in-place: leg IK missed a foot target by more than 1 mm";
    plan.q[i] = q;
    plan.foot_contact[i] = contact;
  }
  return motion_plan_finish(plan);
}

}  // namespace kuavo::planner
