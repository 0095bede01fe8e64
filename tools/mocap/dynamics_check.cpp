#include "tools/mocap/dynamics_check.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "controllers/planner/support_polygon.h"
#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"

namespace kuavo::mocap {
namespace {

using dynamics::ConfigVector;
using dynamics::Mat3;
using dynamics::Vec3;
using dynamics::VelocityVector;

constexpr int kPoints = model::kNumContactPoints;
// Tikhonov term of the least-norm force distribution [relative to J Jᵀ's O(1) entries].
constexpr double kDistributionRegularization = 1e-9;

}  // namespace

VelocityVector config_rate(const ConfigVector& qa, const ConfigVector& qb, double dt) {
  VelocityVector v;
  const Eigen::Quaterniond ra(qa[6], qa[3], qa[4], qa[5]), rb(qb[6], qb[3], qb[4], qb[5]);
  v.head<3>() = ra.toRotationMatrix().transpose() * (qb.head<3>() - qa.head<3>()) / dt;
  Eigen::Quaterniond dq = ra.conjugate() * rb;
  if (dq.w() < 0.0) dq.coeffs() *= -1.0;  // the short way round (q and −q are one rotation)
  const Eigen::AngleAxisd d(dq);
  v.segment<3>(3) = d.angle() * d.axis() / dt;
  v.tail<model::kNumJoints>() = (qb.tail<model::kNumJoints>() - qa.tail<model::kNumJoints>()) / dt;
  return v;
}


void frame_rates(const std::vector<ConfigVector>& q, double rate_hz, std::vector<VelocityVector>& v,
                 std::vector<VelocityVector>& a) {
  const int n = static_cast<int>(q.size());
  const double dt = 1.0 / rate_hz;
  v.assign(n, VelocityVector::Zero());
  a.assign(n, VelocityVector::Zero());
  for (int i = 1; i + 1 < n; ++i) {
    const VelocityVector in = config_rate(q[i - 1], q[i], dt), out = config_rate(q[i], q[i + 1], dt);
    v[i] = 0.5 * (in + out);
    a[i] = (out - in) / dt;
  }
}

void check_dynamics(const model::Model& robot, const std::vector<ConfigVector>& q,
                    const std::vector<ContactLabel>& contacts, double rate_hz, const std::vector<ForceVector>* forces,
                    double mu, DynamicsCheck& out) {
  const int n = static_cast<int>(q.size());
  out = DynamicsCheck{};
  out.frames = n;
  out.tau_Nm.resize(n);
  out.zmp_m.resize(n);
  out.zmp_outside_m.assign(n, 0.0);
  out.forces_N.resize(n);
  std::vector<VelocityVector> v, a;
  frame_rates(q, rate_hz, v, a);
  auto data = std::make_unique<dynamics::Data>();
  std::array<dynamics::FrameJacobian, kPoints> jac;
  double force_sum = 0.0, moment_sum = 0.0;
  const drivers::AnkleMotors ankle_motors = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot));
  out.ankle_slots_are_motors = ankle_motors.active;
  for (int i = 0; i < n; ++i) {
    dynamics::forward_kinematics(robot, *data, q[i]);
    dynamics::forward_velocities(robot, *data, v[i]);
    dynamics::rnea(robot, *data, a[i], true);
    const VelocityVector needed = data->tau;  // generalized force the motion needs
    std::array<bool, kPoints> stance{};
    std::array<Vec3, kPoints> corner;
    for (int c = 0; c < kPoints; ++c) {
      stance[c] = c < 4 ? left_in_contact(contacts[i]) : right_in_contact(contacts[i]);
      corner[c] = dynamics::frame_position(robot, *data, c);
      dynamics::frame_jacobian(robot, *data, c, jac[c]);
    }
    ForceVector f = ForceVector::Zero();
    if (forces) {
      f = (*forces)[i];
    } else {
      // Least-norm stance forces with Σ J_c,baseᵀ f = needed base rows.
      Eigen::Matrix<double, 6, 3 * kPoints> A = Eigen::Matrix<double, 6, 3 * kPoints>::Zero();
      for (int c = 0; c < kPoints; ++c) {
        if (stance[c]) A.middleCols<3>(3 * c) = jac[c].topRows<3>().leftCols<6>().transpose();
      }
      Eigen::Matrix<double, 6, 6> g = A * A.transpose();
      if (g.trace() > 0.0) {
        g.diagonal().array() += kDistributionRegularization * g.trace();
        f = A.transpose() * g.ldlt().solve(needed.head<6>());
      }
    }
    out.forces_N[i] = f;
    VelocityVector tau = needed;
    for (int c = 0; c < kPoints; ++c) tau.noalias() -= jac[c].topRows<3>().transpose() * f.segment<3>(3 * c);
    const double rf = tau.head<3>().norm(), rm = tau.segment<3>(3).norm();
    out.base_force_residual_N_max = std::max(out.base_force_residual_N_max, rf);
    out.base_moment_residual_Nm_max = std::max(out.base_moment_residual_Nm_max, rm);
    force_sum += rf;
    moment_sum += rm;
    out.tau_Nm[i] = tau.tail<model::kNumJoints>();
    std::array<double, model::kNumJoints> ratios;
    for (int j = 0; j < model::kNumJoints; ++j) ratios[j] = std::abs(tau[6 + j]) / robot.limits.torque_Nm[j];
    for (int leg = 0; leg < 2 && ankle_motors.active; ++leg) {  // the ankle slots: their motors
      const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + model::kAnklePitchInLeg;
      Eigen::Vector2d motor;
      if (!drivers::ankle_motor_torques_rt(ankle_motors, leg, Eigen::Vector2d(q[i][7 + j], q[i][8 + j]),
                                           Eigen::Vector2d(tau[6 + j], tau[7 + j]), motor)) {
        continue;  // off the linkage's reach: the joint box stands
      }
      for (int k = 0; k < 2; ++k) ratios[j + k] = std::abs(motor[k]) / ankle_motors.limit_Nm[leg](k);
    }
    const bool single_support = left_in_contact(contacts[i]) != right_in_contact(contacts[i]);
    int frame_violations = 0;
    for (int j = 0; j < model::kNumJoints; ++j) {
      const double ratio = ratios[j];
      if (ratio > 1.0) {
        ++out.torque_violations;
        ++out.torque_violations_by_slot[j];
        ++frame_violations;
        if (single_support) ++out.torque_violations_single_support;
      }
      if (ratio > out.max_torque_ratio) {
        out.max_torque_ratio = ratio;
        out.max_torque_ratio_joint = j;
      }
    }
    if (frame_violations > 0) ++out.torque_violation_frames;
    // Friction and the ZMP of the contact wrench.
    std::array<Eigen::Vector2d, kPoints> pts{};
    int np = 0;
    Vec3 total_f = Vec3::Zero(), total_m = Vec3::Zero();
    for (int c = 0; c < kPoints; ++c) {
      const Vec3 fc = f.segment<3>(3 * c);
      if (!stance[c]) continue;
      pts[np++] = corner[c].head<2>();
      total_f += fc;
      total_m += corner[c].cross(fc);
      const double fz = fc.z();
      if (fz < -kFrictionTolerance_N || std::abs(fc.x()) > mu * fz + kFrictionTolerance_N ||
          std::abs(fc.y()) > mu * fz + kFrictionTolerance_N) {
        ++out.friction_violations;
      }
    }
    if (!forces) {
      // The geometric motion: the ZMP of the wrench it needs, whatever the corners can give.
      const Mat3 r = data->rotation[0];
      total_f = r * needed.head<3>();
      total_m = r * needed.segment<3>(3) + q[i].head<3>().cross(total_f);
    }
    if (np == 0 || total_f.z() <= 0.0) {
      out.zmp_m[i] = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
      out.zmp_outside_m[i] = np == 0 ? 0.0 : 1.0;  // pulling on the floor: counted as far outside
    } else {
      const Eigen::Vector2d zmp(-total_m.y() / total_f.z(), total_m.x() / total_f.z());
      out.zmp_m[i] = zmp;
      const auto hull = planner::convex_hull<kPoints>(pts, np);
      out.zmp_outside_m[i] = std::max(0.0, -planner::signed_margin(hull, zmp));
    }
    out.zmp_outside_m_max = std::max(out.zmp_outside_m_max, out.zmp_outside_m[i]);
  }
  if (n > 0) {
    out.base_force_residual_N_mean = force_sum / n;
    out.base_moment_residual_Nm_mean = moment_sum / n;
  }
}

}  // namespace kuavo::mocap
