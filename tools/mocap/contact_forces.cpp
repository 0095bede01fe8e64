#include "tools/mocap/contact_forces.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "controllers/qp/dense_qp_solver.h"
#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"

namespace kuavo::mocap {
namespace {

using dynamics::VelocityVector;

constexpr int kPoints = model::kNumContactPoints;
constexpr int kForces = 3 * kPoints;
constexpr int kSlots = 2 * model::kLegJoints;  // the leg slots: 4 joints and 2 ankle motors per leg
constexpr int kNv = kForces + kSlots;
constexpr int kFrictionRows = 4 * kPoints;
constexpr int kNi = kFrictionRows + 2 * kSlots;

// ½ w_f ‖f − f_prior‖²: small against the slacks' exact penalty, so the prior only breaks
// ties (which of the distributions that hold the limits): 100 N off it costs 5.
constexpr double kPriorWeight_per_N2 = 1e-3;
// The slack's linear cost, per N·m: above any multiplier a limit row needs where a
// distribution within the cones holds it (w_f · Δf / lever ~ 1e-3 · 500 N / 0.05 m = 10).
constexpr double kExcessCost_per_Nm = 1e3;
// Fallback of a frame whose base wrench no forces in the cones supply: ½ w_b ‖A f − b‖².
constexpr double kBaseWeight = 1.0;

using Qp = qp::DenseQp<kNv, 6, kNi>;
using QpSoft = qp::DenseQp<kNv, 0, kNi>;

template <class P>
void fill_common(P& qp, const std::array<bool, kPoints>& stance, const ForceVector& prior, double mu,
                 const Eigen::Matrix<double, kSlots, kForces>& g_rows, const Eigen::Matrix<double, kSlots, 1>& n_rows,
                 const Eigen::Matrix<double, kSlots, 1>& limit) {
  qp.H.setZero();
  qp.g.setZero();
  qp.C.setZero();
  qp.c_lower.setConstant(-qp::kInfinity);
  qp.c_upper.setConstant(qp::kInfinity);
  qp.x_lower.setConstant(-qp::kInfinity);
  qp.x_upper.setConstant(qp::kInfinity);
  for (int i = 0; i < kForces; ++i) {
    qp.H(i, i) = kPriorWeight_per_N2;
    qp.g[i] = stance[i / 3] ? -kPriorWeight_per_N2 * prior[i] : 0.0;
  }
  for (int c = 0; c < kPoints; ++c) {
    if (!stance[c]) continue;  // its columns stay zero: the cost alone keeps it at 0
    const int x = 3 * c, z = x + 2;
    qp.x_lower[z] = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
      const int r = 4 * c + 2 * axis;
      qp.C(r, x + axis) = 1.0, qp.C(r, z) = -mu, qp.c_upper[r] = 0.0;     // f_t − μ f_z ≤ 0
      qp.C(r + 1, x + axis) = 1.0, qp.C(r + 1, z) = mu, qp.c_lower[r + 1] = 0.0;  // f_t + μ f_z ≥ 0
    }
  }
  for (int j = 0; j < kSlots; ++j) {
    const int s = kForces + j;
    qp.H(s, s) = 1.0;
    qp.g[s] = kExcessCost_per_Nm;
    qp.x_lower[s] = 0.0;
    // τ = n − G f:  −G f + s ≥ −limit − n  and  −G f − s ≤ limit − n.
    const int ra = kFrictionRows + 2 * j, rb = ra + 1;
    qp.C.row(ra).template head<kForces>() = -g_rows.row(j);
    qp.C(ra, s) = 1.0;
    qp.c_lower[ra] = -limit[j] - n_rows[j];
    qp.C.row(rb).template head<kForces>() = -g_rows.row(j);
    qp.C(rb, s) = -1.0;
    qp.c_upper[rb] = limit[j] - n_rows[j];
  }
}

}  // namespace

void contact_forces_for_motion(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q,
                               const std::vector<ContactLabel>& contacts, double rate_hz, double mu,
                               const std::vector<ForceVector>& prior, std::vector<ForceVector>& out,
                               ContactForceStats& stats) {
  const int n = static_cast<int>(q.size());
  stats = ContactForceStats{};
  stats.frames = n;
  out.assign(n, ForceVector::Zero());
  std::vector<VelocityVector> v, a;
  frame_rates(q, rate_hz, v, a);
  auto data = std::make_unique<dynamics::Data>();
  auto qp = std::make_unique<Qp>();
  auto qp_soft = std::make_unique<QpSoft>();
  auto ws = std::make_unique<qp::DenseQpWorkspace<kNv, 6, kNi>>();
  auto ws_soft = std::make_unique<qp::DenseQpWorkspace<kNv, 0, kNi>>();
  auto sol = std::make_unique<qp::DenseQpSolution<kNv, 6, kNi>>();
  auto sol_soft = std::make_unique<qp::DenseQpSolution<kNv, 0, kNi>>();
  qp::DenseQpSettings settings;
  settings.max_iterations = 500;
  drivers::AnkleMotors motors = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot));
  std::array<dynamics::FrameJacobian, kPoints> jac;

  for (int i = 0; i < n; ++i) {
    std::array<bool, kPoints> stance{};
    bool any = false;
    for (int c = 0; c < kPoints; ++c) {
      stance[c] = c < 4 ? left_in_contact(contacts[i]) : right_in_contact(contacts[i]);
      any = any || stance[c];
    }
    if (!any) continue;  // flight: no forces
    dynamics::forward_kinematics(robot, *data, q[i]);
    dynamics::forward_velocities(robot, *data, v[i]);
    dynamics::rnea(robot, *data, a[i], true);
    const VelocityVector needed = data->tau;
    for (int c = 0; c < kPoints; ++c) dynamics::frame_jacobian(robot, *data, c, jac[c]);

    // Base rows and the leg slots as functions of f (τ = n − G f), ankles in motor space.
    Eigen::Matrix<double, 6, kForces> base = Eigen::Matrix<double, 6, kForces>::Zero();
    Eigen::Matrix<double, kSlots, kForces> g_rows = Eigen::Matrix<double, kSlots, kForces>::Zero();
    Eigen::Matrix<double, kSlots, 1> n_rows, limit;
    for (int c = 0; c < kPoints; ++c) {
      if (!stance[c]) continue;
      base.middleCols<3>(3 * c) = jac[c].topRows<3>().leftCols<6>().transpose();
    }
    for (int leg = 0; leg < 2; ++leg) {
      const int first = leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
      for (int k = 0; k < model::kLegJoints; ++k) {
        const int j = first + k, r = 6 * leg + k;
        n_rows[r] = needed[6 + j];
        limit[r] = robot.limits.torque_Nm[j];
        for (int c = 0; c < kPoints; ++c) {
          if (stance[c]) g_rows.row(r).segment<3>(3 * c) = jac[c].topRows<3>().col(6 + j).transpose();
        }
      }
      if (!motors.active) continue;
      const int ja = first + 4;
      const Eigen::Vector2d ankle(q[i][7 + ja], q[i][8 + ja]);
      Eigen::Matrix2d to_motor;
      bool mapped = true;
      for (int col = 0; col < 2 && mapped; ++col) {
        Eigen::Vector2d motor;
        mapped = drivers::ankle_motor_torques_rt(motors, leg, ankle, Eigen::Vector2d::Unit(col), motor);
        to_motor.col(col) = motor;
      }
      if (!mapped) continue;  // off the linkage's reach: the joint box stands (as in the oracle)
      const int r = 6 * leg + 4;
      const Eigen::Vector2d n_motor = to_motor * n_rows.segment<2>(r);
      const Eigen::Matrix<double, 2, kForces> g_motor = to_motor * g_rows.middleRows<2>(r);
      n_rows.segment<2>(r) = n_motor;
      g_rows.middleRows<2>(r) = g_motor;
      limit.segment<2>(r) = motors.limit_Nm[leg];
    }

    fill_common(*qp, stance, prior[i], mu, g_rows, n_rows, limit);
    qp->A.setZero();
    qp->A.leftCols<kForces>() = base;
    qp->b = needed.head<6>();
    Eigen::Matrix<double, kNv, 1> x;
    if (qp::solve_dense_qp(*qp, settings, *ws, *sol) == qp::QpStatus::kSolved) {
      x = sol->x;
    } else {
      ++stats.frames_infeasible;
      fill_common(*qp_soft, stance, prior[i], mu, g_rows, n_rows, limit);
      const Eigen::Matrix<double, kNv, 6> at = qp->A.transpose();
      qp_soft->H.noalias() += kBaseWeight * at * qp->A;
      qp_soft->g.noalias() -= kBaseWeight * at * qp->b;
      if (qp::solve_dense_qp(*qp_soft, settings, *ws_soft, *sol_soft) != qp::QpStatus::kSolved) {
        out[i] = prior[i];
        continue;
      }
      x = sol_soft->x;
    }
    out[i] = x.head<kForces>();
    for (int c = 0; c < kPoints; ++c) {
      if (!stance[c]) out[i].segment<3>(3 * c).setZero();
    }
    const double excess = x.tail<kSlots>().maxCoeff();
    if (excess > 1e-6) {
      ++stats.frames_over_limit;
      stats.max_excess_Nm = std::max(stats.max_excess_Nm, excess);
    }
  }
}

}  // namespace kuavo::mocap
