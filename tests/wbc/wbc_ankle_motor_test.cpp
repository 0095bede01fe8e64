// The ankle motor rows (wbc.h): with the ankle pairs' joint -> motor torque maps set, every
// solved tick's motor torques at the drives' sample -- the ankle torques through the map plus
// the CSP drives' damping on the velocity error, kd·J·(v_ref − v), v_ref the command's and v
// the measured joint velocity -- stay within the planned share of the motors' limits, checked
// on the returned command apart from the QP's rows. The same states without the rows ask the
// motors for more (the scenario binds).
#include <gtest/gtest.h>

#include <random>

#include "tests/wbc/wbc_fixture.h"

namespace kuavo::test {
namespace {

constexpr int kNj = model::kNumJoints;
constexpr double kMotorLimit_Nm = 8.0;  // tight enough to bind in single support
constexpr double kVelocityGain_Nm_s_per_rad = 1.25;  // the CSP ankle drives' kd, motor side

// A 4Pro-like linkage map: pitch = τA + τB, roll = 0.46 (τA − τB) (firmware/README.md),
// inverted: motor (A, B) = G · (τ_pitch, τ_roll).
Eigen::Matrix2d linkage_map() {
  Eigen::Matrix2d joint_from_motor;
  joint_from_motor << 1.0, 1.0, 0.46, -0.46;
  return joint_from_motor.inverse();
}

// Motor torques at the sample of both ankle pairs beyond `limit`: G τ_ff + kv J (v_ref − v), J = Gᵀ⁻¹.
double worst_motor_excess_Nm(const hal::CommandFrame& cmd, const dynamics::VelocityVector& v, const Eigen::Matrix2d& g,
                             double kv, double limit) {
  double worst = -1e9;
  for (int leg : {model::kLeftLegFirst, model::kRightLegFirst}) {
    const Eigen::Vector2d tau(cmd.joints[leg + 4].torque_ff_Nm, cmd.joints[leg + 5].torque_ff_Nm);
    const Eigen::Vector2d v_ref(cmd.joints[leg + 4].velocity_ref_rad_s, cmd.joints[leg + 5].velocity_ref_rad_s);
    const Eigen::Vector2d v_joint(v[6 + leg + 4], v[6 + leg + 5]);
    const Eigen::Vector2d motor = g * tau + kv * g.transpose().inverse() * (v_ref - v_joint);
    worst = std::max(worst, motor.cwiseAbs().maxCoeff() - limit);
  }
  return worst;
}

TEST(WbcAnkleMotors, SolvedTicksKeepEveryAnkleMotorWithinItsLimit) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  static wbc::WbcReference ref;
  static hal::CommandFrame command;
  const Eigen::Matrix2d g = linkage_map();
  const double limit = cfg.ankle_motor_torque_share * kMotorLimit_Nm;  // what the QP may plan
  int binding = 0, solved_with_rows = 0;
  double worst_with_rows = -1e9;
  for (int trial = 0; trial < 60; ++trial) {
    std::mt19937_64 rng(100 + trial);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    dynamics::ConfigVector q = bent_standing_configuration(0.3 + 0.1 * u(rng));
    wbc::wbc_init(m, cfg, ws);
    wbc::wbc_reference_hold_state(m, ws, q, 0, ref);
    const int mode = trial % 3;  // 0 both feet, 1 left swing, 2 right swing
    for (int c = 0; c < wbc::kNumPoints; ++c) ref.in_contact[c] = mode == 0 || (mode == 1 ? c >= 4 : c < 4);
    for (int leg : {model::kLeftLegFirst, model::kRightLegFirst}) {
      ref.joint_velocity_rad_s[leg + 4] = 2.0 * u(rng);
      ref.joint_velocity_rad_s[leg + 5] = 1.0 * u(rng);
    }
    for (int j = 0; j < kNj; ++j) q[7 + j] += 0.05 * u(rng);
    dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    for (int k = 0; k < model::kNv; ++k) v[k] = 0.2 * u(rng);
    // Without the rows: the reference answer (and whether the limit binds here).
    ASSERT_FALSE(ws.ankle_motor_limits.active);
    wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    const bool free_solved = ws.diagnostics.qp_status == qp::QpStatus::kSolved;
    if (free_solved && worst_motor_excess_Nm(command, v, g, kVelocityGain_Nm_s_per_rad, limit) > 0.0) ++binding;
    // With the rows.
    wbc::wbc_init(m, cfg, ws);
    ws.ankle_motor_limits.active = true;
    for (int leg = 0; leg < 2; ++leg) {
      ws.ankle_motor_limits.joint_to_motor[leg] = g;
      ws.ankle_motor_limits.limit_Nm[leg].setConstant(kMotorLimit_Nm);
      ws.ankle_motor_limits.velocity_gain_Nm_s_per_rad[leg].setConstant(kVelocityGain_Nm_s_per_rad);
    }
    wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    ws.ankle_motor_limits.active = false;
    if (ws.diagnostics.qp_status != qp::QpStatus::kSolved) continue;
    ++solved_with_rows;
    worst_with_rows = std::max(worst_with_rows, worst_motor_excess_Nm(command, v, g, kVelocityGain_Nm_s_per_rad, limit));
    // The command carries the QP's torque.
    for (int j = 0; j < kNj; ++j) EXPECT_EQ(command.joints[j].torque_ff_Nm, ws.diagnostics.torque_Nm[j]);
  }
  std::printf("[ figures  ] ankle motors planned within %.1f N m: %d of 60 free answers exceed it; %d solved with the "
              "rows, worst motor excess %.2e N m\n",
              limit, binding, solved_with_rows, worst_with_rows);
  EXPECT_GT(binding, 10);          // the limit binds: the rows have work to do
  EXPECT_GT(solved_with_rows, 30);
  EXPECT_LE(worst_with_rows, 0.0);  // inside by the rows' roundoff margin
}

// The serial leg drives' rows: with the CSP hips' and knees' clamps and damping set, every
// solved tick's torque at the drive's sample, τ_ff + kv·(v_ref − v), stays within the clamp
// (checked on the returned command and the measured v); without the rows the same states
// exceed it.
TEST(WbcSerialLegDrives, SolvedTicksKeepEveryHipAndKneeCommandWithinItsClamp) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  static wbc::WbcReference ref;
  static hal::CommandFrame command;
  // Clamps that bind in single support with the hips and knees moving (the knee carries ~40 N·m).
  constexpr std::array<double, hal::kSerialLegJoints> kClamp_Nm{20.0, 6.0, 20.0, 40.0};
  constexpr double kGain_Nm_s_per_rad = 3.0;  // the WBC's leg kd, as the CSP drives hold it
  auto worst_excess = [&](const hal::CommandFrame& c, const dynamics::VelocityVector& v) {
    double worst = -1e9;
    for (int leg = 0; leg < 2; ++leg) {
      for (int k = 0; k < hal::kSerialLegJoints; ++k) {
        const int jj = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + k;
        const hal::JointCommand& j = c.joints[jj];
        worst = std::max(worst, std::abs(j.torque_ff_Nm + kGain_Nm_s_per_rad * (j.velocity_ref_rad_s - v[6 + jj])) -
                                    kClamp_Nm[k]);
      }
    }
    return worst;
  };
  int binding = 0, solved_with_rows = 0;
  double worst_with_rows = -1e9;
  for (int trial = 0; trial < 60; ++trial) {
    std::mt19937_64 rng(300 + trial);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    dynamics::ConfigVector q = bent_standing_configuration(0.3 + 0.1 * u(rng));
    wbc::wbc_init(m, cfg, ws);
    wbc::wbc_reference_hold_state(m, ws, q, 0, ref);
    const int mode = trial % 3;  // 0 both feet, 1 left swing, 2 right swing
    for (int c = 0; c < wbc::kNumPoints; ++c) ref.in_contact[c] = mode == 0 || (mode == 1 ? c >= 4 : c < 4);
    for (int j = 0; j < 2 * model::kLegJoints; ++j) ref.joint_velocity_rad_s[j] = 2.0 * u(rng);
    for (int j = 0; j < kNj; ++j) q[7 + j] += 0.05 * u(rng);
    dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    for (int k = 0; k < model::kNv; ++k) v[k] = 0.2 * u(rng);
    ASSERT_FALSE(ws.serial_drive_limits.active);
    wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    if (ws.diagnostics.qp_status == qp::QpStatus::kSolved && worst_excess(command, v) > 0.0) ++binding;
    wbc::wbc_init(m, cfg, ws);
    ws.serial_drive_limits.active = true;
    for (int leg = 0; leg < 2; ++leg) {
      for (int k = 0; k < hal::kSerialLegJoints; ++k) {
        ws.serial_drive_limits.limit_Nm[leg][k] = kClamp_Nm[k];
        ws.serial_drive_limits.velocity_gain_Nm_s_per_rad[leg][k] = kGain_Nm_s_per_rad;
      }
    }
    wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    ws.serial_drive_limits.active = false;
    if (ws.diagnostics.qp_status != qp::QpStatus::kSolved) continue;
    ++solved_with_rows;
    worst_with_rows = std::max(worst_with_rows, worst_excess(command, v));
  }
  std::printf("[ figures  ] hip and knee commands: %d of 60 free answers exceed the clamps; %d solved with the rows, "
              "worst excess %.2e N m\n",
              binding, solved_with_rows, worst_with_rows);
  EXPECT_GT(binding, 10);
  EXPECT_GT(solved_with_rows, 30);
  EXPECT_LE(worst_with_rows, 0.0);
}

// The binding's per-joint torque caps (the Ruiwo arm motors' MIT torque range): a capped joint's
// planned torque stays within the cap; uncapped, the same ticks ask for more.
TEST(WbcTorqueCaps, CappedJointsPlanWithinTheirCap) {
  const model::Model& m = wbc_robot();
  wbc::WbcWorkspace& ws = wbc_workspace();
  const wbc::WbcConfig cfg;
  static wbc::WbcReference ref;
  static hal::CommandFrame command;
  constexpr int kCapped[] = {model::kLeftArmFirst + 1, model::kLeftArmFirst + 3};  // shoulder roll, elbow
  constexpr double kCap_Nm = 0.2;
  int binding = 0, solved = 0;
  double worst = -1e9;
  for (int trial = 0; trial < 20; ++trial) {
    std::mt19937_64 rng(500 + trial);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    dynamics::ConfigVector q = bent_standing_configuration(0.3 + 0.1 * u(rng));
    for (int j = 0; j < kNj; ++j) q[7 + j] += 0.05 * u(rng);
    wbc::wbc_init(m, cfg, ws);
    wbc::wbc_reference_hold_state(m, ws, q, 0, ref);
    const dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    for (int j : kCapped) binding += std::abs(command.joints[j].torque_ff_Nm) > kCap_Nm ? 1 : 0;
    wbc::wbc_init(m, cfg, ws);
    for (int j : kCapped) ws.torque_cap_Nm[j] = kCap_Nm;
    wbc::wbc_step_rt(m, cfg, ws, q, v, ref, 0, command);
    ws.torque_cap_Nm.setConstant(qp::kInfinity);
    if (ws.diagnostics.qp_status != qp::QpStatus::kSolved) continue;
    ++solved;
    for (int j : kCapped) worst = std::max(worst, std::abs(command.joints[j].torque_ff_Nm) - kCap_Nm);
  }
  std::printf("[ figures  ] torque caps %.1f N m: %d of 40 uncapped torques exceed them; %d of 20 solved with the caps, "
              "worst excess %.2e N m\n",
              kCap_Nm, binding, solved, worst);
  EXPECT_GT(binding, 10);
  EXPECT_GT(solved, 15);
  EXPECT_LE(worst, 0.0);
}

}  // namespace
}  // namespace kuavo::test
