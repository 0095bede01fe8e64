#include "controllers/mpc/mpc.h"

#include <algorithm>
#include <Eigen/Cholesky>
#include <cmath>
#include <cstdint>
#include <limits>

#include "controllers/qp/dense_qp_solver.h"

namespace kuavo::mpc {
namespace {

constexpr double kTwoPi = 6.28318530717958647692;
// The plan window's dt must be the MPC's; stamps are integers, so this is only roundoff.
constexpr double kDtTolerance_s = 1e-9;

// Tikhonov term on the force-distribution Gram matrix [m², relative to O(0.01–1) entries].
constexpr double kReferenceForceRegularization = 1e-6;

// Ankle pitch within a leg (roll follows): the ankle pair the motor map covers.

Mat3 skew_of(const Vec3& a) { return dynamics::skew(a); }

double wrap_angle(double a) { return std::remainder(a, kTwoPi); }

StateVector state_error(const StateVector& x, const StateVector& x_ref) {
  StateVector d = x - x_ref;
  d[kXEuler] = wrap_angle(d[kXEuler]);  // yaw
  return d;
}

// The knot values the reference state and inputs are made of (reference_forces and
// state_from_configuration): equal values, equal results.
bool same_reference_knot(const planner::PlanKnot& a, const planner::PlanKnot& b) {
  return a.stamp_ns == b.stamp_ns && a.in_contact == b.in_contact && a.q == b.q && a.v == b.v &&
         a.point_position_m == b.point_position_m && a.com_position_m == b.com_position_m;
}

bool knot_finite(const planner::PlanKnot& k) {
  return k.q.allFinite() && k.v.allFinite() && k.point_position_m.allFinite() && k.point_velocity_m_s.allFinite();
}

int contacts_of_foot(const planner::ContactFlags& flags, int foot) {
  int n = 0;
  for (int c = kPointsPerFoot * foot; c < kPointsPerFoot * (foot + 1); ++c) n += flags[c] ? 1 : 0;
  return n;
}

// u_ref forces: the least-norm stance forces that carry the wrench w = [Σf; Σ(cᵢ − r) × fᵢ],
// f = Aᵀ(AAᵀ)⁻¹ w with Aᵢ = [I; [cᵢ − r]×]: by default w = [m g; 0], the weight with no
// moment about the CoM -- with the CoM over the support the static solution itself (an
// equal split would put a moment on the robot and bias the optimum toward leaning); with
// MpcConfig::reference_forces_from_motion the reference's own wrench. Zero in flight.
void reference_forces(const planner::PlanKnot& knot, const Vec6& w, InputVector& u_ref) {
  u_ref.segment<3 * kNumPoints>(kUForces).setZero();
  dynamics::Mat6 gram = dynamics::Mat6::Zero();
  int stance = 0;
  for (int c = 0; c < kNumPoints; ++c) {
    if (!knot.in_contact[c]) continue;
    ++stance;
    const Mat3 s = skew_of(knot.point_position_m.segment<3>(3 * c) - knot.com_position_m);
    gram.topLeftCorner<3, 3>() += Mat3::Identity();
    gram.topRightCorner<3, 3>() += s.transpose();
    gram.bottomLeftCorner<3, 3>() += s;
    gram.bottomRightCorner<3, 3>() += s * s.transpose();
  }
  if (stance == 0) return;
  // Regularized: a line or point support leaves a moment direction without authority.
  gram.diagonal().array() += kReferenceForceRegularization;
  const Vec6 y = gram.ldlt().solve(w);
  for (int c = 0; c < kNumPoints; ++c) {
    if (!knot.in_contact[c]) continue;
    const Mat3 s = skew_of(knot.point_position_m.segment<3>(3 * c) - knot.com_position_m);
    u_ref.segment<3>(kUForces + 3 * c) = y.head<3>() + s.transpose() * y.tail<3>();
  }
}

// u_ref forces for a wrench w the support may not carry (reference_forces_from_motion): the
// stance corners' forces minimizing ½‖A f − w‖² + ½ε‖f‖² subject to the friction pyramids
// |f_x|, |f_y| ≤ μ f_z and f_z ≥ 0 (A as in reference_forces; force rows in N and moment rows
// in N·m weighted alike, a 1 m lever). A wrench inside what the feet can carry comes back
// exactly, as its least-norm forces within the cones; one outside (a centre of pressure off
// the feet, a pull on the ground, a push beyond friction, as an infeasible reference asks)
// as the nearest wrench they can carry. False if the QP failed (u_ref is then left as is).
bool reference_forces_in_cones(const planner::PlanKnot& knot, const Vec6& w, double mu, MpcWorkspace& ws,
                               InputVector& u_ref) {
  constexpr int kF = 3 * kNumPoints;
  WrenchQp& qp = ws.wrench_qp;
  Eigen::Matrix<double, 6, kF> a = Eigen::Matrix<double, 6, kF>::Zero();
  qp.C.setZero();
  qp.c_lower.setConstant(-qp::kInfinity);
  qp.c_upper.setConstant(qp::kInfinity);
  qp.x_lower.setConstant(-qp::kInfinity);
  qp.x_upper.setConstant(qp::kInfinity);
  bool any = false;
  for (int c = 0; c < kNumPoints; ++c) {
    if (!knot.in_contact[c]) continue;  // its columns stay zero: the regularization keeps it at 0
    any = true;
    const int x = 3 * c, z = x + 2;
    a.block<3, 3>(0, x).setIdentity();
    a.block<3, 3>(3, x) = skew_of(knot.point_position_m.segment<3>(3 * c) - knot.com_position_m);
    qp.x_lower[z] = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
      const int r = 4 * c + 2 * axis;
      qp.C(r, x + axis) = 1.0, qp.C(r, z) = -mu, qp.c_upper[r] = 0.0;              // f_t − μ f_z ≤ 0
      qp.C(r + 1, x + axis) = 1.0, qp.C(r + 1, z) = mu, qp.c_lower[r + 1] = 0.0;   // f_t + μ f_z ≥ 0
    }
  }
  u_ref.segment<kF>(kUForces).setZero();
  if (!any) return true;
  qp.H.noalias() = a.transpose() * a;
  qp.H.diagonal().array() += kReferenceForceRegularization;
  qp.g.noalias() = -a.transpose() * w;
  if (qp::solve_dense_qp(qp, qp::DenseQpSettings{}, ws.wrench_qp_workspace, ws.wrench_qp_solution) !=
      qp::QpStatus::kSolved) {
    return false;
  }
  for (int c = 0; c < kNumPoints; ++c) {
    if (knot.in_contact[c]) u_ref.segment<3>(kUForces + 3 * c) = ws.wrench_qp_solution.x.segment<3>(3 * c);
  }
  return true;
}

void fill_weights(const model::Model& model, const MpcConfig& c, MpcWorkspace& ws) {
  const double m = model.total_mass_kg;
  StateVector& w = ws.weight_state;
  for (int i = 0; i < 3; ++i) {
    w[kXComVelocity + i] = c.weight_com_velocity[i];
    w[kXMomentum + i] = c.weight_angular_momentum_normalized[i] / (m * m);
    w[kXBasePosition + i] = c.weight_base_position[i];
    w[kXEuler + i] = c.weight_base_euler[i];
  }
  for (int j = 0; j < 2 * model::kLegJoints; ++j) w[kXJoints + j] = c.weight_leg_joint[j % model::kLegJoints];
  for (int j = 2 * model::kLegJoints; j < kNumMpcJoints; ++j) w[kXJoints + j] = c.weight_arm_joint;
  InputVector& r = ws.weight_input;
  r.segment<3 * kNumPoints>(kUForces).setConstant(c.weight_force);
  r.segment<2 * model::kLegJoints>(kUJointVelocity).setConstant(c.weight_leg_joint_velocity);
  r.segment<kNumMpcJoints - 2 * model::kLegJoints>(kUJointVelocity + 2 * model::kLegJoints)
      .setConstant(c.weight_arm_joint_velocity);
}

// Relaxed-barrier terms of the joint position limits on the joint block of (Q, q).
template <class StageT>
void add_joint_limit_barrier(const MpcConfig& c, const MpcWorkspace& ws, const StateVector& x, double scale,
                             StageT& st) {
  for (int j = 0; j < kNumMpcJoints; ++j) {
    const double qj = x[kXJoints + j];
    double d1, d2;
    relaxed_barrier(qj - ws.joint_min_rad[j], c.joint_limit_barrier_mu, c.joint_limit_barrier_delta_rad, d1, d2);
    st.Q(kXJoints + j, kXJoints + j) += scale * d2;
    st.q[kXJoints + j] += scale * d1;
    relaxed_barrier(ws.joint_max_rad[j] - qj, c.joint_limit_barrier_mu, c.joint_limit_barrier_delta_rad, d1, d2);
    st.Q(kXJoints + j, kXJoints + j) += scale * d2;
    st.q[kXJoints + j] -= scale * d1;
  }
}

// Friction pyramid μ f_z ± f_x ≥ 0, μ f_z ± f_y ≥ 0 of one stance corner, on (R, r).
template <class StageT>
void add_friction_barrier(const MpcConfig& c, double dt, const Vec3& f, int corner, StageT& st) {
  const double mu = c.friction_coefficient;
  for (int axis = 0; axis < 2; ++axis) {
    for (const double sign : {1.0, -1.0}) {
      Vec3 a = Vec3::Zero();
      a[2] = mu;
      a[axis] = -sign;
      double d1, d2;
      relaxed_barrier(a.dot(f), c.friction_barrier_mu, c.friction_barrier_delta_N, d1, d2);
      st.R.template block<3, 3>(kUForces + 3 * corner, kUForces + 3 * corner).noalias() += (dt * d2) * a * a.transpose();
      st.r.template segment<3>(kUForces + 3 * corner) += (dt * d1) * a;
    }
  }
}

// Two unit vectors, in the foot body's axes, normal to the line through the foot's two contact
// corners.
void line_normals(const model::Model& model, const planner::ContactFlags& flags, int first, std::array<Vec3, 2>& out) {
  int ends[2] = {first, first};
  int found = 0;
  for (int c = first; c < first + kPointsPerFoot && found < 2; ++c) {
    if (flags[c]) ends[found++] = c;
  }
  const Vec3 d = (model.frames[ends[1]].position_m - model.frames[ends[0]].position_m).normalized();
  int axis = 0;  // the foot axis least aligned with the line
  d.cwiseAbs().minCoeff(&axis);
  out[0] = d.cross(Vec3::Unit(axis)).normalized();
  out[1] = d.cross(out[0]);
}

// Equality rows of stage k (see mpc.h); returns the max |residual|.
double build_equalities(const model::Model& model, const MpcConfig& cfg, MpcWorkspace& ws,
                        const planner::PlanKnot& knot, int k) {
  auto& st = ws.qp.stages[k];
  const CentroidalPoint& p = ws.point;
  const InputVector& u = ws.u[k];
  int rows = 0;
  double violation = 0.0;
  Vec6 motion;
  MotionRowsX mdx;
  MotionRowsU mdu;
  Eigen::Matrix<double, 3, kNumMpcJoints> jp;
  std::array<Vec3, kNumPoints> corner;
  for (int c = 0; c < kNumPoints; ++c) corner[c] = dynamics::frame_position(model, p.data, c);
  for (int foot = 0; foot < 2; ++foot) {
    const int first = kPointsPerFoot * foot;
    const int body = model.frames[first].body;
    const int n = contacts_of_foot(knot.in_contact, foot);
    for (int c = first; c < first + kPointsPerFoot; ++c) {
      if (knot.in_contact[c]) continue;
      // Force fixed at zero (mpc.h): δf = −f̄. Its R block is diagonal off contact (no friction
      // barrier) and S is zero, so only B couples it: folded into b, then zeroed. This runs
      // after the stage's dynamics and cost; the next build rewrites B's rows, R's diagonal
      // and r.
      for (int i = 0; i < 3; ++i) {
        const int col = kUForces + 3 * c + i;
        const double step = -u[col];
        st.b.noalias() += step * st.B.col(col);
        st.B.col(col).setZero();
        st.R(col, col) = 1.0;
        st.r[col] = -step;
        violation = std::max(violation, std::abs(step));
      }
    }
    if (n > 0) {
      Vec3 centre = Vec3::Zero();
      for (int c = first; c < first + kPointsPerFoot; ++c) {
        if (n >= 3 || knot.in_contact[c]) centre += corner[c];
      }
      centre /= (n >= 3 ? kPointsPerFoot : n);
      point_motion(model, p, body, centre, motion, mdx, mdu);
      const int m = n >= 3 ? 6 : 3;  // foot twist, or the contact centroid's velocity
      st.C.middleRows(rows, m) = mdx.topRows(m);
      st.D.middleRows(rows, m) = mdu.topRows(m);
      st.e.segment(rows, m) = -motion.head(m);
      violation = std::max(violation, motion.head(m).cwiseAbs().maxCoeff());
      if (n >= 3 && cfg.stance_position_gain_1_s > 0.0) {
        // Hold the sole centre on its foothold, not only at rest: v = k (c_ref − c) (base axes).
        Vec3 ref = Vec3::Zero();
        for (int c = first; c < first + kPointsPerFoot; ++c) ref += knot.point_position_m.segment<3>(3 * c);
        ref /= kPointsPerFoot;
        const Vec3 world = ws.x[k].segment<3>(kXBasePosition) + p.rotation * centre;
        st.e.segment<3>(rows) += cfg.stance_position_gain_1_s * (p.rotation.transpose() * (ref - world));
      }
      rows += m;
      if (n == 2) {
        // Two corners (toes or heels): the foot may only roll about the line through them, so
        // its angular velocity across that line is zero too (2 rows, directions fixed in the foot).
        std::array<Vec3, 2> across;
        line_normals(model, knot.in_contact, first, across);
        const Mat3& foot_rotation = p.data.rotation[body];  // base axes (base at identity)
        const Vec3 omega = motion.tail<3>();
        for (const Vec3& e_foot : across) {
          const Vec3 e = foot_rotation * e_foot;
          st.C.row(rows).noalias() = e.transpose() * mdx.bottomRows<3>();
          for (int a = body; a > 0; a = model.bodies[a].parent) {  // e turns with the foot
            if (a - 1 < kNumMpcJoints) st.C(rows, kXJoints + a - 1) += omega.dot(p.data.motion_subspace[a].tail<3>().cross(e));
          }
          st.D.row(rows).noalias() = e.transpose() * mdu.bottomRows<3>();
          st.e[rows] = -omega.dot(e);
          violation = std::max(violation, std::abs(omega.dot(e)));
          ++rows;
        }
      }
    } else {
      // Swing: v_z + k z − (v_z,ref + k z_ref) = 0 on 3 corners, world z.
      const double gain = cfg.swing_position_gain_1_s;
      const Vec3 base = ws.x[k].segment<3>(kXBasePosition);
      const Eigen::RowVector3d rz = p.rotation.row(2);
      for (int c = first; c < first + 3; ++c) {
        point_motion(model, p, body, corner[c], motion, mdx, mdu);
        point_position_jacobian(model, p, body, corner[c], jp);
        const Vec3 vp = motion.head<3>();
        const double value = rz.dot(vp) + gain * (base.z() + rz.dot(corner[c])) -
                             knot.point_velocity_m_s[3 * c + 2] - gain * knot.point_position_m[3 * c + 2];
        st.C.row(rows).noalias() = rz * mdx.topRows<3>();
        st.C(rows, kXBasePosition + 2) += gain;
        for (int e = 0; e < 3; ++e) {
          st.C(rows, kXEuler + e) += p.rotation_derivative[e].row(2).dot(vp + gain * corner[c]);
        }
        st.C.block<1, kNumMpcJoints>(rows, kXJoints).noalias() += gain * (rz * jp);
        st.D.row(rows).noalias() = rz * mdu.topRows<3>();
        st.e[rows] = -value;
        violation = std::max(violation, std::abs(value));
        ++rows;
      }
    }
  }
  // The rows past num_eq stay zero (the solver's residual check multiplies full matrices):
  // mpc_init zeroed them all, so only the rows the previous build used are cleared.
  const int stale = std::max(st.num_eq, rows) - rows;
  if (stale > 0) {
    st.C.middleRows(rows, stale).setZero();
    st.D.middleRows(rows, stale).setZero();
    st.e.segment(rows, stale).setZero();
  }
  st.num_eq = rows;
  return violation;
}

void build_stage_cost(const MpcConfig& cfg, MpcWorkspace& ws, const planner::PlanKnot& knot, int k, bool terminal) {
  auto& st = ws.qp.stages[k];
  const double scale = terminal ? cfg.dt_s * cfg.terminal_weight_scale : ws.stage_dt_s[k];
  // Q and R are diagonal but for the swing x-y cost's block of Q and the friction barriers'
  // 3×3 force blocks of R; only those are cleared (mpc_init zeroed the rest).
  if (ws.swing_block_written[k]) {
    st.Q.template bottomRightCorner<kNx - kXBasePosition, kNx - kXBasePosition>().setZero();
    ws.swing_block_written[k] = false;
  }
  st.Q.diagonal() = scale * ws.weight_state;
  st.q = (scale * ws.weight_state).cwiseProduct(state_error(ws.x[k], ws.x_ref[k]));
  add_joint_limit_barrier(cfg, ws, ws.x[k], scale, st);  // same scale: same equilibrium as the stages
  if (terminal) return;
  if (cfg.stance_leg_torque_share > 0.0) {
    st.R.template block<3 * kNumPoints, 3 * kNumPoints>(kUForces, kUForces).setZero();
  } else {
    for (int c = 0; c < kNumPoints; ++c) st.R.template block<3, 3>(kUForces + 3 * c, kUForces + 3 * c).setZero();
  }
  st.R.diagonal() = scale * ws.weight_input;
  st.r = (scale * ws.weight_input).cwiseProduct(ws.u[k] - ws.u_ref[k]);
  for (int c = 0; c < kNumPoints; ++c) {
    if (knot.in_contact[c]) add_friction_barrier(cfg, scale, ws.u[k].segment<3>(kUForces + 3 * c), c, st);
  }
}

constexpr int kSwingColumns = 5 + kLegChain;  // base x-y, Euler, the leg

// Leju's soft swing x-y tracking: ½ w ‖p_xy(x) − p_xy,ref‖² per corner not in contact, Gauss-Newton
// Hessian. Soft, so the optimizer may still move the touchdown spot.
void add_swing_xy_cost(const model::Model& model, const MpcConfig& cfg, MpcWorkspace& ws,
                       const planner::PlanKnot& knot, int k) {
  if (cfg.weight_swing_xy <= 0.0) return;
  auto& st = ws.qp.stages[k];
  const CentroidalPoint& p = ws.point;
  const Vec3 base = ws.x[k].segment<3>(kXBasePosition);
  Eigen::Matrix<double, 3, kNumMpcJoints> jp;
  Eigen::Matrix<double, 2, kNx> j;
  for (int c = 0; c < kNumPoints; ++c) {
    if (knot.in_contact[c]) continue;
    const int body = model.frames[c].body;
    const Vec3 point = dynamics::frame_position(model, p.data, c);
    point_position_jacobian(model, p, body, point, jp);
    j.setZero();
    j.block<2, 2>(0, kXBasePosition).setIdentity();
    for (int e = 0; e < 3; ++e) j.col(kXEuler + e) = (p.rotation_derivative[e] * point).head<2>();
    const int lo = leg_chain_first_column(model, body);
    if (lo >= 0) {
      j.block<2, kLegChain>(0, kXJoints + lo).noalias() = p.rotation.topRows<2>() * jp.middleCols<kLegChain>(lo);
    } else {
      j.block<2, kNumMpcJoints>(0, kXJoints).noalias() = p.rotation.topRows<2>() * jp;
    }
    const Eigen::Vector2d error = (base + p.rotation * point).head<2>() - knot.point_position_m.segment<2>(3 * c);
    const double w = ws.stage_dt_s[k] * cfg.weight_swing_xy;
    // j is zero in the momentum columns: only Q's base-and-joint block changes.
    if (lo >= 0) {
      // and zero but in base x-y, the Euler angles and the leg's joints: the Gauss-Newton
      // product on those 11 columns only, each entry as the dense product computes it
      // (w · (j₀ₐ j₀ᵦ + j₁ₐ j₁ᵦ) added with fused multiply-adds).
      std::array<int, kSwingColumns> cols{kXBasePosition, kXBasePosition + 1, kXEuler, kXEuler + 1, kXEuler + 2};
      for (int i = 0; i < kLegChain; ++i) cols[5 + i] = kXJoints + lo + i;
      for (int bi = 0; bi < kSwingColumns; ++bi) {
        const int b = cols[bi];
        for (int ai = 0; ai < kSwingColumns; ++ai) {
          const int a = cols[ai];
          const double acc = std::fma(j(1, a), j(1, b), j(0, a) * j(0, b));
          st.Q(a, b) = std::fma(acc, w, st.Q(a, b));
        }
      }
    } else {
      st.Q.template bottomRightCorner<kNx - kXBasePosition, kNx - kXBasePosition>().noalias() +=
          w * j.template rightCols<kNx - kXBasePosition>().transpose() * j.template rightCols<kNx - kXBasePosition>();
    }
    ws.swing_block_written[k] = true;
    st.q.noalias() += w * j.transpose() * error;
  }
}

// Leg joint torques of the stance feet (MpcConfig::stance_leg_torque_share): the moment
// Σ (p_c − o_j) × f_c of the foot's corner forces about joint j's axis is g·f with
// g_c = axis × (p_c − o_j), world axes; a relaxed barrier on both sides of the limit,
// Gauss-Newton on the forces only (the leg geometry of the iterate). With the ankle motors
// known (MpcWorkspace::ankle_motor_limits) the ankle pair's two motor torques, the map of
// (pitch, roll), get the same barrier against the motors' limits. Writes R's off-diagonal
// corner blocks: build_stage_cost clears the whole force block when this is on.
void add_stance_leg_torque_barrier(const model::Model& model, const MpcConfig& cfg, MpcWorkspace& ws,
                              const planner::PlanKnot& knot, int k) {
  if (cfg.stance_leg_torque_share <= 0.0) return;
  auto& st = ws.qp.stages[k];
  const CentroidalPoint& p = ws.point;
  constexpr int kFootForces = 3 * kPointsPerFoot;
  using FootRow = Eigen::Matrix<double, kFootForces, 1>;
  const hal::AnkleMotorLimits& motors = ws.ankle_motor_limits;
  const double dt = ws.stage_dt_s[k];
  for (int foot = 0; foot < 2; ++foot) {
    const int first = foot * kPointsPerFoot;
    const int col = kUForces + 3 * first;
    bool any = false;
    for (int c = first; c < first + kPointsPerFoot; ++c) any = any || knot.in_contact[c];
    if (!any) continue;
    auto barrier = [&](const FootRow& g, double tau, double limit) {
      for (const double sign : {1.0, -1.0}) {
        double d1, d2;
        relaxed_barrier(limit - sign * tau, cfg.leg_torque_barrier_mu, cfg.leg_torque_barrier_delta_Nm, d1, d2);
        st.R.template block<kFootForces, kFootForces>(col, col).noalias() += (dt * d2) * g * g.transpose();
        st.r.template segment<kFootForces>(col) -= (dt * d1 * sign) * g;
      }
    };
    std::array<Vec3, kPointsPerFoot> corner;  // base axes, once per foot (not per joint)
    for (int c = first; c < first + kPointsPerFoot; ++c) corner[c - first] = dynamics::frame_position(model, p.data, c);
    std::array<FootRow, 2> ankle_g;  // pitch, roll
    std::array<double, 2> ankle_tau{};
    for (int joint = 0; joint < model::kLegJoints; ++joint) {  // hip roll … ankle roll
      const int j = foot * model::kLegJoints + joint;
      const int body = j + 1;
      const Vec3 axis = p.rotation * (p.data.rotation[body] * model.bodies[body].axis);
      const Vec3 origin = p.data.position_m[body];
      FootRow g = FootRow::Zero();
      double tau = 0.0;
      for (int c = first; c < first + kPointsPerFoot; ++c) {
        if (!knot.in_contact[c]) continue;
        const Vec3 r = p.rotation * (corner[c - first] - origin);
        const Vec3 gc = axis.cross(r);
        g.segment<3>(3 * (c - first)) = gc;
        tau += gc.dot(ws.u[k].segment<3>(kUForces + 3 * c));
      }
      barrier(g, tau, cfg.stance_leg_torque_share * model.limits.torque_Nm[j]);
      if (joint >= model::kAnklePitchInLeg) {
        ankle_g[joint - model::kAnklePitchInLeg] = g;
        ankle_tau[joint - model::kAnklePitchInLeg] = tau;
      }
    }
    if (!motors.active) continue;
    // The joint torque holding the moment is its negative; the bounds are symmetric.
    for (int m = 0; m < 2; ++m) {
      const double a = motors.joint_to_motor[foot](m, 0), b = motors.joint_to_motor[foot](m, 1);
      barrier(a * ankle_g[0] + b * ankle_g[1], a * ankle_tau[0] + b * ankle_tau[1],
              cfg.stance_leg_torque_share * motors.limit_Nm[foot](m));
    }
  }
}

double tracking_cost(const MpcConfig& cfg, const MpcWorkspace& ws) {
  double cost = 0.0;
  const int T = ws.horizon;
  for (int k = 0; k <= T; ++k) {
    const StateVector e = state_error(ws.x[k], ws.x_ref[k]);
    const double scale = k == T ? cfg.dt_s * cfg.terminal_weight_scale : ws.stage_dt_s[k];
    cost += 0.5 * scale * e.dot(ws.weight_state.cwiseProduct(e));
    if (k < T) {
      const InputVector du = ws.u[k] - ws.u_ref[k];
      cost += 0.5 * scale * du.dot(ws.weight_input.cwiseProduct(du));
    }
  }
  return cost;
}

int window_intervals(const MpcConfig& c) { return static_cast<int>(std::lround(c.horizon_s / c.dt_s)); }

// Stages at dt_s before the coarse tail (all of them with a uniform grid).
int fine_stages(const MpcConfig& c) {
  const int n = window_intervals(c);
  if (c.tail_stride <= 1) return n;
  return std::min(n, static_cast<int>(std::lround(c.fine_horizon_s / c.dt_s)));
}

// The window knot stage k starts at (k = T: the window's last knot).
int stage_knot_of(const MpcConfig& c, int k) {
  const int f = fine_stages(c);
  if (k <= f) return k;
  return std::min(f + (k - f) * c.tail_stride, window_intervals(c));
}

// The grid of one build: the fine stages, then tail stages of tail_stride knots that end early
// at a knot where a contact flag changes, so every knot of a stage has its first knot's
// contacts (a lift-off or touchdown is never moved to a stage boundary). Returns T.
int contact_aligned_grid(const MpcConfig& c, const planner::PlanWindow& reference,
                         std::array<int, kMaxStages + 1>& knots) {
  const int n = window_intervals(c), f = fine_stages(c);
  int k = 0;
  for (; k <= f; ++k) knots[k] = k;
  for (int j = f; j < n;) {
    int end = std::min(j + c.tail_stride, n);
    for (int i = j + 1; i < end; ++i) {
      if (reference.knots[i].in_contact != reference.knots[j].in_contact) {
        end = i;
        break;
      }
    }
    knots[k++] = end;
    j = end;
  }
  return k - 1;
}

// stage_dt_s from stage_knot over the workspace's horizon.
void set_stage_lengths(const MpcConfig& c, MpcWorkspace& ws) {
  for (int k = 0; k < ws.horizon; ++k) ws.stage_dt_s[k] = (ws.stage_knot[k + 1] - ws.stage_knot[k]) * c.dt_s;
}

}  // namespace

int mpc_window_knots(const MpcConfig& c) { return window_intervals(c) + 1; }

int mpc_num_stages(const MpcConfig& c) {
  const int n = window_intervals(c), f = fine_stages(c);
  if (f >= n) return n;
  return f + (n - f + c.tail_stride - 1) / c.tail_stride;
}

const char* mpc_validate_config(const MpcConfig& c) {
  if (!(c.dt_s >= 0.005 && c.dt_s <= 0.05)) return "dt_s must be in [0.005, 0.05] s";
  if (c.plan_output && !(c.horizon_s >= 0.6 - 1e-9 && c.horizon_s <= 1.4 + 1e-9)) {
    return "horizon_s must be in [0.6, 1.4] s";
  }
  if (!c.plan_output && !(c.horizon_s >= 0.2 - 1e-9 && c.horizon_s <= 1.4 + 1e-9)) {
    return "horizon_s (an offline window) must be in [0.2, 1.4] s";
  }
  const int n = window_intervals(c);
  if (n > kMaxStages || n + 1 > planner::kMaxWindowKnots) return "horizon_s / dt_s exceeds kMaxStages (70)";
  if (c.plan_output && n < kMpcPlanKnots + 1) return "horizon shorter than the plan handed to the WBC";
  if (n < 2) return "horizon shorter than two stages";
  if (!(c.tail_stride >= 1 && c.tail_stride <= 4)) return "tail_stride must be in [1, 4]";
  if (c.tail_stride > 1) {
    if (!(std::isfinite(c.fine_horizon_s) && c.fine_horizon_s >= 2.0 * c.dt_s - 1e-9)) {
      return "fine_horizon_s must be at least two stages";
    }
    if (c.plan_output && fine_stages(c) < kMpcPlanKnots) {
      return "fine_horizon_s shorter than the plan handed to the WBC (0.2 s)";
    }
  }
  // The swing and stance rows v = k (p_ref − p), Euler-integrated over a stage, close the loop
  // p_err ← (1 − k·dt_k) p_err: stable for k·dt_k < 2 on the longest stage.
  const double longest_s = c.tail_stride * c.dt_s;
  if (!(c.swing_position_gain_1_s * longest_s < 2.0) || !(c.stance_position_gain_1_s * longest_s < 2.0)) {
    return "swing/stance position gain × the longest stage must be < 2 (a shorter tail stride)";
  }
  if (!(c.friction_coefficient > 0.0 && c.friction_coefficient <= 2.0)) return "friction_coefficient must be in (0, 2]";
  auto bad = [](double w) { return !(std::isfinite(w) && w >= 0.0); };
  for (int i = 0; i < 3; ++i) {
    if (bad(c.weight_com_velocity[i]) || bad(c.weight_angular_momentum_normalized[i]) ||
        bad(c.weight_base_position[i]) || bad(c.weight_base_euler[i])) {
      return "state weights must be finite and >= 0";
    }
  }
  for (double w : c.weight_leg_joint) {
    if (bad(w)) return "state weights must be finite and >= 0";
  }
  if (bad(c.weight_arm_joint) || bad(c.terminal_weight_scale)) return "state weights must be finite and >= 0";
  if (!(c.weight_force > 0.0 && c.weight_leg_joint_velocity > 0.0 && c.weight_arm_joint_velocity > 0.0) ||
      !std::isfinite(c.weight_force + c.weight_leg_joint_velocity + c.weight_arm_joint_velocity)) {
    return "input weights must be finite and > 0 (R positive definite)";
  }
  if (!(c.friction_barrier_mu > 0.0 && c.friction_barrier_delta_N > 0.0 && c.joint_limit_barrier_mu > 0.0 &&
        c.joint_limit_barrier_delta_rad > 0.0) ||
      !std::isfinite(c.friction_barrier_mu + c.friction_barrier_delta_N + c.joint_limit_barrier_mu +
                     c.joint_limit_barrier_delta_rad)) {
    return "barrier mu and delta must be finite and > 0";
  }
  if (bad(c.weight_swing_xy)) return "weight_swing_xy must be finite and >= 0";
  if (!(c.swing_position_gain_1_s >= 0.0 && std::isfinite(c.swing_position_gain_1_s))) {
    return "swing_position_gain_1_s must be finite and >= 0";
  }
  if (!(c.stance_leg_torque_share >= 0.0 && c.stance_leg_torque_share <= 1.0) || !(c.leg_torque_barrier_mu > 0.0) ||
      !(c.leg_torque_barrier_delta_Nm > 0.0) || !std::isfinite(c.leg_torque_barrier_mu + c.leg_torque_barrier_delta_Nm)) {
    return "stance_leg_torque_share must be in [0, 1], its barrier mu and delta finite and > 0";
  }
  if (!(c.stance_position_gain_1_s >= 0.0 && c.stance_position_gain_1_s <= 100.0)) {
    return "stance_position_gain_1_s must be in [0, 100]";
  }
  return nullptr;
}

const char* to_string(MpcStatus s) {
  switch (s) {
    case MpcStatus::kOk: return "ok";
    case MpcStatus::kNotInitialized: return "not_initialized";
    case MpcStatus::kBadInput: return "bad_input";
    case MpcStatus::kBadReference: return "bad_reference";
    case MpcStatus::kQpFailed: return "qp_failed";
  }
  return "unknown";
}

void mpc_init(const model::Model& model, const MpcConfig& config, MpcWorkspace& ws) {
  ws.initialized = false;
  ws.warm = false;
  ws.reference_cached = 0;
  if (mpc_validate_config(config) != nullptr) return;
  ws.horizon = mpc_num_stages(config);
  for (int k = 0; k <= ws.horizon; ++k) ws.stage_knot[k] = stage_knot_of(config, k);
  set_stage_lengths(config, ws);
  ws.previous_horizon = ws.horizon;
  ws.previous_stage_knot = ws.stage_knot;
  fill_weights(model, config, ws);
  ws.joint_min_rad = model.limits.position_min_rad.head<kNumMpcJoints>();
  ws.joint_max_rad = model.limits.position_max_rad.head<kNumMpcJoints>();
  for (auto& st : ws.qp.stages) {  // what the builds never write stays zero (build_stage_cost, build_equalities)
    st.A.setIdentity();              // ... or the identity (A's rows of ṙ and the joints)
    st.B.setZero();
    st.Q.setZero();
    st.R.setZero();
    st.q.setZero();                  // (a stage past this config's horizon keeps no stale gradient)
    st.r.setZero();
    st.b.setZero();
    st.S.setZero();                  // no cross terms: never written, and the Riccati skips it
    st.s_zero = true;
    st.r_dense = 3 * kNumPoints;     // R: the force block and the joint velocities' diagonal
    st.C.setZero();
    st.D.setZero();
    st.e.setZero();
    st.num_eq = 0;
    st.num_ineq = 0;
  }
  ws.swing_block_written.fill(false);
  // Where A and B may be nonzero (the build writes nothing else; 4-row groups, ocp_qp.h): A is
  // the identity but in rows [3, 12), B's force columns reach the momentum rows (6), its
  // joint-velocity columns rows [0, 12) and their joint's row.
  constexpr std::uint16_t kTopRows = 0b111;  // rows [0, 12)
  for (int j = 0; j < kNx; ++j) ws.qp.a_groups[j] = kTopRows | static_cast<std::uint16_t>(1u << (j / 4));
  for (int j = 0; j < 3 * kNumPoints; ++j) ws.qp.b_groups[kUForces + j] = 0b11;  // rows [0, 8)
  for (int j = 0; j < kNumMpcJoints; ++j) {
    ws.qp.b_groups[kUJointVelocity + j] = kTopRows | static_cast<std::uint16_t>(1u << ((kXJoints + j) / 4));
  }
  ws.qp.ab_groups_declared = true;
  ws.qp.horizon = ws.horizon;
  ws.qp.x_initial.setZero();
  ws.qp_settings = qp::OcpSettings{};
  ws.qp_settings.lq_residual = false;  // no one reads it; the solver still checks the step finite
  ws.qp_settings.lq_costate = false;   // nor the costates (the step is x and u)
  ws.initialized = true;
}

void mpc_reset(MpcWorkspace& ws) {
  ws.warm = false;
  ws.reference_cached = 0;
}

MpcStatus mpc_build_qp_rt(const model::Model& model, const MpcConfig& cfg, MpcWorkspace& ws,
                          const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                          const planner::PlanWindow& reference) {
  if (!ws.initialized) return MpcStatus::kNotInitialized;
  if (!q.allFinite() || !v.allFinite()) return MpcStatus::kBadInput;
  StateVector x0;
  state_from_configuration(model, ws.world_data, q, v, x0);
  return mpc_build_qp_from_state_rt(model, cfg, ws, x0, reference);
}

MpcStatus mpc_build_qp_from_state_rt(const model::Model& model, const MpcConfig& cfg, MpcWorkspace& ws,
                                     const StateVector& x_initial, const planner::PlanWindow& reference) {
  if (!ws.initialized) return MpcStatus::kNotInitialized;
  if (!x_initial.allFinite()) return MpcStatus::kBadInput;
  const int W = mpc_window_knots(cfg);  // window knots the stages read
  if (reference.count < W || reference.count > planner::kMaxWindowKnots ||
      !(std::abs(reference.dt_s - cfg.dt_s) <= kDtTolerance_s)) {
    return MpcStatus::kBadReference;
  }
  for (int k = 0; k < W; ++k) {
    if (!knot_finite(reference.knots[k])) return MpcStatus::kBadReference;
  }
  // This window's grid (fixed with a uniform one); the previous one stays for the warm start.
  ws.previous_horizon = ws.horizon;
  ws.previous_stage_knot = ws.stage_knot;
  if (cfg.tail_stride > 1) {
    ws.horizon = contact_aligned_grid(cfg, reference, ws.stage_knot);
    set_stage_lengths(cfg, ws);
  }
  const int T = ws.horizon;

  // Reference trajectory in MPC coordinates, per window knot. Knots of the previous call are
  // taken from the cache: slot j + s held the knot now at j when the window moved s ≥ 0 knots
  // (read before it is overwritten, j ascending).
  const double mg = model.total_mass_kg * model::kGravity_m_s2;
  Vec6 weight = Vec6::Zero();
  weight[2] = mg;
  const hal::TimeNs dt_ns = static_cast<hal::TimeNs>(std::llround(cfg.dt_s * 1e9));
  int s = -1;
  if (ws.reference_cached > 0 && dt_ns > 0) {
    const hal::TimeNs moved = reference.knots[0].stamp_ns - ws.reference_knot[0].stamp_ns;
    if (moved >= 0 && moved % dt_ns == 0 && moved / dt_ns < ws.reference_cached) s = static_cast<int>(moved / dt_ns);
  }
  const int cached = ws.reference_cached;
  for (int k = 0; k < W; ++k) {
    const planner::PlanKnot& knot = reference.knots[k];
    const int j = s >= 0 ? k + s : -1;
    if (j >= 0 && j < cached && same_reference_knot(knot, ws.reference_knot[j])) {
      if (j != k) {
        ws.reference_knot[k] = ws.reference_knot[j];
        ws.reference_state[k] = ws.reference_state[j];
        ws.reference_input[k] = ws.reference_input[j];
        ws.reference_wrench[k] = ws.reference_wrench[j];
      }
    } else {
      ws.reference_knot[k] = knot;
      state_from_configuration(model, ws.world_data, knot.q, knot.v, ws.reference_state[k]);
      reference_forces(knot, weight, ws.reference_input[k]);
      ws.reference_input[k].segment<kNumMpcJoints>(kUJointVelocity) = knot.v.segment<kNumMpcJoints>(6);
      ws.reference_wrench[k].setConstant(std::numeric_limits<double>::quiet_NaN());  // never equal: solved below
    }
  }
  ws.reference_cached = W;
  if (cfg.reference_forces_from_motion) {
    // The wrench the reference itself needs: m (r̈ + g) and ḣ, forward differences of its
    // states (the last knot takes the difference before it), carried by forces within the
    // pyramids. A knot whose wrench is the one its cached forces were solved for keeps them
    // (within a window's SQP iterations, all of them).
    for (int k = 0; k <= T; ++k) {
      const int j = ws.stage_knot[k];
      const int a = std::min(j, W - 2), b = a + 1;
      Vec6 w = weight;
      w.head<3>() += model.total_mass_kg / cfg.dt_s *
                     (ws.reference_state[b].segment<3>(kXComVelocity) - ws.reference_state[a].segment<3>(kXComVelocity));
      w.tail<3>() = (ws.reference_state[b].segment<3>(kXMomentum) - ws.reference_state[a].segment<3>(kXMomentum)) / cfg.dt_s;
      if (w == ws.reference_wrench[j]) continue;
      if (!reference_forces_in_cones(reference.knots[j], w, cfg.friction_coefficient, ws, ws.reference_input[j])) {
        reference_forces(reference.knots[j], w, ws.reference_input[j]);
        ++ws.reference_wrench_failures;
      }
      ws.reference_wrench[j] = w;
    }
  }
  // The stages' reference (yaw kept continuous along the horizon).
  for (int k = 0; k <= T; ++k) {
    const int j = ws.stage_knot[k];
    ws.x_ref[k] = ws.reference_state[j];
    if (k > 0) {
      ws.x_ref[k][kXEuler] = ws.x_ref[k - 1][kXEuler] + wrap_angle(ws.x_ref[k][kXEuler] - ws.x_ref[k - 1][kXEuler]);
    }
    ws.u_ref[k] = ws.reference_input[j];
    ws.head_rad[k] = reference.knots[j].q.segment<2>(7 + kNumMpcJoints);
  }

  StateVector x0 = x_initial;
  x0[kXEuler] = ws.x_ref[0][kXEuler] + wrap_angle(x0[kXEuler] - ws.x_ref[0][kXEuler]);

  // Warm start: the previous solution shifted by the knots elapsed since its knot 0. Stage k
  // now starts at old window time τ = stage_knot[k] + shift: a stage of the old grid starting
  // there gives its state and input; inside an old stage, the state is interpolated along it
  // and the input is that stage's (held over the stage); past the old horizon, the new tail
  // repeats the last state and its inputs come from the reference, whose forces respect the
  // new stages' contacts (a repeated input would put force on a foot that has just entered
  // the horizon as lifted). With a uniform grid: the solution shifted by `shift` stages.
  bool warm = ws.warm;
  int shift = 0;
  if (warm) {
    const double elapsed = static_cast<double>(reference.knots[0].stamp_ns - ws.last_stamp_ns) * 1e-9;
    const double stages = elapsed / cfg.dt_s;
    warm = stages > -0.5 && stages < W - 1;
    shift = warm ? static_cast<int>(std::lround(stages)) : 0;
  }
  if (warm) {
    // On an unchanged grid, ascending k reads old stages j ≥ k only, so the shift runs in
    // place; a grid that moved (a contact switch entered or moved in the tail) reads a copy.
    const int T_old = ws.previous_horizon;
    const std::array<int, kMaxStages + 1>& old_knot = ws.previous_stage_knot;
    bool moved = T_old != T;
    for (int k = 0; k <= T && !moved; ++k) moved = old_knot[k] != ws.stage_knot[k];
    if (moved) {
      for (int k = 0; k <= T_old; ++k) {
        ws.x_previous[k] = ws.x[k];
        ws.u_previous[k] = ws.u[k];
      }
    }
    const std::array<StateVector, kMaxStages + 1>& old_x = moved ? ws.x_previous : ws.x;
    const std::array<InputVector, kMaxStages + 1>& old_u = moved ? ws.u_previous : ws.u;
    int j = 0;
    for (int k = 0; k <= T; ++k) {
      const int tau = ws.stage_knot[k] + shift;
      while (j < T_old && old_knot[j + 1] <= tau) ++j;
      if (j == T_old) {
        ws.x[k] = old_x[T_old];
        ws.u[k] = ws.u_ref[k];
      } else if (old_knot[j] == tau) {
        ws.x[k] = old_x[j];
        ws.u[k] = old_u[j];
      } else {
        const double a = static_cast<double>(tau - old_knot[j]) / (old_knot[j + 1] - old_knot[j]);
        const StateVector xk = old_x[j] + a * (old_x[j + 1] - old_x[j]);
        ws.x[k] = xk;
        ws.u[k] = old_u[j];
      }
    }
    // Keep the warm yaw on the reference's branch (the reference's yaw may have wrapped).
    const double offset = ws.x[0][kXEuler] - x0[kXEuler];
    const double turns = std::round(offset / kTwoPi);
    if (turns != 0.0) {
      for (int k = 0; k <= T; ++k) ws.x[k][kXEuler] -= turns * kTwoPi;
    }
  } else {
    for (int k = 0; k <= T; ++k) {
      ws.x[k] = ws.x_ref[k];
      ws.u[k] = ws.u_ref[k];
    }
  }
  ws.x[0] = x0;  // linearize stage 0 at the measurement: δx₀ = 0
  ws.last_stamp_ns = reference.knots[0].stamp_ns;

  double violation = 0.0;
  for (int k = 0; k < T; ++k) {
    const planner::PlanKnot& knot = reference.knots[ws.stage_knot[k]];
    const double dt = ws.stage_dt_s[k];
    auto& st = ws.qp.stages[k];
    centroidal_evaluate(model, ws.x[k], ws.u[k], ws.head_rad[k], ws.point);
    const CentroidalPoint& p = ws.point;
    // A = I + dt·fx, B = dt·fu. fx is zero but in rows [3, 12) (ḣ, base position, Euler rates)
    // and fu in rows [0, 12) and the joint-velocity identity: the rest of A is the identity and
    // the rest of B zero, as mpc_init wrote them (nothing else writes A or B), and only the
    // varying rows and B's diagonal dt are written (the same values as the whole products).
    st.A.template middleRows<kXJoints - kXMomentum>(kXMomentum).noalias() =
        dt * p.fx.template middleRows<kXJoints - kXMomentum>(kXMomentum);
    st.A.diagonal().template segment<kXJoints - kXMomentum>(kXMomentum).array() += 1.0;
    st.B.template topRows<kXJoints>().noalias() = dt * p.fu.template topRows<kXJoints>();
    st.B.template block<kNumMpcJoints, kNumMpcJoints>(kXJoints, kUJointVelocity).diagonal() =
        dt * p.fu.template block<kNumMpcJoints, kNumMpcJoints>(kXJoints, kUJointVelocity).diagonal();
    st.b = ws.x[k] + dt * p.f - ws.x[k + 1];
    violation = std::max(violation, st.b.cwiseAbs().maxCoeff());
    if (k <= kMpcPlanKnots) {
      ws.twist[k] = p.base_twist;
      ws.twist_dx[k] = p.base_twist_dx;
      ws.twist_du[k] = p.base_twist_du;
    }
    build_stage_cost(cfg, ws, knot, k, false);
    add_swing_xy_cost(model, cfg, ws, knot, k);
    add_stance_leg_torque_barrier(model, cfg, ws, knot, k);
    violation = std::max(violation, build_equalities(model, cfg, ws, knot, k));
  }
  build_stage_cost(cfg, ws, reference.knots[ws.stage_knot[T]], T, true);
  {
    auto& terminal = ws.qp.stages[T];  // no equalities at the terminal stage (ocp_qp.h)
    terminal.C.topRows(terminal.num_eq).setZero();
    terminal.D.topRows(terminal.num_eq).setZero();
    terminal.e.head(terminal.num_eq).setZero();
    terminal.num_eq = 0;
    if (T != ws.previous_horizon) {  // a stage of the last build may end the horizon now: no input cost
      terminal.R.setZero();
      terminal.r.setZero();
    }
  }
  ws.qp.horizon = T;
  ws.qp.x_initial.setZero();
  ws.constraint_violation = violation;
  if (!std::isfinite(violation)) return MpcStatus::kBadInput;
  return MpcStatus::kOk;
}

MpcStatus mpc_solve_qp_rt(MpcWorkspace& ws) {
  const int T = ws.horizon;
  ws.qp_status = qp::solve_ocp_qp(ws.qp, ws.qp_settings, ws.qp_workspace, ws.solution);
  if (ws.qp_status != qp::QpStatus::kSolved) {  // kSolved: x and u finite (ocp_solver.h)
    ws.warm = false;
    return MpcStatus::kQpFailed;
  }
  for (int k = 0; k <= T; ++k) {
    ws.x[k] += ws.solution.x[k];
    if (k < T) ws.u[k] += ws.solution.u[k];
  }
  ws.u[T] = ws.u[T - 1];
  ws.warm = true;
  return MpcStatus::kOk;
}

void mpc_write_plan_rt(const model::Model& model, const MpcConfig& cfg, MpcWorkspace& ws,
                       const planner::PlanWindow& reference, MpcStatus status, MpcPlan& out) {
  out.stamp_ns = reference.count > 0 ? reference.knots[0].stamp_ns : 0;
  out.dt_s = cfg.dt_s;
  out.status = status;
  out.count = 0;
  out.qp_iterations = 0;
  out.constraint_violation = ws.constraint_violation;
  if (status != MpcStatus::kOk) return;
  out.qp_iterations = 1;
  out.cost = tracking_cost(cfg, ws);

  const double m = model.total_mass_kg;
  // Knots 0 … kMpcPlanKnots (the last only for the finite-difference accelerations).
  for (int i = 0; i <= kMpcPlanKnots; ++i) {
    wbc::WbcReference& r = i < kMpcPlanKnots ? out.knots[i] : ws.scratch_reference;
    const planner::PlanKnot& knot = reference.knots[i];
    const StateVector& x = ws.x[i];
    const InputVector& u = ws.u[i];
    // Base twist at the updated point, to first order from the linearization.
    Vec6 twist = ws.twist[i];
    twist.noalias() += ws.twist_dx[i] * ws.solution.x[i];
    twist.noalias() += ws.twist_du[i] * ws.solution.u[i];
    const dynamics::ConfigVector qc = configuration_from_state(x, ws.head_rad[i]);
    dynamics::VelocityVector vc;
    vc.head<6>() = twist;
    vc.segment<kNumMpcJoints>(6) = u.segment<kNumMpcJoints>(kUJointVelocity);
    vc.tail<2>() = knot.v.tail<2>();
    planner::plan_knot_from_state(model, ws.world_data, qc, vc, knot.in_contact, knot.stamp_ns, ws.scratch_knot);

    r.stamp_ns = reference.knots[0].stamp_ns + static_cast<hal::TimeNs>(std::llround(i * cfg.dt_s * 1e9));
    r.base_euler_zyx_rad = x.segment<3>(kXEuler);
    r.base_angular_velocity_rad_s = ws.world_data.rotation[0] * twist.tail<3>();
    r.com_position_m = ws.scratch_knot.com_position_m;
    r.com_velocity_m_s = x.segment<3>(kXComVelocity);
    Vec3 force_sum = Vec3::Zero(), moment = Vec3::Zero();
    for (int c = 0; c < kNumPoints; ++c) {
      const Vec3 f = u.segment<3>(kUForces + 3 * c);
      force_sum += f;
      moment += (ws.scratch_knot.point_position_m.segment<3>(3 * c) - r.com_position_m).cross(f);
    }
    r.momentum_rate.head<3>() = force_sum - m * model::kGravity_m_s2 * Vec3::UnitZ();
    r.momentum_rate.tail<3>() = moment;
    r.joint_position_rad = qc.tail<model::kNumJoints>();
    r.joint_velocity_rad_s = vc.tail<model::kNumJoints>();
    r.point_position_m = ws.scratch_knot.point_position_m;
    r.point_velocity_m_s = ws.scratch_knot.point_velocity_m_s;
    r.contact_force_N = u.segment<3 * kNumPoints>(kUForces);
    r.in_contact = knot.in_contact;
  }
  for (int i = 0; i < kMpcPlanKnots; ++i) {
    wbc::WbcReference& r = out.knots[i];
    const wbc::WbcReference& next = i + 1 < kMpcPlanKnots ? out.knots[i + 1] : ws.scratch_reference;
    r.base_angular_acceleration_rad_s2 = (next.base_angular_velocity_rad_s - r.base_angular_velocity_rad_s) / cfg.dt_s;
    r.joint_acceleration_rad_s2 = (next.joint_velocity_rad_s - r.joint_velocity_rad_s) / cfg.dt_s;
    r.point_acceleration_m_s2 = (next.point_velocity_m_s - r.point_velocity_m_s) / cfg.dt_s;
  }
  out.count = kMpcPlanKnots;
}

MpcStatus mpc_step_rt(const model::Model& model, const MpcConfig& config, MpcWorkspace& ws,
                      const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                      const planner::PlanWindow& reference, MpcPlan& out) {
  MpcStatus status = mpc_build_qp_rt(model, config, ws, q, v, reference);
  if (status == MpcStatus::kOk) status = mpc_solve_qp_rt(ws);
  mpc_write_plan_rt(model, config, ws, reference, status, out);
  return status;
}

void relaxed_barrier(double h, double mu, double delta, double& d1, double& d2) {
  if (h > delta) {
    d1 = -mu / h;
    d2 = mu / (h * h);
  } else {
    d1 = mu * (h - 2.0 * delta) / (delta * delta);
    d2 = mu / (delta * delta);
  }
}

}  // namespace kuavo::mpc
