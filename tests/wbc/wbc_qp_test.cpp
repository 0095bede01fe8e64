// The QP's answer is physically consistent: (q̈, f, τ) satisfy the full equations of motion
// (checked against an independent RNEA), friction pyramid, torque limits and zero swing
// forces; standing still it is the closed-form answer q̈ = 0, Σf_z = m g.
#include <gtest/gtest.h>

#include <random>

#include "tests/wbc/wbc_fixture.h"

namespace kuavo::test {
namespace {

using wbc::kNumForces;
using wbc::kNumPoints;
constexpr int kNv = model::kNv;
constexpr int kNj = model::kNumJoints;

struct Independent {
  dynamics::Data data;
  dynamics::FrameJacobian jacobian;
  Eigen::Matrix<double, kNumForces, kNv> contact_jacobian;
  wbc::ForceVector bias;
};

Independent& independent() {
  static Independent s;
  return s;
}

// J_c and J̇v at (q, v), computed apart from the WBC.
void contact_terms(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v) {
  Independent& s = independent();
  const model::Model& m = wbc_robot();
  dynamics::forward_kinematics(m, s.data, q);
  dynamics::forward_velocities(m, s.data, v);
  dynamics::bias_accelerations(m, s.data);
  for (int c = 0; c < kNumPoints; ++c) {
    dynamics::frame_jacobian(m, s.data, c, s.jacobian);
    s.contact_jacobian.middleRows<3>(3 * c) = s.jacobian.topRows<3>();
    s.bias.segment<3>(3 * c) = dynamics::frame_bias_acceleration(m, s.data, c).head<3>();
  }
}

// Residual of M q̈ + b − Sᵀτ − J_cᵀ f, by RNEA (which computes M q̈ + b in one pass).
dynamics::VelocityVector dynamics_residual(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                                           const wbc::WbcDiagnostics& d) {
  contact_terms(q, v);
  Independent& s = independent();
  dynamics::rnea(wbc_robot(), s.data, d.acceleration, true);
  dynamics::VelocityVector generalized = s.contact_jacobian.transpose() * d.contact_force_N;
  generalized.tail<kNj>() += d.torque_Nm;
  return s.data.tau - generalized;
}

void expect_constraints_hold(const wbc::WbcReference& ref, const wbc::WbcDiagnostics& d, double mu) {
  const model::Model& m = wbc_robot();
  for (int c = 0; c < kNumPoints; ++c) {
    const Eigen::Vector3d f = d.contact_force_N.segment<3>(3 * c);
    if (!ref.in_contact[c]) {
      EXPECT_EQ(f.norm(), 0.0) << "swing point " << c;
      continue;
    }
    EXPECT_GE(f.z(), -1e-9) << c;
    EXPECT_LE(std::abs(f.x()), mu * f.z() + 1e-7) << c;
    EXPECT_LE(std::abs(f.y()), mu * f.z() + 1e-7) << c;
  }
  for (int j = 0; j < kNj; ++j) EXPECT_LE(std::abs(d.torque_Nm[j]), m.limits.torque_Nm[j] + 1e-6) << j;
}

TEST(WbcQp, StandingStillIsTheClosedFormAnswer) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  ASSERT_EQ(wbc::wbc_validate_config(cfg), nullptr);
  wbc::wbc_init(m, cfg, ws);
  const dynamics::ConfigVector q = bent_standing_configuration();
  const dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  static wbc::WbcReference ref;
  wbc::wbc_reference_hold_state(m, ws, q, 0, ref);
  // Planned forces that balance gravity exactly (min-norm solution of the base rows), so
  // every task is met by q̈ = 0.
  contact_terms(q, v);
  dynamics::compute_all_terms(m, independent().data, q, v);
  const Eigen::Matrix<double, 6, kNumForces> a = independent().contact_jacobian.leftCols<6>().transpose();
  const Eigen::Matrix<double, 6, 1> b = independent().data.tau.head<6>();
  ref.contact_force_N = a.transpose() * (a * a.transpose()).ldlt().solve(b);

  static hal::CommandFrame command;
  ASSERT_EQ(wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command), wbc::WbcStatus::kOk);
  const wbc::WbcDiagnostics& d = ws.diagnostics;
  EXPECT_EQ(d.qp_status, qp::QpStatus::kSolved);
  EXPECT_LT(d.acceleration.cwiseAbs().maxCoeff(), 1e-6);
  double fz_N = 0.0;
  for (int c = 0; c < kNumPoints; ++c) fz_N += d.contact_force_N[3 * c + 2];
  const double weight_N = m.total_mass_kg * model::kGravity_m_s2;
  EXPECT_NEAR(fz_N, weight_N, 1e-6 * weight_N);
  EXPECT_LT((d.contact_force_N - ref.contact_force_N).norm(), 1e-4);
  EXPECT_LT(dynamics_residual(q, v, d).cwiseAbs().maxCoeff(), 1e-8);
  expect_constraints_hold(ref, d, cfg.friction_coefficient);
  // Output: reference pose (q̈ ≈ 0 adds nothing), torque feed-forward = the QP torque.
  for (int j = 0; j < kNj; ++j) {
    EXPECT_NEAR(command.joints[j].position_ref_rad, q[7 + j], 1e-9);
    EXPECT_EQ(command.joints[j].torque_ff_Nm, d.torque_Nm[j]);
    EXPECT_EQ(command.joints[j].mode, hal::JointMode::kPdTorque);
  }
  std::printf("standing still: max|qdd| %.2e, sum fz %.6f N (m g %.6f N), EoM residual %.2e\n",
              d.acceleration.cwiseAbs().maxCoeff(), fz_N, weight_N, dynamics_residual(q, v, d).cwiseAbs().maxCoeff());
}

TEST(WbcQp, HoldStateReferenceKeepsStancePointsStillAndCarriesTheWeight) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  wbc::wbc_init(m, cfg, ws);
  const dynamics::ConfigVector q = bent_standing_configuration();
  static wbc::WbcReference ref;
  wbc::wbc_reference_hold_state(m, ws, q, 0, ref);
  static hal::CommandFrame command;
  ASSERT_EQ(wbc::wbc_step_rt(m, cfg, ws, q, dynamics::VelocityVector::Zero(), ref, 0, command), wbc::WbcStatus::kOk);
  const wbc::WbcDiagnostics& d = ws.diagnostics;
  // Stance points do not accelerate: J q̈ + J̇v = 0 (v = 0 here, so J q̈ = 0).
  contact_terms(q, dynamics::VelocityVector::Zero());
  EXPECT_LT((independent().contact_jacobian * d.acceleration + independent().bias).cwiseAbs().maxCoeff(), 1e-6);
  double fz_N = 0.0;
  for (int c = 0; c < kNumPoints; ++c) fz_N += d.contact_force_N[3 * c + 2];
  EXPECT_NEAR(fz_N, m.total_mass_kg * model::kGravity_m_s2, 1e-6);
  EXPECT_LT(d.acceleration.cwiseAbs().maxCoeff(), 1e-6);
}

// Random moving states, both feet or one foot in contact: the returned triple is consistent.
// H's acceleration block is Σ (task rows)ᵀ(task rows) plus diagonal weights; the WBC forms it
// by blocks (a foot's rows reach only the base and its leg). Off the diagonal it must equal
// the dense product of the task rows, whose point rows are √w·J_c with J_c computed apart;
// H is symmetric and the force block and the acceleration–force block are diagonal / zero.
TEST(WbcQp, HessianIsTheTaskRowsGramMatrix) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  wbc::wbc_init(m, cfg, ws);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  static wbc::WbcReference ref;
  static hal::CommandFrame command;
  double worst_h = 0.0, worst_rows = 0.0, worst_other = 0.0;
  for (int trial = 0; trial < 30; ++trial) {
    dynamics::ConfigVector q = bent_standing_configuration(0.3 + 0.1 * u(rng));
    wbc::wbc_reference_hold_state(m, ws, q, 0, ref);
    for (int c = 0; c < kNumPoints; ++c) ref.in_contact[c] = trial % 3 == 0 || (trial % 3 == 1 ? c >= 4 : c < 4);
    for (int j = 0; j < kNj; ++j) q[7 + j] += 0.1 * u(rng);
    dynamics::VelocityVector v;
    for (int k = 0; k < kNv; ++k) v[k] = 0.3 * u(rng);
    wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    const Eigen::MatrixXd rows = ws.task_rows;
    const Eigen::MatrixXd dense = rows.transpose() * rows;
    const Eigen::MatrixXd H = ws.qp.H;
    const double scale = 1.0 + dense.cwiseAbs().maxCoeff();
    for (int j = 0; j < kNv; ++j) {
      for (int i = 0; i < kNv; ++i) {
        if (i != j) worst_h = std::max(worst_h, std::abs(H(i, j) - dense(i, j)) / scale);
      }
    }
    worst_other = std::max(worst_other, (H - H.transpose()).cwiseAbs().maxCoeff());
    worst_other = std::max(worst_other, H.block(kNv, 0, kNumForces, kNv).cwiseAbs().maxCoeff());
    Eigen::MatrixXd force_block = H.bottomRightCorner(kNumForces, kNumForces);
    force_block.diagonal().setZero();
    worst_other = std::max(worst_other, force_block.cwiseAbs().maxCoeff());
    contact_terms(q, v);
    for (int c = 0; c < kNumPoints; ++c) {
      const double w = std::sqrt(ref.in_contact[c] ? cfg.weight_stance_point : cfg.weight_swing_point);
      const Eigen::MatrixXd expected = w * independent().contact_jacobian.middleRows<3>(3 * c);
      worst_rows = std::max(worst_rows, (rows.middleRows(3 * c, 3) - expected).cwiseAbs().maxCoeff() / (1.0 + expected.cwiseAbs().maxCoeff()));
    }
  }
  EXPECT_LT(worst_h, 1e-12);
  EXPECT_LT(worst_rows, 1e-12);
  EXPECT_EQ(worst_other, 0.0);
}

TEST(WbcQp, RandomStatesSatisfyDynamicsFrictionTorqueLimitsAndSwingZero) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  wbc::wbc_init(m, cfg, ws);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  static wbc::WbcReference ref;
  static hal::CommandFrame command;
  int solved = 0, stance_checked = 0;
  double worst_residual = 0.0, worst_stance_acc = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    dynamics::ConfigVector q0 = bent_standing_configuration(0.3 + 0.1 * u(rng));
    wbc::wbc_reference_hold_state(m, ws, q0, 0, ref);
    const int mode = trial % 3;  // 0 both feet, 1 left swing, 2 right swing
    for (int c = 0; c < kNumPoints; ++c) ref.in_contact[c] = mode == 0 || (mode == 1 ? c >= 4 : c < 4);
    for (int c = 0; c < kNumPoints; ++c) {
      if (!ref.in_contact[c]) ref.point_position_m[3 * c + 2] += 0.03;  // lift the swing foot
    }
    dynamics::ConfigVector q = q0;
    dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    const bool moving = trial % 2 == 1;
    if (moving) {
      for (int j = 0; j < kNj; ++j) q[7 + j] += 0.02 * u(rng);
      for (int k = 0; k < kNv; ++k) v[k] = 0.2 * u(rng);
    }
    const wbc::WbcStatus status = wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    if (status != wbc::WbcStatus::kOk) continue;
    ++solved;
    const wbc::WbcDiagnostics& d = ws.diagnostics;
    worst_residual = std::max(worst_residual, dynamics_residual(q, v, d).cwiseAbs().maxCoeff());
    expect_constraints_hold(ref, d, cfg.friction_coefficient);
    if (!moving && mode == 0) {
      contact_terms(q, v);
      const auto acc = independent().contact_jacobian * d.acceleration + independent().bias;
      worst_stance_acc = std::max(worst_stance_acc, acc.cwiseAbs().maxCoeff());
      ++stance_checked;
    }
  }
  EXPECT_EQ(solved, 200);
  EXPECT_GT(stance_checked, 20);
  EXPECT_LT(worst_residual, 1e-7);
  EXPECT_LT(worst_stance_acc, 1e-4);
  std::printf("random states: %d/200 solved, worst EoM residual %.2e, worst stance point accel %.2e m/s^2\n",
              solved, worst_residual, worst_stance_acc);
}

}  // namespace
}  // namespace kuavo::test
