// Stepping in place: the swing rows (normal velocity), the swing corners' fixed zero force and
// the shifted warm start.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "tests/mpc/mpc_fixture.h"

namespace kuavo::test {
namespace {

using mpc::MpcStatus;

// Sole-corner positions (world) of the MPC's predicted state x_k.
Eigen::Matrix<double, 24, 1> predicted_corners(MpcFixture& f, int k) {
  const dynamics::ConfigVector q = mpc::configuration_from_state(f.ws.x[k], f.ws.head_rad[k]);
  dynamics::forward_kinematics(f.model, f.data, q);
  Eigen::Matrix<double, 24, 1> p;
  for (int c = 0; c < 8; ++c) p.segment<3>(3 * c) = dynamics::frame_position(f.model, f.data, c);
  return p;
}

TEST(MpcStepping, ConvergedPlanLiftsTheSwingFootAndLeansOverTheStanceFoot) {
  MpcFixture& f = mpc_fixture();
  const SteppingPlan plan;
  stepping_window(f, 0, plan);
  const dynamics::VelocityVector v0 = dynamics::VelocityVector::Zero();
  for (int it = 0; it < 15; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan), MpcStatus::kOk) << it;
  }
  std::printf("stepping: violation after 15 iterations %.2e\n", f.plan.constraint_violation);
  EXPECT_LT(f.plan.constraint_violation, 1e-6);
  const int T = f.ws.horizon;
  const double y_left = f.window.knots[0].point_position_m[1], y_right = f.window.knots[0].point_position_m[13];
  double max_z_err = 0.0, max_z_err_coarse = 0.0, max_swing_force = 0.0, min_stance_fz = 1e9;
  bool saw_swing = false;
  for (int k = 0; k < T; ++k) {
    const planner::PlanKnot& knot = f.window.knots[f.ws.stage_knot[k]];
    const Eigen::Matrix<double, 24, 1> p = predicted_corners(f, k);
    for (int c = 0; c < 8; ++c) {
      if (knot.in_contact[c]) {
        min_stance_fz = std::min(min_stance_fz, f.ws.u[k][3 * c + 2]);
        continue;
      }
      max_swing_force = std::max(max_swing_force, f.ws.u[k].segment<3>(3 * c).cwiseAbs().maxCoeff());
      const int first = c < 4 ? 0 : 4;
      if (knot.in_contact[first] || knot.in_contact[first + 1]) continue;  // heel-off: the heel pivots up freely
      saw_swing = true;
      double& worst = f.ws.stage_dt_s[k] < 1.5 * f.config.dt_s ? max_z_err : max_z_err_coarse;
      worst = std::max(worst, std::abs(p[3 * c + 2] - knot.point_position_m[3 * c + 2]));
    }
  }
  // Where is the CoM (from the plan knots' kinematics) in the middle of the left swing (0.5 s;
  // the stage starting there or, in a coarse tail, just after)?
  const int mid = first_stage_from(f, 25);
  const dynamics::ConfigVector q25 = mpc::configuration_from_state(f.ws.x[mid], f.ws.head_rad[mid]);
  dynamics::forward_kinematics(f.model, f.data, q25);
  dynamics::crba(f.model, f.data);
  const double lean = (f.data.com_m.y() - 0.5 * (y_left + y_right)) / (y_right - 0.5 * (y_left + y_right));
  std::printf("swing corner z error max %.2f mm (in the coarse tail: %.2f mm), swing force max %.2e N, min stance fz %.1f N, CoM at mid-swing %.0f %% of the way to the stance foot\n",
              1e3 * max_z_err, 1e3 * max_z_err_coarse, max_swing_force, min_stance_fz, 100 * lean);
  EXPECT_TRUE(saw_swing);
  EXPECT_LT(max_swing_force, 1e-6);
  EXPECT_LT(max_z_err, 0.01);  // the normal-velocity rows track z with gain 20/s
  // Beyond the first 0.4 s, over the tail's stages (dt_k = 0.08 s by default), Euler's local
  // error on the sine swing is dt_k²/2 · h (π / swing)², and the row carries an error over by
  // (1 − k dt_k): at most that local error / (1 − |1 − k dt_k|).
  const double dt_tail = *std::max_element(f.ws.stage_dt_s.begin(), f.ws.stage_dt_s.begin() + f.ws.horizon);
  const double loop = std::abs(1.0 - f.config.swing_position_gain_1_s * dt_tail);
  const double local = 0.5 * dt_tail * dt_tail * plan.height_m * std::pow(M_PI / plan.swing_s, 2);
  EXPECT_LT(max_z_err_coarse, std::max(0.01, local / (1.0 - loop)));
  EXPECT_GT(min_stance_fz, -1.0);
  EXPECT_GT(lean, 0.5);  // the CoM is moved over the stance foot
}

// Heel-toe: the last 0.1 s of double support on the swing foot's toes (partial-contact rows).
TEST(MpcStepping, HeelToeSequenceConverges) {
  MpcFixture& f = mpc_fixture();
  SteppingPlan plan;
  plan.heel_off_s = 0.1;
  stepping_window(f, 0, plan);
  for (int it = 0; it < 15; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, dynamics::VelocityVector::Zero(), f.window, f.plan),
              MpcStatus::kOk) << it;
  }
  EXPECT_LT(f.plan.constraint_violation, 1e-6);
  // During heel-off (stages 10–14) the heels carry nothing and rise as the foot pivots on its toes.
  const Eigen::Matrix<double, 24, 1> p14 = predicted_corners(f, 14);
  std::printf("heel-off: left heel force %.1e N, heel z at lift-off %.1f mm, toe z %.2f mm\n",
              f.ws.u[12].segment<6>(6).cwiseAbs().maxCoeff(), 1e3 * p14[8], 1e3 * p14[2]);
  EXPECT_LT(f.ws.u[12].segment<6>(6).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT(std::abs(p14[2]), 1e-3);  // the toes stay down
}

// 50 Hz calls with the window advancing one stage each time and the "measured" state taken from
// the previous prediction (perfect tracking): the warm start is shifted, every call succeeds,
// and the linearization stays consistent through lift-offs and touchdowns.
TEST(MpcStepping, ShiftedWarmStartThroughFourSteps) {
  MpcFixture& f = mpc_fixture();
  const SteppingPlan plan;
  static mpc::CentroidalPoint point;
  dynamics::ConfigVector q = f.q0;
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  double max_violation = 0.0, max_tail_violation = 0.0;
  const int calls = static_cast<int>(4 * (plan.stance_s + plan.swing_s) / f.config.dt_s);
  for (int call = 0; call < calls; ++call) {
    stepping_window(f, static_cast<hal::TimeNs>(call) * 20'000'000, plan);
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, q, v, f.window, f.plan), MpcStatus::kOk) << call;
    ASSERT_EQ(f.plan.count, mpc::kMpcPlanKnots);
    // Consistency of the linearization point over the knots the WBC reads (the newest tail stage
    // is a guess by construction and shows up in plan.constraint_violation, up to ~0.4 here).
    for (int k = 0; call >= 3 && k < mpc::kMpcPlanKnots; ++k) {
      const auto& st = f.ws.qp.stages[k];
      max_violation = std::max(max_violation, st.b.cwiseAbs().maxCoeff());
      if (st.num_eq > 0) max_violation = std::max(max_violation, st.e.head(st.num_eq).cwiseAbs().maxCoeff());
    }
    max_tail_violation = std::max(max_tail_violation, f.plan.constraint_violation);
    // Next measured state = predicted x_1 (and the base twist that goes with it).
    mpc::centroidal_evaluate(f.model, f.ws.x[1], f.ws.u[1], f.ws.head_rad[1], point);
    q = mpc::configuration_from_state(f.ws.x[1], f.ws.head_rad[1]);
    v.setZero();
    v.head<6>() = point.base_twist;
    v.segment<mpc::kNumMpcJoints>(6) = f.ws.u[1].segment<mpc::kNumMpcJoints>(mpc::kUJointVelocity);
  }
  std::printf("4 steps: max violation at the linearization point, knots 0-9 %.2e, whole horizon %.2e; final base z %.3f m, y %.3f m\n",
              max_violation, max_tail_violation, q[2], q[1]);
  EXPECT_LT(max_violation, 1e-3);
  EXPECT_NEAR(q[2], f.q0[2], 0.03);
  EXPECT_NEAR(q[1], f.q0[1], 0.05);
}

}  // namespace
}  // namespace kuavo::test

namespace kuavo::test {
namespace {

// Every allowed horizon converges on the stepping problem (1.4 s uses the full capacity, 70).
class MpcHorizon : public ::testing::TestWithParam<double> {};

TEST_P(MpcHorizon, ConvergesOnTheSteppingProblem) {
  mpc::MpcConfig cfg;
  cfg.horizon_s = GetParam();
  MpcFixture& f = mpc_fixture(cfg);
  EXPECT_EQ(f.ws.stage_knot[f.ws.horizon], static_cast<int>(std::lround(GetParam() / 0.02)));
  stepping_window(f, 0, SteppingPlan{});
  for (int it = 0; it < 12; ++it) {
    ASSERT_EQ(mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, dynamics::VelocityVector::Zero(), f.window, f.plan),
              mpc::MpcStatus::kOk);
  }
  EXPECT_LT(f.plan.constraint_violation, 1e-6);
  EXPECT_EQ(f.plan.count, mpc::kMpcPlanKnots);
}

INSTANTIATE_TEST_SUITE_P(Horizons, MpcHorizon, ::testing::Values(0.6, 0.8, 1.0, 1.4),
                         [](const auto& info) { return std::to_string(static_cast<int>(std::lround(info.param * 1000))) + "ms"; });

}  // namespace
}  // namespace kuavo::test

namespace kuavo::test {
namespace {

// The equality rows as the QP holds them (C, D, e of a stage), against an independent
// evaluation with the rigid-body library's world kinematics, differentiated by central
// differences: stance foot twist rows, swing normal-velocity rows. (The swing corners' zero
// force is not a row: those inputs are fixed, checked in the test below.)
struct RowOracle {
  MpcFixture* f;
  const planner::PlanKnot* knot;
  mpc::HeadVector head;
  mpc::CentroidalPoint point;
  dynamics::Data data;
  dynamics::FrameJacobian jac;

  Eigen::VectorXd rows(const mpc::StateVector& x, const mpc::InputVector& u) {
    const model::Model& m = f->model;
    mpc::centroidal_evaluate(m, x, u, head, point);  // only for the base twist (checked in centroidal_model_test)
    const dynamics::ConfigVector q = mpc::configuration_from_state(x, head);
    dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
    v.head<6>() = point.base_twist;
    v.segment<mpc::kNumMpcJoints>(6) = u.segment<mpc::kNumMpcJoints>(mpc::kUJointVelocity);
    dynamics::forward_kinematics(m, data, q);
    dynamics::forward_velocities(m, data, v);
    const dynamics::Mat3 r = data.rotation[0];
    Eigen::VectorXd out(mpc::kMaxEqualities);
    int n_rows = 0;
    for (int foot = 0; foot < 2; ++foot) {
      const int first = 4 * foot;
      int n = 0;
      for (int c = first; c < first + 4; ++c) n += knot->in_contact[c] ? 1 : 0;
      if (n == 4) {
        dynamics::Vec3 centre = dynamics::Vec3::Zero();
        for (int c = first; c < first + 4; ++c) centre += dynamics::frame_position(m, data, c) / 4.0;
        dynamics::point_jacobian(m, data, m.frames[first].body, centre, jac);
        const dynamics::Vec6 twist = jac * v;
        out.segment<3>(n_rows) = r.transpose() * twist.head<3>();
        out.segment<3>(n_rows + 3) = r.transpose() * twist.tail<3>();
        n_rows += 6;
      } else if (n > 0) {  // partial contact: the contact corners' centroid does not move
        dynamics::Vec3 centre = dynamics::Vec3::Zero();
        for (int c = first; c < first + 4; ++c) {
          if (knot->in_contact[c]) centre += dynamics::frame_position(m, data, c) / n;
        }
        dynamics::point_jacobian(m, data, m.frames[first].body, centre, jac);
        const dynamics::Vec6 twist = jac * v;
        out.segment<3>(n_rows) = r.transpose() * twist.head<3>();
        n_rows += 3;
        if (n == 2) {  // angular velocity across the contact line, directions fixed in the foot
          int ends[2] = {first, first}, found = 0;
          for (int c = first; c < first + 4; ++c) {
            if (knot->in_contact[c] && found < 2) ends[found++] = c;
          }
          const dynamics::Vec3 d = (m.frames[ends[1]].position_m - m.frames[ends[0]].position_m).normalized();
          int axis = 0;
          d.cwiseAbs().minCoeff(&axis);
          const dynamics::Vec3 e1 = d.cross(dynamics::Vec3::Unit(axis)).normalized(), e2 = d.cross(e1);
          const dynamics::Mat3 foot = data.rotation[m.frames[first].body];
          out[n_rows++] = (foot * e1).dot(twist.tail<3>());
          out[n_rows++] = (foot * e2).dot(twist.tail<3>());
        }
      } else {
        for (int c = first; c < first + 3; ++c) {
          out[n_rows++] = dynamics::frame_velocity(m, data, c).z() + f->config.swing_position_gain_1_s * dynamics::frame_position(m, data, c).z() -
                          knot->point_velocity_m_s[3 * c + 2] - f->config.swing_position_gain_1_s * knot->point_position_m[3 * c + 2];
        }
      }
    }
    return out.head(n_rows);
  }
};

TEST(MpcStepping, EqualityRowsMatchFiniteDifferencesOfTheWorldKinematics) {
  MpcFixture& f = mpc_fixture();
  SteppingPlan plan;
  plan.heel_off_s = 0.1;  // stages 10–14: left toes only (partial-contact rows)
  stepping_window(f, 0, plan);
  dynamics::VelocityVector v0 = dynamics::VelocityVector::Zero();
  v0[0] = 0.1;
  v0[1] = -0.1;
  for (int it = 0; it < 3; ++it) mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan);
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v0, f.window), mpc::MpcStatus::kOk);
  static RowOracle oracle;
  constexpr double kStep = 1e-6;
  int swing_stages = 0;
  int partial_stages = 0;
  // The stages starting at (or, in a coarse tail, first after) knots 2, 12 (toes), 20, 30
  // (swing), 40, 48 (toes), 56 (swing).
  for (const int knot : {2, 12, 20, 30, 40, 48, 56}) {
    const int k = first_stage_from(f, knot);
    const auto& st = f.ws.qp.stages[k];
    oracle.f = &f;
    oracle.knot = &f.window.knots[f.ws.stage_knot[k]];
    oracle.head = f.ws.head_rad[k];
    const Eigen::VectorXd value = oracle.rows(f.ws.x[k], f.ws.u[k]);
    ASSERT_EQ(value.size(), st.num_eq) << k;
    swing_stages += st.num_eq == 9 ? 1 : 0;     // 3 normal velocity + 6 twist
    partial_stages += st.num_eq == 11 ? 1 : 0;  // 3 centroid + 2 across the toe line + 6 twist
    const int ne = st.num_eq;
    EXPECT_LT((value + st.e.head(ne)).cwiseAbs().maxCoeff(), 1e-9) << k;
    Eigen::MatrixXd cx(ne, mpc::kNx), du(ne, mpc::kNu);
    for (int i = 0; i < mpc::kNx; ++i) {
      mpc::StateVector xp = f.ws.x[k], xm = f.ws.x[k];
      xp[i] += kStep;
      xm[i] -= kStep;
      cx.col(i) = (oracle.rows(xp, f.ws.u[k]) - oracle.rows(xm, f.ws.u[k])) / (2 * kStep);
    }
    for (int i = 0; i < mpc::kNu; ++i) {
      mpc::InputVector up = f.ws.u[k], um = f.ws.u[k];
      up[i] += kStep;
      um[i] -= kStep;
      du.col(i) = (oracle.rows(f.ws.x[k], up) - oracle.rows(f.ws.x[k], um)) / (2 * kStep);
    }
    const double ex = (st.C.topRows(ne) - cx).cwiseAbs().maxCoeff() / std::max(1.0, cx.cwiseAbs().maxCoeff());
    const double eu = (st.D.topRows(ne) - du).cwiseAbs().maxCoeff() / std::max(1.0, du.cwiseAbs().maxCoeff());
    std::printf("stage %d: %d rows, relative error C %.1e, D %.1e\n", k, ne, ex, eu);
    EXPECT_LT(ex, 1e-6) << k;
    EXPECT_LT(eu, 1e-6) << k;
  }
  EXPECT_GE(swing_stages, 2);
  EXPECT_GE(partial_stages, 2);
}

}  // namespace
}  // namespace kuavo::test

namespace kuavo::test {
namespace {

double barrier(double h, double mu, double delta) {  // OCS2's relaxed log barrier, by its definition
  if (h > delta) return -mu * std::log(h);
  const double z = (h - 2.0 * delta) / delta;
  return 0.5 * mu * (z * z - 1.0) - mu * std::log(delta);
}

// The stage cost written out from its definition (mpc.h), with world kinematics for the swing
// corners: its finite-difference gradient must be the QP's (q, r) at the linearization point.
double stage_cost(MpcFixture& f, int k, const mpc::StateVector& x, const mpc::InputVector& u, dynamics::Data& data) {
  const mpc::MpcConfig& c = f.config;
  const planner::PlanKnot& knot = f.window.knots[f.ws.stage_knot[k]];
  const double dt = f.ws.stage_dt_s[k];  // a coarse tail's stages integrate over several dt
  mpc::StateVector e = x - f.ws.x_ref[k];
  e[mpc::kXEuler] = std::remainder(e[mpc::kXEuler], 2 * M_PI);
  const mpc::InputVector du = u - f.ws.u_ref[k];
  double cost = 0.5 * dt * (e.dot(f.ws.weight_state.cwiseProduct(e)) + du.dot(f.ws.weight_input.cwiseProduct(du)));
  for (int j = 0; j < mpc::kNumMpcJoints; ++j) {
    const double qj = x[mpc::kXJoints + j];
    cost += dt * (barrier(qj - f.model.limits.position_min_rad[j], c.joint_limit_barrier_mu, c.joint_limit_barrier_delta_rad) +
                      barrier(f.model.limits.position_max_rad[j] - qj, c.joint_limit_barrier_mu, c.joint_limit_barrier_delta_rad));
  }
  // Leg joint torques of the stance feet from their corner forces (mpc.h: the
  // foot geometry is the linearization point's, so the term has no state gradient), world
  // kinematics of the whole configuration (the MPC works in base axes).
  if (c.stance_leg_torque_share > 0.0) {
    dynamics::forward_kinematics(f.model, data, mpc::configuration_from_state(f.ws.x[k], f.ws.head_rad[k]));
    for (int foot = 0; foot < 2; ++foot) {
      bool down = false;
      for (int p = 4 * foot; p < 4 * foot + 4; ++p) down = down || knot.in_contact[p];
      if (!down) continue;
      Eigen::Vector2d ankle = Eigen::Vector2d::Zero();
      for (int joint = 0; joint < 6; ++joint) {
        const int body = 1 + 6 * foot + joint;
        const dynamics::Vec3 axis = data.rotation[body] * f.model.bodies[body].axis;
        double tau = 0.0;
        for (int p = 4 * foot; p < 4 * foot + 4; ++p) {
          if (!knot.in_contact[p]) continue;
          const dynamics::Vec3 r = dynamics::frame_position(f.model, data, p) - data.position_m[body];
          tau += axis.dot(r.cross(dynamics::Vec3(u.segment<3>(3 * p))));
        }
        const double limit = c.stance_leg_torque_share * f.model.limits.torque_Nm[6 * foot + joint];
        cost += dt * (barrier(limit - tau, c.leg_torque_barrier_mu, c.leg_torque_barrier_delta_Nm) +
                      barrier(limit + tau, c.leg_torque_barrier_mu, c.leg_torque_barrier_delta_Nm));
        if (joint >= 4) ankle[joint - 4] = tau;  // pitch, roll
      }
      // The ankle motors: (A, B) = joint_to_motor · (pitch, roll), each within its share.
      const hal::AnkleMotorLimits& m = f.ws.ankle_motor_limits;
      for (int k2 = 0; m.active && k2 < 2; ++k2) {
        const double tau = m.joint_to_motor[foot].row(k2).dot(ankle);
        const double limit = c.stance_leg_torque_share * m.limit_Nm[foot](k2);
        cost += dt * (barrier(limit - tau, c.leg_torque_barrier_mu, c.leg_torque_barrier_delta_Nm) +
                      barrier(limit + tau, c.leg_torque_barrier_mu, c.leg_torque_barrier_delta_Nm));
      }
    }
  }
  dynamics::forward_kinematics(f.model, data, mpc::configuration_from_state(x, f.ws.head_rad[k]));
  for (int p = 0; p < 8; ++p) {
    const dynamics::Vec3 fp = u.segment<3>(3 * p);
    if (knot.in_contact[p]) {
      const double mu = c.friction_coefficient;
      for (const double h : {mu * fp.z() - fp.x(), mu * fp.z() + fp.x(), mu * fp.z() - fp.y(), mu * fp.z() + fp.y()}) {
        cost += dt * barrier(h, c.friction_barrier_mu, c.friction_barrier_delta_N);
      }
    } else {
      const Eigen::Vector2d d = dynamics::frame_position(f.model, data, p).head<2>() - knot.point_position_m.segment<2>(3 * p);
      cost += 0.5 * dt * c.weight_swing_xy * d.squaredNorm();
    }
  }
  return cost;
}

// The stepping window from t = 0, the MPC warmed by two iterations from the nominal pose moving
// sideways at vy: returns the initial velocity the QP is then built at.
dynamics::VelocityVector warm_stepping(MpcFixture& f, double vy) {
  stepping_window(f, 0, SteppingPlan{});
  dynamics::VelocityVector v0 = dynamics::VelocityVector::Zero();
  v0[1] = vy;
  for (int it = 0; it < 2; ++it) mpc::mpc_step_rt(f.model, f.config, f.ws, f.q0, v0, f.window, f.plan);
  return v0;
}

void expect_stage_cost_gradient(MpcFixture& f) {
  const dynamics::VelocityVector v0 = warm_stepping(f, 0.15);
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v0, f.window), mpc::MpcStatus::kOk);
  static dynamics::Data data;
  constexpr double kStep = 1e-6;
  for (const int knot : {3, 24, 50}) {  // stance, then swing stages (coarse in the default tail)
    const int k = first_stage_from(f, knot);
    const auto& st = f.ws.qp.stages[k];
    mpc::StateVector gx;
    mpc::InputVector gu;
    for (int i = 0; i < mpc::kNx; ++i) {
      mpc::StateVector xp = f.ws.x[k], xm = f.ws.x[k];
      xp[i] += kStep;
      xm[i] -= kStep;
      gx[i] = (stage_cost(f, k, xp, f.ws.u[k], data) - stage_cost(f, k, xm, f.ws.u[k], data)) / (2 * kStep);
    }
    for (int i = 0; i < mpc::kNu; ++i) {
      mpc::InputVector up = f.ws.u[k], um = f.ws.u[k];
      up[i] += kStep;
      um[i] -= kStep;
      gu[i] = (stage_cost(f, k, f.ws.x[k], up, data) - stage_cost(f, k, f.ws.x[k], um, data)) / (2 * kStep);
    }
    // A swing corner's force is a fixed input (mpc.h): its r entry is the fixing term, not the
    // cost gradient; checked in SwingForcesAreFixedInputsWithExactZeroResult.
    mpc::InputVector r = st.r;
    for (int c = 0; c < mpc::kNumPoints; ++c) {
      if (!f.window.knots[f.ws.stage_knot[k]].in_contact[c]) {
        r.segment<3>(3 * c).setZero();
        gu.segment<3>(3 * c).setZero();
      }
    }
    const double ex = (st.q - gx).cwiseAbs().maxCoeff() / std::max(1e-3, gx.cwiseAbs().maxCoeff());
    const double eu = (r - gu).cwiseAbs().maxCoeff() / std::max(1e-3, gu.cwiseAbs().maxCoeff());
    std::printf("stage %d: gradient relative error x %.1e (max %.2e), u %.1e (max %.2e)\n", k, ex, gx.cwiseAbs().maxCoeff(), eu,
                gu.cwiseAbs().maxCoeff());
    EXPECT_LT(ex, 1e-5) << k;
    EXPECT_LT(eu, 1e-5) << k;
  }
}

TEST(MpcStepping, StageCostGradientMatchesFiniteDifferencesOfItsDefinition) { expect_stage_cost_gradient(mpc_fixture()); }

// The same with the ankle motors known (the firmware's binding): the linkage's map near the
// zero pose (drivers/transmission: A ≈ 0.5 τ_pitch + 1.1 τ_roll, B ≈ 0.5 τ_pitch − 1.1 τ_roll)
// and 6 N·m limits, so the stance ankles' motor torques (~4 N·m standing) press on the barrier
// well beyond the joint-space terms: without the motor rows r differs by their gradient.
TEST(MpcStepping, StageCostGradientWithTheAnkleMotorsMatchesFiniteDifferences) {
  MpcFixture& f = mpc_fixture();
  hal::AnkleMotorLimits& m = f.ws.ankle_motor_limits;
  m.active = true;
  for (int leg = 0; leg < 2; ++leg) {
    m.joint_to_motor[leg] << 0.497, 1.100, 0.503, -1.100;
    m.limit_Nm[leg] = Eigen::Vector2d(6.0, 6.0);
  }
  expect_stage_cost_gradient(f);
  m = hal::AnkleMotorLimits{};  // the fixture is shared
}

// The swing corners' zero force as fixed inputs: in the QP their B columns are zero (folded into
// b: the dynamics' constant term equals the unfixed one plus B's columns times the step), R's
// row and column are the unit vector, r = f̄; after the solve every swing corner's force is
// exactly zero (f̄ + δf, δf = −f̄ bit for bit) while stance corners carry the weight.
TEST(MpcStepping, SwingForcesAreFixedInputsWithExactZeroResult) {
  MpcFixture& f = mpc_fixture();
  const dynamics::VelocityVector v0 = warm_stepping(f, 0.1);
  // A warm start whose swing forces are not zero: the fixed step must cancel them.
  for (int k = 0; k <= f.ws.horizon; ++k) f.ws.u[k].segment<3 * mpc::kNumPoints>(0).array() += 0.5;
  ASSERT_EQ(mpc::mpc_build_qp_rt(f.model, f.config, f.ws, f.q0, v0, f.window), mpc::MpcStatus::kOk);
  int fixed = 0;
  for (int k = 0; k < f.ws.horizon; ++k) {
    const auto& st = f.ws.qp.stages[k];
    // The unfixed dynamics from the model, as mpc_build_qp_rt forms them before fixing.
    static mpc::CentroidalPoint point;
    mpc::centroidal_evaluate(f.model, f.ws.x[k], f.ws.u[k], f.ws.head_rad[k], point);
    const double dt = f.ws.stage_dt_s[k];
    mpc::StateVector b = f.ws.x[k] + dt * point.f - f.ws.x[k + 1];
    for (int c = 0; c < mpc::kNumPoints; ++c) {
      if (f.window.knots[f.ws.stage_knot[k]].in_contact[c]) continue;
      for (int i = 0; i < 3; ++i) {
        const int col = 3 * c + i;
        b += dt * point.fu.col(col) * (-f.ws.u[k][col]);
        EXPECT_EQ(st.B.col(col).cwiseAbs().maxCoeff(), 0.0) << k;
        EXPECT_EQ(st.R(col, col), 1.0) << k;
        EXPECT_EQ(st.R.row(col).cwiseAbs().sum(), 1.0) << k;
        EXPECT_EQ(st.r[col], f.ws.u[k][col]) << k;
        ++fixed;
      }
    }
    EXPECT_LT((st.b - b).cwiseAbs().maxCoeff(), 1e-12) << k;
  }
  EXPECT_GT(fixed, 0);
  ASSERT_EQ(mpc::mpc_solve_qp_rt(f.ws), mpc::MpcStatus::kOk);
  double stance_fz = 0.0;
  for (int k = 0; k < f.ws.horizon; ++k) {
    for (int c = 0; c < mpc::kNumPoints; ++c) {
      if (!f.window.knots[f.ws.stage_knot[k]].in_contact[c]) {
        EXPECT_EQ(f.ws.u[k].segment<3>(3 * c).cwiseAbs().maxCoeff(), 0.0) << k << " " << c;
      } else if (k == 0) {
        stance_fz += f.ws.u[k][3 * c + 2];
      }
    }
  }
  EXPECT_GT(stance_fz, 0.5 * f.model.total_mass_kg * model::kGravity_m_s2);
}

}  // namespace
}  // namespace kuavo::test
