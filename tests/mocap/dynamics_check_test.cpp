// The inverse-dynamics oracle (tools/mocap/dynamics_check.h) against closed forms: the
// weight of a standing robot, a base accelerated by hand, the ZMP of a static pose at its
// CoM, friction and torque limits crossed on purpose.
#include "tools/mocap/dynamics_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"
#include "tests/mocap/motion_fixture.h"

namespace kuavo::mocap {
namespace {

using namespace kuavo::mocap::test;

constexpr double kMu = 0.5;  // the MPC's friction coefficient (mpc::MpcConfig)

std::vector<ConfigVector> repeat(const ConfigVector& q, int n) { return std::vector<ConfigVector>(n, q); }

double force_z_sum(const ForceVector& f) {
  double s = 0.0;
  for (int c = 0; c < kCorners; ++c) s += f[3 * c + 2];
  return s;
}
Vec3 force_sum(const ForceVector& f) {
  Vec3 s = Vec3::Zero();
  for (int c = 0; c < kCorners; ++c) s += f.segment<3>(3 * c);
  return s;
}

// Distance from p to the axis-aligned box of the corners [first, first + 4) (a foot at zero
// heading), 0 inside.
double outside_foot(const std::array<Vec3, kCorners>& c, int first, const Eigen::Vector2d& p) {
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (int k = first; k < first + 4; ++k) {
    x0 = std::min(x0, c[k].x()), x1 = std::max(x1, c[k].x());
    y0 = std::min(y0, c[k].y()), y1 = std::max(y1, c[k].y());
  }
  const double dx = std::max({x0 - p.x(), 0.0, p.x() - x1});
  const double dy = std::max({y0 - p.y(), 0.0, p.y() - y1});
  return std::hypot(dx, dy);
}

// The quasi-static joint torques g(q) − Σ J_cᵀ f_c, computed here from the rigid-body
// primitives (the oracle's own formula written out independently).
Eigen::Matrix<double, model::kNumJoints, 1> static_torques(const ConfigVector& q, const ForceVector& f,
                                                           const std::array<bool, kCorners>& stance) {
  dynamics::Data& d = scratch();
  dynamics::forward_kinematics(robot(), d, q);
  dynamics::forward_velocities(robot(), d, dynamics::VelocityVector::Zero());
  dynamics::rnea(robot(), d, dynamics::VelocityVector::Zero(), true);
  dynamics::VelocityVector tau = d.tau;
  dynamics::FrameJacobian j;
  for (int c = 0; c < kCorners; ++c) {
    if (!stance[c]) continue;
    dynamics::frame_jacobian(robot(), d, c, j);
    tau -= j.topRows<3>().transpose() * f.segment<3>(3 * c);
  }
  return tau.tail<model::kNumJoints>();
}

// (a) Standing still on both feet, forces distributed by the oracle: the corners carry the
// weight, nothing else is needed, the ZMP is the CoM's ground projection.
TEST(mocap_dynamics_check, StaticStandCarriesTheWeightWithZmpAtTheCom) {
  const ConfigVector q = standing().q;
  const int n = 12;
  DynamicsCheck out;
  check_dynamics(robot(), repeat(q, n), std::vector<ContactLabel>(n, ContactLabel::kDoubleSupport), kRate_hz,
                 nullptr, kMu, out);
  ASSERT_EQ(out.frames, n);
  ASSERT_EQ(out.forces_N.size(), static_cast<std::size_t>(n));
  const Vec3 com = com_of(q);
  double worst = 0.0;
  for (int i = 0; i < n; ++i) {
    SCOPED_TRACE(i);
    const Vec3 f = force_sum(out.forces_N[i]);
    worst = std::max(worst, std::abs(f.z() - weight_N()));
    // The least-norm distribution is Tikhonov-regularized at 1e-9 of trace(A Aᵀ) (~50):
    // relative error ~1e-9·50/λ_min(A Aᵀ) ~ 1e-6 at most; 1e-3 N on a 540 N weight.
    EXPECT_NEAR(f.z(), weight_N(), 1e-3);
    EXPECT_NEAR(f.x(), 0.0, 1e-3);
    EXPECT_NEAR(f.y(), 0.0, 1e-3);
    // The ZMP of a static wrench is the CoM's ground projection.
    ASSERT_TRUE(out.zmp_m[i].allFinite());
    EXPECT_NEAR(out.zmp_m[i].x(), com.x(), 1e-9);
    EXPECT_NEAR(out.zmp_m[i].y(), com.y(), 1e-9);
    EXPECT_EQ(out.zmp_outside_m[i], 0.0);
  }
  RecordProperty("weight_error_N", number(worst));
  RecordProperty("residual_N", number(out.base_force_residual_N_max));
  EXPECT_LT(out.base_force_residual_N_max, 1e-3);
  EXPECT_LT(out.base_moment_residual_Nm_max, 1e-3);
  EXPECT_EQ(out.zmp_outside_m_max, 0.0);
  EXPECT_EQ(out.friction_violations, 0);
  EXPECT_EQ(out.torque_violations, 0);
  EXPECT_GT(out.max_torque_ratio, 0.0);
  EXPECT_LT(out.max_torque_ratio, 1.0);
}

// (b) The same stand with the contact forces given as zero: the base must be held by
// nothing, so the residual is the whole weight, and its moment the weight's about the base
// origin: m·g·|(c − p)_xy| (the robot moved away from the world origin so a residual
// expressed anywhere else would differ).
TEST(mocap_dynamics_check, ZeroForcesLeaveTheWeightAsResidual) {
  ConfigVector q = standing().q;
  q.head<2>() += Eigen::Vector2d(1.3, -0.7);
  const int n = 5;
  const std::vector<ForceVector> zero(n, ForceVector::Zero());
  DynamicsCheck out;
  check_dynamics(robot(), repeat(q, n), std::vector<ContactLabel>(n, ContactLabel::kDoubleSupport), kRate_hz, &zero,
                 kMu, out);
  const Vec3 com = com_of(q);
  const double lever = (com - q.head<3>()).head<2>().norm();
  EXPECT_NEAR(out.base_force_residual_N_max, weight_N(), 1e-9 * weight_N());
  EXPECT_NEAR(out.base_force_residual_N_mean, weight_N(), 1e-9 * weight_N());
  EXPECT_NEAR(out.base_moment_residual_Nm_max, weight_N() * lever, 1e-9 * weight_N());
  EXPECT_NEAR(out.base_moment_residual_Nm_mean, weight_N() * lever, 1e-9 * weight_N());
  for (int i = 0; i < n; ++i) EXPECT_EQ(out.forces_N[i], ForceVector::Zero());
  // Zero forces are inside every pyramid (f_z = 0 ≥ −tolerance, |f_xy| = 0 ≤ μ·0 + tolerance).
  EXPECT_EQ(out.friction_violations, 0);
}

// frame_rates: a base lifted with constant acceleration (z = ½ a t²) has v = a t and q̈ = a
// at the interior frames (central differences of a quadratic are exact), zero at both ends.
TEST(mocap_dynamics_check, FrameRatesOfAConstantAcceleration) {
  const double a = 2.0, dt = 1.0 / kRate_hz;
  std::vector<ConfigVector> q(15, standing().q);
  for (std::size_t i = 0; i < q.size(); ++i) q[i][2] += 0.5 * a * std::pow(i * dt, 2);
  std::vector<dynamics::VelocityVector> v, acc;
  frame_rates(q, kRate_hz, v, acc);
  ASSERT_EQ(v.size(), q.size());
  ASSERT_EQ(acc.size(), q.size());
  EXPECT_EQ(v.front(), dynamics::VelocityVector::Zero());
  EXPECT_EQ(v.back(), dynamics::VelocityVector::Zero());
  EXPECT_EQ(acc.front(), dynamics::VelocityVector::Zero());
  EXPECT_EQ(acc.back(), dynamics::VelocityVector::Zero());
  for (std::size_t i = 1; i + 1 < q.size(); ++i) {
    SCOPED_TRACE(i);
    // Roundoff of z ~ 0.8 m differenced twice over dt² = 1e-4 s²: ~1e-16·0.8/1e-4 ≈ 1e-12.
    EXPECT_NEAR(v[i][2], a * i * dt, 1e-9);
    EXPECT_NEAR(acc[i][2], a, 1e-8);
    EXPECT_LT((acc[i] - a * dynamics::VelocityVector::Unit(2)).norm(), 1e-8);
  }
}

// (c) The whole robot accelerated upward at a = 2 m/s² (base z = ½ a t²): the floor must
// push m(g + a) at every interior frame, m·g at the two end frames (a motion starts and
// ends at rest).
TEST(mocap_dynamics_check, UpwardAccelerationNeedsMassTimesGPlusA) {
  const double a = 2.0, dt = 1.0 / kRate_hz;
  const int n = 21;
  std::vector<ConfigVector> q(n, standing().q);
  for (int i = 0; i < n; ++i) q[i][2] += 0.5 * a * std::pow(i * dt, 2);
  DynamicsCheck out;
  check_dynamics(robot(), q, std::vector<ContactLabel>(n, ContactLabel::kDoubleSupport), kRate_hz, nullptr, kMu, out);
  const double m = robot().total_mass_kg;
  double worst = 0.0;
  for (int i = 0; i < n; ++i) {
    SCOPED_TRACE(i);
    const double expected = (i == 0 || i == n - 1) ? weight_N() : m * (model::kGravity_m_s2 + a);
    worst = std::max(worst, std::abs(force_z_sum(out.forces_N[i]) - expected));
    // The acceleration of a quadratic by central differences is exact to ~1e-8 m/s² (above),
    // i.e. ~1e-6 N; the distribution's regularization adds ~1e-6 relative: 1e-3 N.
    EXPECT_NEAR(force_z_sum(out.forces_N[i]), expected, 1e-3);
    EXPECT_NEAR(force_sum(out.forces_N[i]).head<2>().norm(), 0.0, 1e-3);
  }
  RecordProperty("force_error_N", number(worst));
  EXPECT_LT(out.base_force_residual_N_max, 1e-3);
  EXPECT_EQ(out.friction_violations, 0);
}

// The standing pose on the left foot only: the CoM lies between the feet, outside the left
// sole, so the geometric ZMP (the CoM) is outside by its distance to that sole, and the
// corners can only hold the weight's moment by pulling on the floor.
TEST(mocap_dynamics_check, SingleSupportWithTheComBesideTheFootIsOutside) {
  const ConfigVector q = standing().q;
  const int n = 4;
  DynamicsCheck out;
  check_dynamics(robot(), repeat(q, n), std::vector<ContactLabel>(n, ContactLabel::kLeftSupport), kRate_hz, nullptr,
                 kMu, out);
  const Vec3 com = com_of(q);
  const double expected = outside_foot(corners_of(q), 0, com.head<2>());
  ASSERT_GT(expected, 0.02);  // the precondition: the CoM is well beside the left sole
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(out.zmp_m[i].x(), com.x(), 1e-9);
    EXPECT_NEAR(out.zmp_m[i].y(), com.y(), 1e-9);
    EXPECT_NEAR(out.zmp_outside_m[i], expected, 1e-9);
    for (int c = 4; c < kCorners; ++c) EXPECT_EQ(out.forces_N[i].segment<3>(3 * c), Vec3::Zero()) << "swing corner";
  }
  EXPECT_NEAR(out.zmp_outside_m_max, expected, 1e-9);
  EXPECT_GE(out.friction_violations, n);  // at least one pulling corner per frame
}

// (d) Given forces: a corner pushed sideways past μ f_z is counted (beyond the 1 N
// tolerance, not within it), a pulling corner is counted, a swing corner is not checked.
TEST(mocap_dynamics_check, FrictionViolationsAreCountedPerStanceCorner) {
  const ConfigVector q = standing().q;
  const int n = 3;
  const auto labels = std::vector<ContactLabel>(n, ContactLabel::kDoubleSupport);
  const double fz = weight_N() / kCorners;
  ForceVector base = ForceVector::Zero();
  for (int c = 0; c < kCorners; ++c) base[3 * c + 2] = fz;
  const auto run = [&](const ForceVector& f, const std::vector<ContactLabel>& l) {
    const std::vector<ForceVector> forces(n, f);
    DynamicsCheck out;
    check_dynamics(robot(), repeat(q, n), l, kRate_hz, &forces, kMu, out);
    return out;
  };
  EXPECT_EQ(run(base, labels).friction_violations, 0);
  ForceVector inside = base;
  inside[0] = kMu * fz + 0.5 * kFrictionTolerance_N;
  EXPECT_EQ(run(inside, labels).friction_violations, 0);
  ForceVector outside = base;
  outside[0] = kMu * fz + 1.5 * kFrictionTolerance_N;  // corner 0 along x
  const DynamicsCheck one = run(outside, labels);
  EXPECT_EQ(one.friction_violations, n);
  for (int i = 0; i < n; ++i) EXPECT_EQ(one.forces_N[i], outside) << "given forces are reported as given";
  ForceVector two = outside;
  two[3 * 5 + 1] = -(kMu * fz + 10.0);  // corner 5 along −y
  EXPECT_EQ(run(two, labels).friction_violations, 2 * n);
  ForceVector pull = base;
  pull[3 * 6 + 2] = -2.0 * kFrictionTolerance_N;  // corner 6 pulls on the floor
  EXPECT_EQ(run(pull, labels).friction_violations, n);
  // The right foot in the air: its corners (here the wild corner 5) are not checked.
  EXPECT_EQ(run(two, std::vector<ContactLabel>(n, ContactLabel::kLeftSupport)).friction_violations, n);
}

// A heel that pulls while the toe pushes puts the ZMP beyond the toe, by a lever rule:
// toe 600 N down at x_t, heel 100 N up at x_h → ZMP x = (600 x_t − 100 x_h)/500, outside
// the sole by 0.2 (x_t − x_h).
TEST(mocap_dynamics_check, ZmpOfGivenForcesFollowsTheLeverRule) {
  const ConfigVector q = standing().q;
  const auto c = corners_of(q);
  const int n = 3;
  ForceVector f = ForceVector::Zero();
  f[3 * 0 + 2] = 300.0, f[3 * 1 + 2] = 300.0;    // left toes
  f[3 * 2 + 2] = -50.0, f[3 * 3 + 2] = -50.0;    // left heels pull
  const std::vector<ForceVector> forces(n, f);
  DynamicsCheck out;
  check_dynamics(robot(), repeat(q, n), std::vector<ContactLabel>(n, ContactLabel::kLeftSupport), kRate_hz, &forces,
                 kMu, out);
  const double xt = 0.5 * (c[0].x() + c[1].x()), xh = 0.5 * (c[2].x() + c[3].x());
  const double yl = 0.25 * (c[0].y() + c[1].y() + c[2].y() + c[3].y());
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(out.zmp_m[i].x(), (600.0 * xt - 100.0 * xh) / 500.0, 1e-9);
    EXPECT_NEAR(out.zmp_m[i].y(), yl, 1e-9);
    EXPECT_NEAR(out.zmp_outside_m[i], 0.2 * (xt - xh), 1e-9);
  }
  EXPECT_EQ(out.friction_violations, 2 * n);  // the two pulling heels
}

// The ankle pair's motor torques (A, B) for joint torques (pitch, roll) by virtual work with a
// finite-difference Jacobian of the linkage's closed-form position map: τ_m = (Jᵀ)⁻¹ τ.
Eigen::Vector2d ankle_motor_torques_fd(const drivers::AnkleMotors& a, int leg, const Eigen::Vector2d& q,
                                       const Eigen::Vector2d& tau) {
  const double h = 1e-6;
  Eigen::Matrix2d J;
  for (int c = 0; c < 2; ++c) {
    Eigen::Vector2d plus, minus;
    EXPECT_TRUE(drivers::ankle_motor_from_joint_rt(a.legs[leg].ankle, q + h * Eigen::Vector2d::Unit(c), plus));
    EXPECT_TRUE(drivers::ankle_motor_from_joint_rt(a.legs[leg].ankle, q - h * Eigen::Vector2d::Unit(c), minus));
    for (int k = 0; k < 2; ++k) {
      J(k, c) = (drivers::motor_position_rad(a.legs[leg].ankle_motor[k], plus[k]) -
                 drivers::motor_position_rad(a.legs[leg].ankle_motor[k], minus[k])) / (2 * h);
    }
  }
  return J.transpose().inverse() * tau;
}

// (d) Torques: 2000 N pushing up under one toe bends the left leg past its limits. The
// oracle's torques equal g(q) − Jᵀf written out here, its counts and worst ratio follow;
// the ankle slots count their two motors against the drives' clamps.
TEST(mocap_dynamics_check, TorqueBeyondTheLimitIsCounted) {
  const ConfigVector q = standing().q;
  const int n = 3;
  ForceVector f = ForceVector::Zero();
  f[2] = 2000.0;  // corner 0, up
  const std::vector<ForceVector> forces(n, f);
  DynamicsCheck out;
  check_dynamics(robot(), repeat(q, n), std::vector<ContactLabel>(n, ContactLabel::kDoubleSupport), kRate_hz,
                 &forces, kMu, out);
  std::array<bool, kCorners> stance;
  stance.fill(true);
  const auto tau = static_torques(q, f, stance);
  const auto& limit = robot().limits.torque_Nm;
  std::array<double, model::kNumJoints> ratio;
  for (int j = 0; j < model::kNumJoints; ++j) ratio[j] = std::abs(tau[j]) / limit[j];
  const drivers::AnkleMotors motors = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot()));
  for (int leg = 0; leg < 2; ++leg) {
    const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + 4;
    const Eigen::Vector2d m = ankle_motor_torques_fd(motors, leg, q.segment<2>(7 + j), tau.segment<2>(j));
    for (int k = 0; k < 2; ++k) ratio[j + k] = std::abs(m[k]) / 27.0;  // kuavo.json: each ankle motor's peak
  }
  int over = 0, worst = -1;
  double worst_ratio = 0.0;
  for (int j = 0; j < model::kNumJoints; ++j) {
    const double r = ratio[j];
    over += r > 1.0 ? 1 : 0;
    if (r > worst_ratio) worst_ratio = r, worst = j;
  }
  ASSERT_GT(over, 0) << "the precondition: 2000 N under a toe exceeds a leg limit";
  for (int i = 0; i < n; ++i) EXPECT_LT((out.tau_Nm[i] - tau).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(out.torque_violations, n * over);
  EXPECT_GT(out.max_torque_ratio, 1.0);
  EXPECT_NEAR(out.max_torque_ratio, worst_ratio, 1e-6);
  EXPECT_EQ(out.max_torque_ratio_joint, worst);
  EXPECT_LT(worst, 2 * model::kLegJoints) << "the worst joint is a leg joint";
  // Where: each slot over its limit counts once per frame, every frame has some, none on one foot.
  EXPECT_TRUE(out.ankle_slots_are_motors);
  for (int j = 0; j < model::kNumJoints; ++j) {
    EXPECT_EQ(out.torque_violations_by_slot[j], ratio[j] > 1.0 ? n : 0) << "slot " << j;
  }
  EXPECT_EQ(out.torque_violation_frames, n);
  EXPECT_EQ(out.torque_violations_single_support, 0);

  // The same push on the left foot alone in the middle frame: only that frame counts as one
  // foot's (the right corners carry no force either way, so the torques are the same).
  std::vector<ContactLabel> labels(n, ContactLabel::kDoubleSupport);
  labels[1] = ContactLabel::kLeftSupport;
  DynamicsCheck single;
  check_dynamics(robot(), repeat(q, n), labels, kRate_hz, &forces, kMu, single);
  EXPECT_EQ(single.torque_violations, n * over);
  EXPECT_EQ(single.torque_violations_single_support, over);
  EXPECT_EQ(single.torque_violation_frames, n);
}

}  // namespace
}  // namespace kuavo::mocap
