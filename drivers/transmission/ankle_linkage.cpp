#include "drivers/transmission/ankle_linkage.h"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

namespace kuavo::drivers {

namespace {

using Vec3 = Eigen::Vector3d;

Vec3 rot_y(double a, const Vec3& v) {
  const double c = std::cos(a), s = std::sin(a);
  return {c * v.x() + s * v.z(), v.y(), -s * v.x() + c * v.z()};
}
Vec3 rot_y_deriv(double a, const Vec3& v) {
  const double c = std::cos(a), s = std::sin(a);
  return {-s * v.x() + c * v.z(), 0.0, -c * v.x() - s * v.z()};
}
Vec3 rot_x(double a, const Vec3& v) {
  const double c = std::cos(a), s = std::sin(a);
  return {v.x(), c * v.y() - s * v.z(), s * v.y() + c * v.z()};
}
Vec3 rot_x_deriv(double a, const Vec3& v) {
  const double c = std::cos(a), s = std::sin(a);
  return {0.0, -s * v.y() - c * v.z(), c * v.y() - s * v.z()};
}

// Foot anchor i in the shank frame: pitch (y) is the parent of roll (x).
Vec3 foot_point(const AnkleGeometry& g, int i, const Vec2& q) {
  return g.ankle_centre_m + rot_y(q[0], rot_x(q[1], g.foot_anchor_m[i]));
}
Vec3 crank_end(const AnkleGeometry& g, int i, double phi) {
  return g.crank_pivot_m[i] + rot_y(phi, g.crank_arm_m[i]);
}

// Solves |pivot + Ry(phi) e - F|^2 = L^2 for phi: A cos(phi) + B sin(phi) = K.
// Returns both candidates via alpha and delta: phi = alpha + branch * delta.
bool crank_solutions(const AnkleGeometry& g, int i, const Vec3& foot, double& alpha, double& delta) {
  const Vec3 d = foot - g.crank_pivot_m[i];
  const Vec3& e = g.crank_arm_m[i];
  const double A = d.x() * e.x() + d.z() * e.z();
  const double B = d.x() * e.z() - d.z() * e.x();
  const double K =
      0.5 * (e.squaredNorm() + d.squaredNorm() - g.rod_length_m[i] * g.rod_length_m[i]) - d.y() * e.y();
  const double R = std::hypot(A, B);
  if (!(R > 0.0) || std::abs(K) > R) return false;
  alpha = std::atan2(B, A);
  delta = std::acos(K / R);
  return true;
}

double wrap_pi(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

AnkleGeometry left_raw() {
  AnkleGeometry g;
  g.ankle_centre_m = Vec3(-0.00043, 0.0, -0.346);  // leg_l5_joint origin (FACTS.md §2.2)
  g.crank_pivot_m = {Vec3(0.0, 0.0318, -0.090), Vec3(0.0, -0.0362, -0.153)};
  g.crank_arm_m = {Vec3(-0.056027, -0.0085, 0.015), Vec3(-0.056027, 0.0085, 0.015)};
  g.foot_anchor_m = {Vec3(-0.056027, 0.0255, 0.015), Vec3(-0.056027, -0.0255, 0.015)};
  g.rod_length_m = {0.0, 0.0};
  return g;
}

}  // namespace

void finish_ankle_geometry(AnkleGeometry& g) {
  const Vec2 zero = Vec2::Zero();
  for (int i = 0; i < 2; ++i) {
    if (g.rod_length_m[i] <= 0.0) g.rod_length_m[i] = (crank_end(g, i, 0.0) - foot_point(g, i, zero)).norm();
    double alpha = 0.0, delta = 0.0;
    g.branch[i] = 1;
    if (crank_solutions(g, i, foot_point(g, i, zero), alpha, delta)) {
      g.branch[i] = std::abs(wrap_pi(alpha + delta)) <= std::abs(wrap_pi(alpha - delta)) ? 1 : -1;
    }
  }
}

AnkleGeometry make_left_ankle() {
  AnkleGeometry g = left_raw();
  finish_ankle_geometry(g);
  return g;
}

AnkleGeometry make_right_ankle() {
  // The right leg mirrors the left in y (FACTS.md §2.4); the ankle centre is the
  // right leg's own URDF value.
  AnkleGeometry g = left_raw();
  g.ankle_centre_m = Vec3(0.00012, 0.0, -0.346);
  for (int i = 0; i < 2; ++i) {
    g.crank_pivot_m[i].y() *= -1.0;
    g.crank_arm_m[i].y() *= -1.0;
    g.foot_anchor_m[i].y() *= -1.0;
  }
  finish_ankle_geometry(g);
  return g;
}

bool ankle_motor_from_joint_rt(const AnkleGeometry& g, const Vec2& q, Vec2& motor) {
  Vec2 out;
  for (int i = 0; i < 2; ++i) {
    double alpha = 0.0, delta = 0.0;
    if (!crank_solutions(g, i, foot_point(g, i, q), alpha, delta)) return false;
    out[i] = wrap_pi(alpha + g.branch[i] * delta);
  }
  motor = out;
  return true;
}

Mat2 ankle_jacobian_rt(const AnkleGeometry& g, const Vec2& q, const Vec2& motor) {
  // Implicit differentiation of |E_i(phi_i) - F_i(q)|^2 = L_i^2:
  // dphi_i/dq_j = (E - F) . dF/dq_j / ((E - F) . dE/dphi_i).
  Mat2 J;
  for (int i = 0; i < 2; ++i) {
    const Vec3 r = crank_end(g, i, motor[i]) - foot_point(g, i, q);
    const double dphi = r.dot(rot_y_deriv(motor[i], g.crank_arm_m[i]));
    const Vec3 dF_pitch = rot_y_deriv(q[0], rot_x(q[1], g.foot_anchor_m[i]));
    const Vec3 dF_roll = rot_y(q[0], rot_x_deriv(q[1], g.foot_anchor_m[i]));
    J(i, 0) = r.dot(dF_pitch) / dphi;
    J(i, 1) = r.dot(dF_roll) / dphi;
  }
  return J;
}

DriverError ankle_joint_from_motor_rt(const AnkleGeometry& g, const Vec2& motor, Vec2& joint,
                                      int* iterations) {
  Vec2 q = joint.allFinite() ? joint : Vec2::Zero();
  for (int it = 0; it < kAnkleNewtonMaxIterations; ++it) {
    Vec2 m;
    if (!ankle_motor_from_joint_rt(g, q, m)) return DriverError::kTransmissionUnsolved;
    const Vec2 r(wrap_pi(m[0] - motor[0]), wrap_pi(m[1] - motor[1]));
    if (r.cwiseAbs().maxCoeff() < kAnkleNewtonTolerance_rad) {
      joint = q;
      if (iterations != nullptr) *iterations = it;
      return DriverError::kOk;
    }
    const Mat2 J = ankle_jacobian_rt(g, q, m);
    const double det = J.determinant();
    if (!(std::abs(det) > 1e-9)) return DriverError::kTransmissionUnsolved;
    q -= J.inverse() * r;
  }
  return DriverError::kTransmissionUnsolved;
}

}  // namespace kuavo::drivers
