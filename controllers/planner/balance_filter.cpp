#include "controllers/planner/balance_filter.h"

#include <algorithm>
#include <cmath>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/planner/leg_ik.h"
#include "controllers/planner/support_polygon.h"

namespace kuavo::planner {
namespace {

using Mat3 = Eigen::Matrix3d;
using Row3 = Eigen::RowVector3d;
constexpr double kIkTolerance_m = 1e-3;
// Terminal weights: the filtered CoM ends where the motion's does, at rest.
constexpr double kTerminalPosition = 1e4, kTerminalVelocity = 1e3, kTerminalAcceleration = 1e2;

struct Frame {
  Vec3 com = Vec3::Zero();
  Polygon2<kNumPoints> support{};
  std::array<Vec3, kNumPoints> corners{};
};

void frame_geometry(const model::Model& model, dynamics::Data& data, const MotionPlan& plan, int i, Frame& f) {
  PlanKnot knot;
  plan_knot_from_state(model, data, plan.q[i], dynamics::VelocityVector::Zero(), {}, 0, knot);
  f.com = knot.com_position_m;
  std::array<Eigen::Vector2d, kNumPoints> pts{};
  int n = 0;
  for (int c = 0; c < kNumPoints; ++c) {
    f.corners[c] = knot.point_position_m.segment<3>(3 * c);
    if (plan.foot_contact[i][c < kCornersPerFoot ? kLeftFoot : kRightFoot]) pts[n++] = f.corners[c].head<2>();
  }
  f.support = n >= 3 ? convex_hull<kNumPoints>(pts, n) : Polygon2<kNumPoints>{};
}

}  // namespace

const char* balance_filter(const model::Model& model, const BalanceFilterConfig& config, MotionPlan& plan,
                           BalanceFilterWorkspace& ws, BalanceFilterReport& report) {
  report = BalanceFilterReport{};
  const int n = plan.frame_count;
  if (n < 3) return "balance filter: the motion needs at least three frames";
  const double dt = 1.0 / plan.rate_hz;
  const double g = model::kGravity_m_s2;

  // 1. Per frame: the motion's CoM, its support polygon and the ZMP reference.
  Frame f;
  for (int i = 0; i < n; ++i) {
    frame_geometry(model, ws.data, plan, i, f);
    ws.com[i] = f.com.head<2>();
    ws.com_height[i] = f.com.z() - 0.25 * (f.corners[0].z() + f.corners[1].z() + f.corners[4].z() + f.corners[5].z());
    ws.has_support[i] = f.support.count >= 3;
    ws.zmp_ref[i] = ws.has_support[i] ? project_into(f.support, ws.com[i], config.support_margin_m) : ws.com[i];
    if (!ws.has_support[i]) ++report.frames_in_flight;
  }
  auto zmp_outside = [&](const std::array<Eigen::Vector2d, kMaxMotionFrames>& com, int i) {
    if (!ws.has_support[i] || i == 0 || i == n - 1) return 0.0;
    const Eigen::Vector2d acc = (com[i + 1] - 2.0 * com[i] + com[i - 1]) / (dt * dt);
    const Eigen::Vector2d zmp = com[i] - ws.com_height[i] / g * acc;
    frame_geometry(model, ws.data, plan, i, f);
    return std::max(0.0, -signed_margin(f.support, zmp));
  };
  for (int i = 0; i < n; ++i) report.zmp_outside_before_m = std::max(report.zmp_outside_before_m, zmp_outside(ws.com, i));

  // 2. Per axis: backward Riccati pass of the LQ tracking problem, forward rollout.
  double zc = 0.0;
  for (int i = 0; i < n; ++i) zc += ws.com_height[i];
  zc /= n;
  Mat3 a;
  a << 1.0, dt, 0.5 * dt * dt, 0.0, 1.0, dt, 0.0, 0.0, 1.0;
  const Vec3 b(dt * dt * dt / 6.0, 0.5 * dt * dt, dt);
  const Row3 c_zmp(1.0, 0.0, -zc / g);
  const Row3 c_com(1.0, 0.0, 0.0);
  auto& filtered = ws.filtered_com;
  for (int axis = 0; axis < 2; ++axis) {
    auto& gains = axis == 0 ? ws.gain_x : ws.gain_y;
    Mat3 p = Vec3(kTerminalPosition, kTerminalVelocity, kTerminalAcceleration).asDiagonal();
    Vec3 s = -kTerminalPosition * ws.com[n - 1][axis] * Vec3::UnitX();
    for (int k = n - 2; k >= 0; --k) {
      const double wz = ws.has_support[k] ? config.zmp_weight : 0.0;
      const Mat3 q = wz * c_zmp.transpose() * c_zmp + config.com_weight * c_com.transpose() * c_com;
      const Vec3 qv = -(wz * ws.zmp_ref[k][axis] * c_zmp.transpose() + config.com_weight * ws.com[k][axis] * c_com.transpose());
      const double h = config.jerk_weight + b.dot(p * b);
      const Row3 gk = b.transpose() * p * a;
      const double hk = b.dot(s);
      gains[k] = {-gk[0] / h, -gk[1] / h, -gk[2] / h, -hk / h};
      const Mat3 p_next = q + a.transpose() * p * a - gk.transpose() * gk / h;
      s = qv + a.transpose() * s - gk.transpose() * (hk / h);
      p = 0.5 * (p_next + p_next.transpose());
    }
    Vec3 x(ws.com[0][axis], 0.0, 0.0);
    for (int k = 0; k < n; ++k) {
      filtered[k][axis] = x[0];
      if (k == n - 1) break;
      const auto& gk = gains[k];
      const double u = gk[0] * x[0] + gk[1] * x[1] + gk[2] * x[2] + gk[3];
      x = a * x + b * u;
    }
  }

  // 3. Move the base by the correction; legs re-solved so the corners keep their paths.
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d shift = filtered[i] - ws.com[i];
    report.max_correction_m = std::max(report.max_correction_m, shift.norm());
    if (shift.norm() > config.max_correction_m) return "balance filter: the motion needs a CoM correction beyond max_correction_m";
    frame_geometry(model, ws.data, plan, i, f);
    dynamics::ConfigVector q = plan.q[i];
    q.head<2>() += shift;
    if (solve_leg_ik(model, ws.data, f.corners, q) > kIkTolerance_m) {
      return "balance filter: leg IK missed a foot corner by more than 1 mm (the corrected base is out of the legs' reach)";
    }
    plan.q[i] = q;
  }
  // The correction is exact for the cart-table model only; measure what the real CoM does.
  for (int i = 0; i < n; ++i) {
    frame_geometry(model, ws.data, plan, i, f);
    ws.com[i] = f.com.head<2>();
  }
  for (int i = 0; i < n; ++i) report.zmp_outside_after_m = std::max(report.zmp_outside_after_m, zmp_outside(ws.com, i));
  return motion_plan_finish(plan);
}

}  // namespace kuavo::planner
