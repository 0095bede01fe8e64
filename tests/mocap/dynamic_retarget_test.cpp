// Dynamic retargeting (tools/mocap/dynamic_retarget.h): the stage torque terms against
// finite differences and against the inverse-dynamics oracle, bad input refused with a
// message, and a motion that is already feasible coming back nearly unchanged (checked by
// the independent oracle, tools/mocap/dynamics_check.h).
#include "tools/mocap/dynamic_retarget.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "controllers/mpc/centroidal_model.h"
#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"
#include "tests/mocap/motion_fixture.h"
#include "tools/mocap/dynamics_check.h"
#include "tools/mocap/feasibility_repair.h"
#include "tools/mocap/motion_plan_io.h"

namespace kuavo::mocap {
namespace {

using namespace kuavo::mocap::test;
using mpc::InputVector;
using mpc::kNu;
using mpc::kNx;
using mpc::StateVector;
using TauVector = Eigen::Matrix<double, mpc::kNumMpcJoints, 1>;

constexpr int kForces = 3 * model::kNumContactPoints;
constexpr double kMu = 0.5;  // DynamicRetargetConfig's OCP friction coefficient (mpc::MpcConfig)

planner::ContactFlags both_feet() {
  planner::ContactFlags c{};
  c.fill(true);
  return c;
}

// A pose that exercises every term: knees bent deeper than standing, arms out of their
// hanging pose, the base rolled, pitched and turned, the head turned.
ConfigVector bent_pose() {
  ConfigVector q = dynamics::neutral_configuration(robot());
  q.tail<model::kNumJoints>() = control::centred_standing_pose(robot(), scratch(), 0.70);
  constexpr int kArms = 7 + 2 * model::kLegJoints;
  const double arms[2 * model::kArmJoints] = {-0.6, 0.4, 0.3, -0.9, 0.2, -0.1, 0.15,
                                              0.3, -0.5, -0.2, -0.4, -0.3, 0.2, -0.1};
  for (int j = 0; j < 2 * model::kArmJoints; ++j) q[kArms + j] = arms[j];
  q[7 + 26] = 0.2, q[7 + 27] = -0.1;  // head
  const Mat3 r = (Eigen::AngleAxisd(0.3, Vec3::UnitZ()) * Eigen::AngleAxisd(-0.08, Vec3::UnitY()) *
                  Eigen::AngleAxisd(0.05, Vec3::UnitX()))
                     .toRotationMatrix();
  set_base_rotation(q, r);
  q.head<2>() = Eigen::Vector2d(0.4, -0.2);
  control::place_on_ground(robot(), scratch(), q);
  return q;
}

StateVector state_of(const ConfigVector& q) {
  StateVector x;
  mpc::state_from_configuration(robot(), scratch(), q, dynamics::VelocityVector::Zero(), x);
  return x;
}

TauVector torque_at(const StateVector& x, const InputVector& u, const mpc::HeadVector& head,
                    const planner::ContactFlags& contact) {
  StageTorque st;
  stage_torque(robot(), scratch(), x, u, head, contact, false, st);
  return st.tau_Nm;
}

// stage_torque's derivatives: the force columns are exact (τ is linear in f: central
// differences with a 1 N step reproduce them to roundoff), the state columns are forward
// differences with the implementation's own step, checked here by central differences
// with a different step (1e-5 rad).
TEST(mocap_dynamic_retarget, StageTorqueDerivativesMatchFiniteDifferences) {
  const ConfigVector q = bent_pose();
  const StateVector x = state_of(q);
  const mpc::HeadVector head = q.tail<2>();
  const planner::ContactFlags contact = both_feet();
  InputVector u = InputVector::Zero();
  for (int c = 0; c < kCorners; ++c) u.segment<3>(3 * c) = Vec3(4.0 - c, 0.5 * c - 2.0, 50.0 + 7.0 * c);
  u.tail<mpc::kNumMpcJoints>().setLinSpaced(-0.5, 0.7);  // joint velocities: no part in a quasi-static torque

  StageTorque st;
  stage_torque(robot(), scratch(), x, u, head, contact, true, st);
  ASSERT_TRUE(st.tau_Nm.allFinite());
  ASSERT_TRUE(st.d_dx.allFinite());
  ASSERT_TRUE(st.d_du.allFinite());

  // Input columns: τ is affine in u, so the central difference is exact up to roundoff
  // (|τ| ~ 100 N·m · 1e-16 / 1 N ≈ 1e-14).
  const double hu = 1.0;
  for (int i = 0; i < kNu; ++i) {
    InputVector up = u, um = u;
    up[i] += hu, um[i] -= hu;
    const TauVector fd = (torque_at(x, up, head, contact) - torque_at(x, um, head, contact)) / (2.0 * hu);
    EXPECT_LT((st.d_du.col(i) - fd).cwiseAbs().maxCoeff(), 1e-9) << "u column " << i;
    if (i >= kForces) {
      EXPECT_EQ(st.d_du.col(i), TauVector::Zero()) << "joint-velocity column " << i;
    }
  }

  // State columns. The implementation's forward difference (step h = 1e-6) is off by
  // ½ h |∂²τ/∂x²|; with corner forces ~100 N on lever arms ≤ 1 m, |∂²τ/∂x²| ≲ 1e3 N·m/rad²,
  // so ≲ 5e-4 N·m/rad, plus its roundoff ε|τ|/h ≈ 1e-8. The central difference here (1e-5)
  // is off by h²/6 |∂³τ| ≈ 2e-8 and ε|τ|/h ≈ 1e-9. Tolerance: that 5e-4 N·m/rad bound
  // (measured: 3.5e-5); a wrong sign, axis or column is off by O(10–100) N·m/rad.
  const double hx = 1e-5;
  double worst = 0.0;
  for (int i = 0; i < kNx; ++i) {
    StateVector xp = x, xm = x;
    xp[i] += hx, xm[i] -= hx;
    const TauVector fd = (torque_at(xp, u, head, contact) - torque_at(xm, u, head, contact)) / (2.0 * hx);
    const double err = (st.d_dx.col(i) - fd).cwiseAbs().maxCoeff();
    worst = std::max(worst, err);
    EXPECT_LT(err, 5e-4) << "x column " << i;
  }
  RecordProperty("d_dx_max_error", number(worst));
  // The derivative is not trivially zero: gravity and the forces load the legs and arms.
  EXPECT_GT(st.d_dx.middleCols<mpc::kNumMpcJoints>(mpc::kXJoints).cwiseAbs().maxCoeff(), 10.0);
  EXPECT_GT(st.d_dx.middleCols<3>(mpc::kXEuler).cwiseAbs().maxCoeff(), 1.0);
}

// A swing foot's corners carry no force term: flags off → τ does not depend on their forces.
TEST(mocap_dynamic_retarget, StageTorqueIgnoresSwingCorners) {
  const ConfigVector q = bent_pose();
  const StateVector x = state_of(q);
  planner::ContactFlags left_only = both_feet();
  for (int c = 4; c < kCorners; ++c) left_only[c] = false;
  InputVector u = InputVector::Zero();
  for (int c = 0; c < kCorners; ++c) u.segment<3>(3 * c) = Vec3(1.0, 2.0, 60.0);
  InputVector u2 = u;
  u2.segment<12>(12).setConstant(500.0);
  StageTorque a, b;
  stage_torque(robot(), scratch(), x, u, q.tail<2>(), left_only, true, a);
  stage_torque(robot(), scratch(), x, u2, q.tail<2>(), left_only, true, b);
  EXPECT_EQ(a.tau_Nm, b.tau_Nm);
  EXPECT_EQ(a.d_du.middleCols<12>(12), (Eigen::Matrix<double, mpc::kNumMpcJoints, 12>::Zero()));
}

// A static pose held by the oracle's least-norm forces: its torques (RNEA) against
// stage_torque's (the MPC state made by state_from_configuration, the oracle's forces as
// its input), and against g(q) − Jᵀf written out here.
void expect_oracle_torques(const ConfigVector& q) {
  const int n = 5;
  DynamicsCheck check;
  check_dynamics(robot(), std::vector<ConfigVector>(n, q),
                 std::vector<ContactLabel>(n, ContactLabel::kDoubleSupport), kRate_hz, nullptr, kMu, check);
  ASSERT_LT(check.base_force_residual_N_max, 1e-3);  // the least-norm forces hold the pose
  const ForceVector& f = check.forces_N[n / 2];
  double fz = 0.0;
  for (int c = 0; c < kCorners; ++c) fz += f[3 * c + 2];
  EXPECT_NEAR(fz, weight_N(), 1e-3);

  InputVector u = InputVector::Zero();
  u.head<kForces>() = f;
  StageTorque st;
  stage_torque(robot(), scratch(), state_of(q), u, q.tail<2>(), both_feet(), false, st);
  const TauVector oracle = check.tau_Nm[n / 2].head<mpc::kNumMpcJoints>();
  // Two routes through the same rigid-body model: equal to roundoff (the Euler-angle round
  // trip of the base orientation costs ~1e-15 rad, × |∂τ/∂e| ~ 100 N·m).
  EXPECT_LT((st.tau_Nm - oracle).cwiseAbs().maxCoeff(), 1e-9);
  ::testing::Test::RecordProperty("oracle_difference_Nm", number((st.tau_Nm - oracle).cwiseAbs().maxCoeff()));
  EXPECT_GT(oracle.head<2 * model::kLegJoints>().cwiseAbs().maxCoeff(), 1.0) << "a loaded pose";

  dynamics::Data& d = scratch();
  dynamics::forward_kinematics(robot(), d, q);
  dynamics::forward_velocities(robot(), d, dynamics::VelocityVector::Zero());
  dynamics::rnea(robot(), d, dynamics::VelocityVector::Zero(), true);
  dynamics::VelocityVector tau = d.tau;
  dynamics::FrameJacobian j;
  for (int c = 0; c < kCorners; ++c) {
    dynamics::frame_jacobian(robot(), d, c, j);
    tau -= j.topRows<3>().transpose() * f.segment<3>(3 * c);
  }
  EXPECT_LT((st.tau_Nm - tau.segment<mpc::kNumMpcJoints>(6)).cwiseAbs().maxCoeff(), 1e-9);
}

// Two independent computations of the same static torques, on the standing pose and on the
// bent, turned and tilted one.
TEST(mocap_dynamic_retarget, StageTorqueEqualsTheOracleOnAStaticPose) {
  {
    SCOPED_TRACE("standing");
    expect_oracle_torques(standing().q);
  }
  {
    SCOPED_TRACE("bent pose");
    expect_oracle_torques(bent_pose());
  }
}

// ---- dynamic_retarget ----

std::unique_ptr<planner::MotionPlan> plan_of(const std::vector<ConfigVector>& q, const std::vector<ContactLabel>& l) {
  auto plan = std::make_unique<planner::MotionPlan>();
  std::string error;
  EXPECT_TRUE(motion_plan_from_frames(q, l, kRate_hz, "test motion", *plan, error)) << error;
  return plan;
}

std::unique_ptr<planner::MotionPlan> standing_plan(double seconds) {
  const int n = static_cast<int>(std::lround(seconds * kRate_hz)) + 1;
  return plan_of(std::vector<ConfigVector>(n, standing().q),
                 std::vector<ContactLabel>(n, ContactLabel::kDoubleSupport));
}

TEST(mocap_dynamic_retarget, RefusesANonFiniteFrame) {
  auto plan = standing_plan(0.5);
  plan->q[17][7 + 3] = std::numeric_limits<double>::quiet_NaN();
  DynamicResult out;
  std::string error;
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, DynamicRetargetConfig{}, out, error));
  EXPECT_NE(error.find("not finite"), std::string::npos) << error;
  EXPECT_NE(error.find("17"), std::string::npos) << error;
}

TEST(mocap_dynamic_retarget, RefusesAStartOutsideDoubleSupport) {
  for (const std::array<bool, 2> start : {std::array<bool, 2>{false, false}, std::array<bool, 2>{true, false},
                                          std::array<bool, 2>{false, true}}) {
    auto plan = standing_plan(0.5);
    for (int i = 0; i < 10; ++i) plan->foot_contact[i] = start;
    DynamicResult out;
    std::string error;
    EXPECT_FALSE(dynamic_retarget(robot(), *plan, DynamicRetargetConfig{}, out, error));
    EXPECT_NE(error.find("double support"), std::string::npos) << error;
  }
}

TEST(mocap_dynamic_retarget, RefusesAFlightAndNamesItsTime) {
  auto plan = standing_plan(1.0);
  for (int i = 40; i < 55; ++i) plan->foot_contact[i] = {false, false};
  DynamicResult out;
  std::string error;
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, DynamicRetargetConfig{}, out, error));
  EXPECT_NE(error.find("flight at 0.40 s"), std::string::npos) << error;
}

TEST(mocap_dynamic_retarget, RefusesABadConfig) {
  auto plan = standing_plan(0.5);
  DynamicResult out;
  std::string error;
  DynamicRetargetConfig cfg;
  cfg.commit_stages = 0;
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, cfg, out, error));
  EXPECT_NE(error.find("commit_stages"), std::string::npos) << error;
  cfg = DynamicRetargetConfig{};
  cfg.ocp.dt_s = -1.0;
  error.clear();
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, cfg, out, error));
  EXPECT_FALSE(error.empty());
  cfg = DynamicRetargetConfig{};
  cfg.support_margin_m = std::numeric_limits<double>::quiet_NaN();
  error.clear();
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, cfg, out, error));
  EXPECT_NE(error.find("support_margin_m"), std::string::npos) << error;
  for (const double w : {-1.0, std::numeric_limits<double>::infinity()}) {
    cfg = DynamicRetargetConfig{};
    cfg.ankle_motor_weight = w;
    error.clear();
    EXPECT_FALSE(dynamic_retarget(robot(), *plan, cfg, out, error));
    EXPECT_NE(error.find("ankle_motor_weight"), std::string::npos) << error;
  }
  cfg = DynamicRetargetConfig{};
  cfg.ankle_motor_share = 1.5;
  error.clear();
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, cfg, out, error));
  EXPECT_NE(error.find("ankle_motor_share"), std::string::npos) << error;
  for (const double t : {0.5e-3, std::numeric_limits<double>::quiet_NaN()}) {
    cfg = DynamicRetargetConfig{};
    cfg.tail_step_tolerance = t;  // below step_tolerance (1e-3), or not a number
    error.clear();
    EXPECT_FALSE(dynamic_retarget(robot(), *plan, cfg, out, error));
    EXPECT_NE(error.find("tail_step_tolerance"), std::string::npos) << error;
  }
  // The online MPC's coarse tail is refused: the windows read their stages as frames.
  cfg = DynamicRetargetConfig{};
  EXPECT_EQ(cfg.ocp.tail_stride, 1);
  cfg.ocp.tail_stride = 4;
  error.clear();
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, cfg, out, error));
  EXPECT_NE(error.find("uniform grid"), std::string::npos) << error;
}

// The planning model's sole corners: each moved in by the margin in x and in y (FACTS.md's
// corners: toe +0.17084, heel -0.073164, sides ±0.04773 on leg_*6_link), nothing else changed.
TEST(mocap_dynamic_retarget, PlanningSoleIsInsetByTheMargin) {
  const double m = 0.015;
  const model::Model planning = planning_model(robot(), m);
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    SCOPED_TRACE(model::frame_name(robot(), c));
    const Vec3& p = robot().frames[c].position_m;
    const Vec3& q = planning.frames[c].position_m;
    EXPECT_NEAR(std::abs(p.x() - q.x()), m, 1e-12);
    EXPECT_NEAR(std::abs(p.y() - q.y()), m, 1e-12);
    EXPECT_EQ(p.z(), q.z());
    EXPECT_NEAR(std::abs(q.y()), 0.04773 - m, 1e-9);
    EXPECT_TRUE(std::abs(q.x() - (0.17084 - m)) < 1e-9 || std::abs(q.x() - (-0.073164 + m)) < 1e-9) << q.x();
    EXPECT_EQ(planning.frames[c].body, robot().frames[c].body);
  }
  const model::Model none = planning_model(robot(), 0.0);
  for (int c = 0; c < model::kNumContactPoints; ++c) EXPECT_EQ(none.frames[c].position_m, robot().frames[c].position_m);
}

// Forces planned on the inset corners, moved onto the robot's: per foot the same force and
// the same moment about the world origin (forward kinematics of a bent, turned pose with both
// models), every corner's force a non-negative multiple of forces in the cone, and a zero
// margin gives the forces back unchanged.
TEST(mocap_dynamic_retarget, InsetForcesMoveOntoTheRobotsCornersWithTheSameWrench) {
  const model::Model planning = planning_model(robot(), 0.02);
  const ConfigVector q = bent_pose();
  auto data_r = std::make_unique<dynamics::Data>();
  auto data_p = std::make_unique<dynamics::Data>();
  dynamics::forward_kinematics(robot(), *data_r, q);
  dynamics::forward_kinematics(planning, *data_p, q);
  CornerForces f;
  for (int c = 0; c < model::kNumContactPoints; ++c) {  // inside the μ = 0.5 pyramid
    f.segment<3>(3 * c) = Vec3(0.3 * std::sin(c + 1.0), 0.3 * std::cos(2.0 * c), 1.0) * (50.0 + 20.0 * c);
  }
  const CornerForces g = forces_on_robot_corners(robot(), planning, f);
  for (int foot = 0; foot < 2; ++foot) {
    Vec3 force_p = Vec3::Zero(), force_r = Vec3::Zero(), moment_p = Vec3::Zero(), moment_r = Vec3::Zero();
    for (int k = 4 * foot; k < 4 * foot + 4; ++k) {
      force_p += f.segment<3>(3 * k), force_r += g.segment<3>(3 * k);
      moment_p += dynamics::frame_position(planning, *data_p, k).cross(Vec3(f.segment<3>(3 * k)));
      moment_r += dynamics::frame_position(robot(), *data_r, k).cross(Vec3(g.segment<3>(3 * k)));
      const Vec3 gk = g.segment<3>(3 * k);
      EXPECT_GT(gk.z(), 0.0);
      EXPECT_LE(std::abs(gk.x()), kMu * gk.z() + 1e-9);
      EXPECT_LE(std::abs(gk.y()), kMu * gk.z() + 1e-9);
    }
    EXPECT_LT((force_r - force_p).norm(), 1e-9);
    EXPECT_LT((moment_r - moment_p).norm(), 1e-9) << "foot " << foot;
    EXPECT_GT((g - f).norm(), 1.0) << "the forces did move";
  }
  const model::Model none = planning_model(robot(), 0.0);
  EXPECT_LT((forces_on_robot_corners(robot(), none, f) - f).norm(), 1e-12);
}

// The repair with `forbid flight` over a hop keeps the flight (feasibility_repair.h), and
// the dynamic stage then refuses it, naming the time in the output clock (lead-in included).
TEST(mocap_dynamic_retarget, ForbiddenFlightRepairIsRefusedDownstream) {
  const int a = 50;  // the first dance frame in the air
  const Motion hop = hop_motion(120, a, 70);
  std::vector<RepairOverride> overrides;
  std::string error;
  ASSERT_TRUE(parse_repair_overrides("0.45 0.75 forbid flight\n", overrides, error)) << error;
  RepairedMotion rep;
  ASSERT_TRUE(repair_motion(robot(), hop.q, hop.labels, kRate_hz, RepairConfig{}, overrides, rep, error)) << error;
  const int first_flight = rep.lead_frames + a;
  ASSERT_EQ(rep.contacts[first_flight], ContactLabel::kFlight);
  auto plan = plan_of(rep.q, rep.contacts);
  DynamicResult out;
  EXPECT_FALSE(dynamic_retarget(robot(), *plan, DynamicRetargetConfig{}, out, error));
  char expected[64];
  std::snprintf(expected, sizeof expected, "flight at %.2f s (frame %d)", first_flight / kRate_hz, first_flight);
  EXPECT_NE(error.find(expected), std::string::npos) << error;
}

// What the oracle says of a result, with the optimization's own forces, and how far the
// result is from its reference.
struct Acceptance {
  double base_m = 0.0, orientation_rad = 0.0, joints_rad = 0.0;
  double force_sum_rel = 0.0;  // max over frames of |Σ f_z / (m g) − 1|
  DynamicsCheck check;
};

Acceptance accept(const planner::MotionPlan& plan, const DynamicResult& r) {
  Acceptance a;
  const auto frames = static_cast<std::size_t>(plan.frame_count);
  if (r.q.size() != frames || r.forces_N.size() != frames || r.contacts.size() != frames) {
    ADD_FAILURE() << "the result has " << r.q.size() << " frames for " << frames;
    return a;
  }
  for (int i = 0; i < plan.frame_count; ++i) {
    const ConfigVector& p = plan.q[i];
    const ConfigVector& q = r.q[i];
    a.base_m = std::max(a.base_m, (q.head<3>() - p.head<3>()).norm());
    const Eigen::Quaterniond op(p[6], p[3], p[4], p[5]), oq(q[6], q[3], q[4], q[5]);
    a.orientation_rad = std::max(a.orientation_rad, op.angularDistance(oq));
    a.joints_rad =
        std::max(a.joints_rad, (q.tail<model::kNumJoints>() - p.tail<model::kNumJoints>()).cwiseAbs().maxCoeff());
    double fz = 0.0;
    for (int c = 0; c < kCorners; ++c) fz += r.forces_N[i][3 * c + 2];
    a.force_sum_rel = std::max(a.force_sum_rel, std::abs(fz / weight_N() - 1.0));
  }
  check_dynamics(robot(), r.q, r.contacts, plan.rate_hz, &r.forces_N, kMu, a.check);
  return a;
}

void expect_nearly_unchanged(const planner::MotionPlan& plan, const DynamicResult& r, const Acceptance& a) {
  ASSERT_EQ(r.q.size(), static_cast<std::size_t>(plan.frame_count));
  ASSERT_EQ(r.forces_N.size(), r.q.size());
  for (int i = 0; i < plan.frame_count; ++i) {
    ASSERT_TRUE(r.q[i].allFinite()) << i;
    ASSERT_EQ(r.contacts[i], make_label(plan.foot_contact[i][0], plan.foot_contact[i][1])) << i;
  }
  EXPECT_EQ(r.stats.foothold_miss_frames, 0);
  // A feasible reference is the optimum up to the cost's trade-offs (force regularization
  // against CoM tracking, joint-limit barriers ~1 mrad): a few mm and mrad (measured: standing
  // 0.1 mm, 0.4 mrad; the weight shift 3.3 mm, 2.6 mrad base, 4.8 mrad joints).
  EXPECT_LT(a.base_m, 5e-3);
  EXPECT_LT(a.orientation_rad, 5e-3);
  EXPECT_LT(a.joints_rad, 1e-2);
  // The CoM of these motions accelerates at most 0.015 π² ≈ 0.15 m/s² (1.5 % of g); 3 %
  // allows the discretized dynamics' transients (measured: < 0.1 %).
  EXPECT_LT(a.force_sum_rel, 0.03);
  EXPECT_EQ(a.check.torque_violations, 0);
  EXPECT_EQ(a.check.friction_violations, 0);
  EXPECT_EQ(a.check.zmp_outside_m_max, 0.0);
  // Base residual: the oracle differentiates the interpolated frames while the optimization
  // integrates its centroidal model with explicit Euler at 20 ms and its forces are linear
  // between nodes; the difference is an error in the CoM acceleration, a fraction of the
  // ≤ 0.15 m/s² above (≤ 8 N), and its moment on a ≤ 1 m lever. Bounds 1 % of m·g (5.4 N)
  // and 5.4 N·m (measured: ≤ 0.2 N, ≤ 0.3 N·m); the built-in dance's mean is ~50 N.
  EXPECT_LT(a.check.base_force_residual_N_mean, 0.01 * weight_N());
  EXPECT_LT(a.check.base_moment_residual_Nm_mean, 0.01 * weight_N() * 1.0);
}

DynamicRetargetConfig short_config() {
  DynamicRetargetConfig cfg;
  cfg.max_sqp_iterations = 30;  // a feasible reference converges in a few
  return cfg;
}

TEST(mocap_dynamic_retarget, StandingComesBackUnchanged) {
  const auto plan = standing_plan(2.0);
  DynamicResult out;
  std::string error;
  ASSERT_TRUE(dynamic_retarget(robot(), *plan, short_config(), out, error)) << error;
  const Acceptance a = accept(*plan, out);
  expect_nearly_unchanged(*plan, out, a);
  RecordProperty("base_mm", number(a.base_m * 1e3));
  RecordProperty("orientation_mrad", number(a.orientation_rad * 1e3));
  RecordProperty("joints_mrad", number(a.joints_rad * 1e3));
  RecordProperty("force_sum_pct", number(a.force_sum_rel * 1e2));
  RecordProperty("residual_N_mean", number(a.check.base_force_residual_N_mean));
  RecordProperty("residual_Nm_mean", number(a.check.base_moment_residual_Nm_mean));
  RecordProperty("windows_not_converged", number(out.stats.windows_not_converged));
  EXPECT_EQ(out.stats.qp_failures, 0);
}

// A slow sideways weight shift (3 cm and back over 2 s, feet planted): feasible as it is.
TEST(mocap_dynamic_retarget, SlowWeightShiftComesBackNearlyUnchanged) {
  const int n = 201;
  const Motion shift = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.base_shift.y() = 0.03 * 0.5 * (1.0 - std::cos(2.0 * M_PI * i / (n - 1)));
    return k;
  });
  ASSERT_LT(shift.worst_ik_error_m, 1e-6);
  const auto plan = plan_of(shift.q, shift.labels);
  DynamicResult out;
  std::string error;
  ASSERT_TRUE(dynamic_retarget(robot(), *plan, short_config(), out, error)) << error;
  const Acceptance a = accept(*plan, out);
  expect_nearly_unchanged(*plan, out, a);
  RecordProperty("base_mm", number(a.base_m * 1e3));
  RecordProperty("orientation_mrad", number(a.orientation_rad * 1e3));
  RecordProperty("joints_mrad", number(a.joints_rad * 1e3));
  RecordProperty("force_sum_pct", number(a.force_sum_rel * 1e2));
  RecordProperty("residual_N_mean", number(a.check.base_force_residual_N_mean));
  RecordProperty("residual_Nm_mean", number(a.check.base_moment_residual_Nm_mean));
  EXPECT_EQ(out.stats.qp_failures, 0);
}

// One window's converged solution against the OCP's first-order conditions, with the MPC's
// own QP builder and solver as the oracle: a 1 s weight shift retargeted as a single window
// (commit_stages = T) to a tight step tolerance; the QP built afresh at the committed stage
// trajectory must (1) find the nonlinear constraints satisfied there (dynamics defects b and
// the stance rows' residuals e, which the build evaluates from the model), (2) be solved to
// its KKT conditions (stationarity and primal, checked here from the stage matrices), and
// (3) ask for no step: the point is a fixed point of the SQP, so the QP's multipliers make the
// NLP's Lagrangian stationary. The TO adds joint-velocity barriers the MPC build does not
// have: their gradient at these speeds (≤ 0.2 rad/s against ≥ 10 rad/s limits, μ = 0.01)
// moves the step by ~1e-4 at most, hence the 1e-3 bound on (3).
TEST(mocap_dynamic_retarget, ConvergedWindowSatisfiesTheKktConditions) {
  const int n = 101;  // 1.0 s: one 1.0 s window of 50 stages
  const Motion shift = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.base_shift.y() = 0.03 * 0.5 * (1.0 - std::cos(2.0 * M_PI * i / (n - 1)));
    return k;
  });
  const auto plan = plan_of(shift.q, shift.labels);
  DynamicRetargetConfig cfg;
  const int T = static_cast<int>(std::lround(cfg.ocp.horizon_s / cfg.ocp.dt_s));
  cfg.commit_stages = T;
  cfg.step_tolerance = 1e-7;
  cfg.support_margin_m = 0.015;  // the inset sole in the OCP too
  DynamicResult out;
  std::string error;
  ASSERT_TRUE(dynamic_retarget(robot(), *plan, cfg, out, error)) << error;
  ASSERT_EQ(out.stats.windows, 1);
  ASSERT_EQ(out.stats.windows_not_converged, 0);
  ASSERT_EQ(static_cast<int>(out.stage_x.size()), T + 1);

  // The OCP as the optimization poses it: the planning model's limits (the ankles at one
  // motor's clamp) and its inset sole corners, the robot's dynamics.
  const model::Model planning = planning_model(robot(), cfg.support_margin_m);
  ASSERT_LT(planning.limits.torque_Nm[model::kLeftLegFirst + 4], robot().limits.torque_Nm[model::kLeftLegFirst + 4]);
  auto ws = std::make_unique<mpc::MpcWorkspace>();
  mpc::mpc_init(planning, cfg.ocp, *ws);
  auto window = std::make_unique<planner::PlanWindow>();
  planner::motion_plan_window_rt(planning, scratch(), *plan, plan->start_ns, cfg.ocp.dt_s, T + 1, *window);
  ws->warm = true;  // linearize at the committed trajectory, unshifted
  ws->last_stamp_ns = window->knots[0].stamp_ns;
  for (int k = 0; k <= T; ++k) {
    ws->x[k] = out.stage_x[k];
    ws->u[k] = out.stage_u[k];
  }
  ASSERT_EQ(mpc::mpc_build_qp_from_state_rt(planning, cfg.ocp, *ws, out.stage_x[0], *window), mpc::MpcStatus::kOk);
  double defect = 0.0, residual = 0.0;
  for (int k = 0; k < T; ++k) {
    const auto& st = ws->qp.stages[k];
    defect = std::max(defect, st.b.cwiseAbs().maxCoeff());
    if (st.num_eq > 0) residual = std::max(residual, st.e.head(st.num_eq).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(defect, 1e-6) << "dynamics defects at the converged point";
  EXPECT_LT(residual, 1e-6) << "stance rows at the converged point";
  // The certificate needs the costates, which the MPC's solve leaves unwritten (it reads x, u).
  ws->qp_settings.lq_costate = true;
  ASSERT_EQ(mpc::mpc_solve_qp_rt(*ws), mpc::MpcStatus::kOk);
  const auto& qp = ws->qp;
  const auto& sol = ws->solution;
  double stat = (sol.x[0] - qp.x_initial).cwiseAbs().maxCoeff(), primal = stat, step = 0.0;
  for (int k = 0; k <= T; ++k) {
    const auto& st = qp.stages[k];
    Eigen::Matrix<double, kNx, 1> gx = st.Q * sol.x[k] + st.q - sol.costate[k];
    step = std::max(step, sol.x[k].cwiseAbs().maxCoeff());
    if (k < T) {
      const int ne = st.num_eq;
      gx += st.S.transpose() * sol.u[k] + st.A.transpose() * sol.costate[k + 1];
      Eigen::Matrix<double, kNu, 1> gu = st.R * sol.u[k] + st.S * sol.x[k] + st.r + st.B.transpose() * sol.costate[k + 1];
      if (ne > 0) {
        gx += st.C.topRows(ne).transpose() * sol.nu[k].head(ne);
        gu += st.D.topRows(ne).transpose() * sol.nu[k].head(ne);
        primal = std::max(primal, (st.C.topRows(ne) * sol.x[k] + st.D.topRows(ne) * sol.u[k] - st.e.head(ne)).cwiseAbs().maxCoeff());
      }
      primal = std::max(primal, (st.A * sol.x[k] + st.B * sol.u[k] + st.b - sol.x[k + 1]).cwiseAbs().maxCoeff());
      stat = std::max(stat, gu.cwiseAbs().maxCoeff());
      step = std::max(step, sol.u[k].tail<mpc::kNumMpcJoints>().cwiseAbs().maxCoeff());
      step = std::max(step, sol.u[k].head<3 * kCorners>().cwiseAbs().maxCoeff() / weight_N());
    }
    if (k > 0) stat = std::max(stat, gx.cwiseAbs().maxCoeff());
  }
  EXPECT_LT(stat, 1e-8);
  EXPECT_LT(primal, 1e-9);
  EXPECT_LT(step, 1e-3) << "the committed trajectory is not a fixed point of the OCP's SQP";
  RecordProperty("defect", number(defect));
  RecordProperty("stance_residual", number(residual));
  RecordProperty("qp_stationarity", number(stat));
  RecordProperty("step", number(step));
  std::printf("KKT at the converged window: defects %.2e, stance rows %.2e, QP stationarity %.2e, primal %.2e, step %.2e\n",
              defect, residual, stat, primal, step);
}

// A brisk plié bounce (pelvis 4 cm down and up, 1.5 Hz, three times, feet planted): the floor
// pushes m(g + z̈) with z̈ up to 0.02·(3π)² ≈ 1.8 m/s² (±98 N). The optimization's forces,
// interpolated to the frames, must be the ones the motion's own accelerations need — the
// oracle differentiates the frames, so a force sequence shifted by one 20 ms stage leaves
// ω·dt·98 N ≈ 18 N of residual (mean ~12 N; measured 11.7 N with node k carrying u_k instead
// of u_{k−1}, 1.5 N as it is). The residual's max is at the two end frames, where the oracle
// takes q̈ = 0 while this motion starts and ends accelerating (m·1.8 ≈ 98 N): not checked.
TEST(mocap_dynamic_retarget, BounceForcesAreTheOnesTheFramesNeed) {
  const int n = 201;
  const Motion bounce = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    k.base_shift.z() = -0.02 * (1.0 - std::cos(2.0 * M_PI * 1.5 * i / kRate_hz));
    return k;
  });
  ASSERT_LT(bounce.worst_ik_error_m, 1e-6);
  const auto plan = plan_of(bounce.q, bounce.labels);
  DynamicResult out;
  std::string error;
  ASSERT_TRUE(dynamic_retarget(robot(), *plan, short_config(), out, error)) << error;
  const Acceptance a = accept(*plan, out);
  EXPECT_EQ(a.check.torque_violations, 0);
  EXPECT_EQ(a.check.friction_violations, 0);
  EXPECT_EQ(a.check.zmp_outside_m_max, 0.0);
  EXPECT_LT(a.base_m, 1e-2);
  EXPECT_GT(a.force_sum_rel, 0.1) << "the bounce does load and unload the feet";
  EXPECT_LT(a.check.base_force_residual_N_mean, 5.0);
  RecordProperty("base_mm", number(a.base_m * 1e3));
  RecordProperty("force_sum_pct", number(a.force_sum_rel * 1e2));
  RecordProperty("residual_N_mean", number(a.check.base_force_residual_N_mean));
  RecordProperty("residual_N_max", number(a.check.base_force_residual_N_max));
  RecordProperty("residual_Nm_mean", number(a.check.base_moment_residual_Nm_mean));
}

// The base drop's envelope against its closed form: a single spike of height H comes out as
// a triangle-smoothed plateau, H at the spike, 0 past w + 2·(w/2) frames, with second
// differences within 2H/(2·(w/2) + 1)² (the first differences of one pass are within
// ±H/(2·(w/2) + 1)); any input stays under the curve.
TEST(mocap_dynamic_retarget, BaseDropEnvelopeCoversEveryFrameSmoothly) {
  const int n = 300, w = 20, h = w / 2;
  const double H = 0.02;
  std::vector<double> spike(n, 0.0);
  spike[100] = H;
  const std::vector<double> s = smooth_envelope(spike, w);
  ASSERT_EQ(static_cast<int>(s.size()), n);
  EXPECT_DOUBLE_EQ(s[100], H);
  EXPECT_EQ(s[100 + w + 2 * h + 1], 0.0);
  EXPECT_EQ(s[100 - w - 2 * h - 1], 0.0);
  EXPECT_GT(s[100 + w + 2 * h - 1], 0.0);
  double worst = 0.0;
  for (int i = 1; i + 1 < n; ++i) worst = std::max(worst, std::abs(s[i + 1] - 2.0 * s[i] + s[i - 1]));
  EXPECT_LE(worst, 2.0 * H / ((2 * h + 1) * (2 * h + 1)) + 1e-15);
  EXPECT_GT(worst, 0.5 * H / ((2 * h + 1) * (2 * h + 1)));
  // Scattered drops of every size: each frame's own stays covered.
  std::vector<double> v(n, 0.0);
  for (int i = 0; i < n; i += 7) v[i] = 0.001 * ((i * 37) % 21);
  const std::vector<double> e = smooth_envelope(v, w);
  for (int i = 0; i < n; ++i) EXPECT_GE(e[i], v[i] - 1e-15) << i;
}

// The swing-foot correction against its closed-form bounds: a stance, a swing of L = 31
// frames, a stance with another correction, and a swing to the end. Stance frames keep their
// own correction; through the swing it goes from the one before to the one after with steps
// within 1.5·Δ/(L + 1) and second differences within 6·Δ/(L + 1)² (a smoothstep's slope and
// curvature), monotonically, through their mean at the swing's middle (s = 1/2); the last
// swing holds the last stance's. Switched in one frame (the old rule), the step is Δ.
TEST(mocap_dynamic_retarget, SwingCorrectionsCarryTheStanceOnesSmoothly) {
  const int a = 10, L = 31, b = a + L, n = b + 10 + 5;
  std::vector<bool> stance(n, true);
  std::vector<Vec3> held(n, Vec3::Zero());
  for (int i = a; i < b; ++i) stance[i] = false;
  for (int i = b + 10; i < n; ++i) stance[i] = false;
  const Vec3 before(0.01, -0.004, 0.002), after(-0.02, 0.03, -0.005);
  for (int i = 0; i < a; ++i) held[i] = before + Vec3(0.0, 0.0, 1e-4 * i);  // a stance foot's drift
  for (int i = b; i < b + 10; ++i) held[i] = after;
  for (int i = a; i < b; ++i) held[i] = Vec3(1.0, 1.0, 1.0);               // swing frames: ignored
  for (int i = b + 10; i < n; ++i) held[i] = Vec3(1.0, 1.0, 1.0);
  const std::vector<Vec3> c = swing_corrections(stance, held);
  ASSERT_EQ(static_cast<int>(c.size()), n);
  for (int i = 0; i < n; ++i) {
    if (stance[i]) {
      EXPECT_EQ(c[i], held[i]) << i;
    }
  }
  const Vec3 from = held[a - 1];
  const double delta = (after - from).norm();
  double step = 0.0, curve = 0.0;
  for (int i = a - 1; i <= b; ++i) {
    step = std::max(step, (c[i + 1] - c[i]).norm());
    if (i > a - 1) curve = std::max(curve, (c[i + 1] - 2.0 * c[i] + c[i - 1]).norm());
    // On the segment from → after, moving forwards only.
    const double s = (c[i] - from).dot(after - from) / (delta * delta);
    EXPECT_NEAR((c[i] - from - s * (after - from)).norm(), 0.0, 1e-12) << i;
    if (i >= a) {
      EXPECT_GE(s, (c[i - 1] - from).dot(after - from) / (delta * delta) - 1e-12) << i;
    }
  }
  EXPECT_LE(step, 1.5 * delta / (L + 1) + 1e-12);
  EXPECT_LE(curve, 6.0 * delta / ((L + 1) * (L + 1)) + 1e-12);
  EXPECT_NEAR((c[a + L / 2] - 0.5 * (from + after)).norm(), 0.0, 1e-12);
  for (int i = b + 10; i < n; ++i) EXPECT_LT((c[i] - after).norm(), 1e-15) << i;
  RecordProperty("step_mm", number(step * 1e3));
  RecordProperty("one_frame_switch_mm", number(delta * 1e3));
}

// smooth_stages against the closed form of [1 2 1]/4: a straight line plus a component
// alternating every stage comes back as the line on every stage the fixed ends do not reach
// (stages 2 … S−2 after two passes), the ends untouched, and a yaw running through ±π stays
// on its line modulo 2π (averaged without the branch, it would land near 0).
TEST(mocap_dynamic_retarget, StageSmoothingRemovesTheStageRateRingingAndKeepsLines) {
  const int S = 40;
  const double alt = 0.05;
  std::vector<StateVector> xs(S + 1), line(S + 1);
  for (int k = 0; k <= S; ++k) {
    for (int i = 0; i < kNx; ++i) line[k][i] = 0.01 * i + 0.002 * (i + 1) * k;
    const double yaw = M_PI - 0.3 + 0.03 * k;  // crosses π at k = 10
    line[k][mpc::kXEuler] = std::remainder(yaw, 2.0 * M_PI);
    xs[k] = line[k];
    const double sign = k % 2 == 0 ? 1.0 : -1.0;
    for (int i = 0; i < kNx; ++i) xs[k][i] += sign * alt * (1.0 + 0.1 * i);
  }
  std::vector<StateVector> once = xs;
  smooth_stages(once, 0);
  for (int k = 0; k <= S; ++k) EXPECT_EQ(once[k], xs[k]) << "0 passes change nothing";
  std::vector<StateVector> out = xs;
  smooth_stages(out, 2);
  EXPECT_EQ(out[0], xs[0]);
  EXPECT_EQ(out[S], xs[S]);
  double worst = 0.0;
  for (int k = 2; k <= S - 2; ++k) {
    for (int i = 0; i < kNx; ++i) {
      double d = out[k][i] - line[k][i];
      if (i == mpc::kXEuler) d = std::remainder(d, 2.0 * M_PI);
      worst = std::max(worst, std::abs(d));
    }
  }
  RecordProperty("max_error", number(worst));
  EXPECT_LT(worst, 1e-12);
  // Stage 1 keeps a quarter of the end's alternating part (the end stays as it was).
  EXPECT_NEAR(out[1][3] - line[1][3], 0.25 * alt * 1.3, 1e-12);
}


// ---- the ankle-motor hinge (DynamicRetargetConfig::ankle_motor_weight) ----

// The largest ankle-motor torque the plan's own stages ask of the stance foot, quasi-static
// (stage_torque: g(q) − J_cᵀf of the stage's forces) through the linkage map at the stage's
// ankle angles (drivers/transmission/ankle_motors.h), over the left-foot-only stages from
// from_s on.
double max_left_stance_motor(const DynamicResult& r, double dt, double from_s) {
  const drivers::AnkleMotors motors = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot()));
  EXPECT_TRUE(motors.active);
  double worst = 0.0;
  for (std::size_t k = 0; k + 1 < r.stage_x.size(); ++k) {
    if (k * dt < from_s) continue;
    // Left only: the right sole's corners carry no force in the plan (swing).
    if (r.stage_u[k].segment<12>(12).norm() > 1e-9) continue;
    planner::ContactFlags left{};
    for (int c = 0; c < 4; ++c) left[c] = true;
    const TauVector tau = torque_at(r.stage_x[k], r.stage_u[k], r.stage_head[k], left);
    const int j = 4;  // left ankle pitch, roll
    Eigen::Vector2d m;
    const Eigen::Vector2d q(r.stage_x[k][mpc::kXJoints + j], r.stage_x[k][mpc::kXJoints + j + 1]);
    if (!drivers::ankle_motor_torques_rt(motors, 0, q, Eigen::Vector2d(tau[j], tau[j + 1]), m)) continue;
    worst = std::max(worst, m.cwiseAbs().maxCoeff());
  }
  return worst;
}

// One step forward with the right foot (weight onto the left over 0.8 s, a 0.4 s swing of
// 8 cm forward and 3 cm high, weight back), 1.2 s windows: those that cross its touchdown hold
// the landed corners where the current iterate sets them down. Before a window's first build
// the workspace still holds the previous window's trajectory, unshifted; read there, the
// touchdown sat where the foot was one commit (0.2 s) earlier, and each such window spent its
// first iterations dragging the leg there and back. The landing changes only the path to the
// window's fixed point, not the point: the deterministic iteration count tells the two apart.
// Measured: 5.73 SQP iterations a window (max 12), 1 rejected step; read unshifted, 14.40
// (max 53), 12.
TEST(mocap_dynamic_retarget, WindowsCrossingATouchdownStartFromWhereTheFootLands) {
  const Standing& st = standing();
  const int n = 301;  // 3 s at 100 Hz
  const Vec3 over_left = st.feet[0].centre - 0.5 * (st.feet[0].centre + st.feet[1].centre);
  Foot stepped = st.feet[1];
  stepped.centre.x() += 0.08;
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    const auto smooth = [](double s) { s = std::clamp(s, 0.0, 1.0); return s * s * (3.0 - 2.0 * s); };
    const double on_left = smooth((i - 20) / 80.0) - smooth((i - 160) / 80.0);
    k.base_shift = 0.8 * on_left * Vec3(over_left.x(), over_left.y(), 0.0);
    if (i >= 110 && i < 150) {
      k.right = swing(st.feet[1], stepped, i, 110, 150, 0.03);
      k.right_down = false;
    } else if (i >= 150) {
      k.right = stepped;
    }
    k.base_shift.x() += 0.04 * smooth((i - 110) / 80.0);
    return k;
  });
  ASSERT_LT(m.worst_ik_error_m, 1e-5);
  const auto plan = plan_of(m.q, m.labels);
  DynamicRetargetConfig cfg;
  cfg.set_horizon(1.2);
  DynamicResult out;
  std::string error;
  ASSERT_TRUE(dynamic_retarget(robot(), *plan, cfg, out, error)) << error;
  RecordProperty("sqp_iterations_mean", number(out.stats.sqp_iterations_mean));
  RecordProperty("rejected_steps", number(out.stats.rejected_steps));
  std::printf("step: %d windows, %.2f SQP iterations a window (max %d), %d rejected steps\n", out.stats.windows,
              out.stats.sqp_iterations_mean, out.stats.sqp_iterations_max, out.stats.rejected_steps);
  EXPECT_EQ(out.stats.windows_not_converged, 0);
  EXPECT_EQ(out.stats.qp_failures, 0);
  EXPECT_LE(out.stats.sqp_iterations_mean, 10.0) << "the windows retrace the swing from a stale touchdown";
}

// Standing on the left foot with the CoM 3.5 cm ahead of the ankle and 3.5 cm outside it:
// pitch and roll each stay within the MPC's ankle box (0.9 × 27 N·m), but together they ask
// one ankle motor for more than its 27 N·m clamp (pitch ≈ τ_A + τ_B, roll ≈ 0.46 (τ_A − τ_B)).
// Without the hinge the plan keeps the CoM there; with it the plan's motors stay within
// the clamp (the hinge starts at ankle_motor_share = 0.9 of it).
TEST(mocap_dynamic_retarget, AnkleMotorHingeKeepsTheStanceMotorsWithinTheirClamp) {
  const Standing& st = standing();
  dynamics::forward_kinematics(robot(), scratch(), st.q);
  dynamics::crba(robot(), scratch());
  const Vec3 mid = 0.5 * (st.feet[0].centre + st.feet[1].centre);
  const Vec3 com_from_mid = scratch().com_m - mid;
  // The left ankle axis: the sole centre is 0.049 m ahead of it (toe +0.171, heel −0.073).
  const Vec3 ankle = st.feet[0].centre - Vec3(0.049, 0.0, 0.0);
  const Vec3 target = ankle + Vec3(0.035, 0.055, 0.0);
  Vec3 shift = target - mid - com_from_mid;
  shift.z() = 0.0;
  const int n = 251;
  const Motion m = make_motion(n, [&](int i) {
    Keyframe k = stand_key();
    const double s = std::min(1.0, i / 100.0), w = s * s * (3.0 - 2.0 * s);
    k.base_shift = w * shift;
    if (i >= 110) {
      const double l = std::min(1.0, (i - 110) / 20.0);
      k.right.centre.z() = 0.03 * l * l * (3.0 - 2.0 * l);
      k.right_down = false;
    }
    return k;
  });
  ASSERT_LT(m.worst_ik_error_m, 1e-5);
  const auto plan = plan_of(m.q, m.labels);
  DynamicRetargetConfig cfg;
  cfg.max_sqp_iterations = 60;
  DynamicResult off, on;
  std::string error;
  ASSERT_TRUE(dynamic_retarget(robot(), *plan, cfg, off, error)) << error;
  cfg.ankle_motor_weight = 10.0;
  ASSERT_TRUE(dynamic_retarget(robot(), *plan, cfg, on, error)) << error;
  const double dt = cfg.ocp.dt_s;
  const double worst_off = max_left_stance_motor(off, dt, 1.6), worst_on = max_left_stance_motor(on, dt, 1.6);
  RecordProperty("motor_off_Nm", number(worst_off));
  RecordProperty("motor_on_Nm", number(worst_on));
  ASSERT_GT(worst_off, 28.0) << "the precondition: the reference asks a motor beyond its clamp";
  EXPECT_LE(worst_on, 27.0);
  EXPECT_GT(off.stats.stages_over_ankle_motors, 0);
  EXPECT_EQ(on.stats.stages_over_ankle_motors, 0);
}

// The ankle-effort cost (DynamicRetargetConfig::ankle_effort_weight, at 0.1) on a held
// double support whose reference stands the CoM 3.5 cm farther ahead of the ankles than the
// standing pose does (4.9 cm ahead), as the human clips' TO output did, and on one that stands
// it 3 cm behind that (as the built-in dance's mostly did). The plan's centre of pressure is
// read as the feet's ankle pitch over their normal force (the stages' quasi-static torques),
// against the plan without the cost: ahead, at least half the lead beyond standing's goes and
// none of standing's; behind, the plan keeps it (the ankles hold a centre of pressure nearer
// them with more reserve, and a dance that leans back may). And standing comes back as it was.
TEST(mocap_dynamic_retarget, AnkleEffortCostBringsALeanAheadBackToStandings) {
  const Standing& st = standing();
  dynamics::forward_kinematics(robot(), scratch(), st.q);
  dynamics::crba(robot(), scratch());
  const auto ankle = [&](int leg) {
    return scratch().position_m[1 + leg * model::kLegJoints + model::kAnklePitchInLeg];
  };
  const double lead_standing = scratch().com_m.x() - 0.5 * (ankle(0) + ankle(1)).x();
  RecordProperty("lead_standing_m", number(lead_standing));
  DynamicRetargetConfig cfg;
  cfg.ankle_effort_weight = 0.1;
  {
    SCOPED_TRACE("standing");
    const auto plan = standing_plan(2.0);
    DynamicRetargetConfig c = cfg;
    c.max_sqp_iterations = 30;
    DynamicResult out;
    std::string error;
    ASSERT_TRUE(dynamic_retarget(robot(), *plan, c, out, error)) << error;
    const Acceptance a = accept(*plan, out);
    RecordProperty("standing_base_m", number(a.base_m));
    // Measured 0.4 mm, 0.04 mrad (without the cost the same).
    EXPECT_LT(a.base_m, 1e-3);
    EXPECT_LT(a.orientation_rad, 1e-3);
  }
  // Σ |ankle pitch| / Σ f_z over the held stages (1.5 s on).
  const auto lead = [&](const DynamicResult& r) {
    double pitch = 0.0, fz = 0.0;
    for (std::size_t k = 0; k + 1 < r.stage_x.size(); ++k) {
      if (k * cfg.ocp.dt_s < 1.5) continue;
      const TauVector tau = torque_at(r.stage_x[k], r.stage_u[k], r.stage_head[k], both_feet());
      pitch += std::abs(tau[model::kLeftLegFirst + model::kAnklePitchInLeg]) +
               std::abs(tau[model::kRightLegFirst + model::kAnklePitchInLeg]);
      for (int c = 0; c < kCorners; ++c) fz += r.stage_u[k][3 * c + 2];
    }
    return pitch / fz;
  };
  for (const double shift_x : {0.035, -0.03}) {
    SCOPED_TRACE(shift_x > 0.0 ? "ahead" : "behind");
    const int n = 301;  // 3 s: the lean in over the first second, then held
    const Motion m = make_motion(n, [&](int i) {
      Keyframe k = stand_key();
      const double s = std::min(1.0, i / 100.0);
      k.base_shift.x() = s * s * (3.0 - 2.0 * s) * shift_x;
      return k;
    });
    ASSERT_LT(m.worst_ik_error_m, 1e-5);
    const auto plan = plan_of(m.q, m.labels);
    DynamicRetargetConfig c = cfg;
    DynamicResult on, off;
    std::string error;
    ASSERT_TRUE(dynamic_retarget(robot(), *plan, c, on, error)) << error;
    c.ankle_effort_weight = 0.0;
    ASSERT_TRUE(dynamic_retarget(robot(), *plan, c, off, error)) << error;
    const double lead_off = lead(off), lead_on = lead(on);
    RecordProperty(shift_x > 0.0 ? "ahead_off_m" : "behind_off_m", number(lead_off));
    RecordProperty(shift_x > 0.0 ? "ahead_on_m" : "behind_on_m", number(lead_on));
    std::printf("centre of pressure ahead of the ankles: standing %.4f m; held %+.3f m: %.4f m without the cost, "
                "%.4f m with it\n", lead_standing, shift_x, lead_off, lead_on);
    EXPECT_EQ(on.stats.windows_not_converged, 0);
    EXPECT_EQ(on.stats.qp_failures, 0);
    if (shift_x > 0.0) {
      ASSERT_GT(lead_off - lead_standing, 0.025) << "the precondition: the plan without the cost keeps the lean";
      EXPECT_LT(lead_on - lead_standing, 0.5 * (lead_off - lead_standing));
      EXPECT_GT(lead_on - lead_standing, -0.005) << "it goes back to standing's, not behind it";
    } else {
      ASSERT_LT(lead_off - lead_standing, -0.02) << "the precondition: the plan without the cost keeps the lean";
      EXPECT_NEAR(lead_on, lead_off, 0.003) << "a lean behind standing's costs nothing in pitch";
    }
  }
}

}  // namespace
}  // namespace kuavo::mocap
