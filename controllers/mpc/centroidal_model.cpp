#include "controllers/mpc/centroidal_model.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "controllers/wbc/wbc_reference.h"

namespace kuavo::mpc {
namespace {

using dynamics::skew;

// R = Rz(ψ) Ry(θ) Rx(φ), its partial derivatives, and E_B⁻¹ (ω_b = E_B ė) with its partials.
// E_B⁻¹ = [0, sφ/cθ, cφ/cθ; 0, cφ, −sφ; 1, sφ tθ, cφ tθ] (singular at pitch ±90°, far outside
// anything a standing or dancing humanoid does).
void orientation_terms(const Vec3& e, CentroidalPoint& p) {
  const double cy = std::cos(e[0]), sy = std::sin(e[0]);
  const double cp = std::cos(e[1]), sp = std::sin(e[1]);
  const double cr = std::cos(e[2]), sr = std::sin(e[2]);
  Mat3 rz, ry, rx;
  rz << cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0;
  ry << cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp;
  rx << 1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr;
  p.rotation = rz * ry * rx;
  p.rotation_derivative[0] = skew(Vec3::UnitZ()) * p.rotation;
  p.rotation_derivative[1] = rz * skew(Vec3::UnitY()) * ry * rx;
  p.rotation_derivative[2] = p.rotation * skew(Vec3::UnitX());
  const double tp = sp / cp, c2 = cp * cp;
  p.euler_rate_map << 0.0, sr / cp, cr / cp, 0.0, cr, -sr, 1.0, sr * tp, cr * tp;
  p.euler_rate_map_derivative[0].setZero();
  p.euler_rate_map_derivative[1] << 0.0, sr * sp / c2, cr * sp / c2, 0.0, 0.0, 0.0, 0.0, sr / c2, cr / c2;
  p.euler_rate_map_derivative[2] << 0.0, cr / cp, -sr / cp, 0.0, -sr, -cr, 0.0, cr * tp, -sr * tp;
}

}  // namespace

int leg_chain_first_column(const model::Model& model, int body) {
  int n = 0, lo = kNumMpcJoints, hi = -1;
  for (int a = body; a > 0; a = model.bodies[a].parent) {
    const int k = a - 1;
    if (k >= kNumMpcJoints) continue;
    ++n;
    lo = std::min(lo, k);
    hi = std::max(hi, k);
  }
  return n == kLegChain && hi - lo + 1 == kLegChain ? lo : -1;
}

void point_position_jacobian(const model::Model& model, const CentroidalPoint& p, int body,
                             const Vec3& point_base_m, Eigen::Matrix<double, 3, kNumMpcJoints>& jacobian) {
  jacobian.setZero();
  for (int a = body; a > 0; a = model.bodies[a].parent) {
    const int k = a - 1;
    if (k >= kNumMpcJoints) continue;  // head: a parameter
    const Vec6& s = p.data.motion_subspace[a];
    jacobian.col(k) = s.head<3>() + s.tail<3>().cross(point_base_m);
  }
}

void point_motion(const model::Model& model, const CentroidalPoint& p, int body, const Vec3& point_base_m,
                  Vec6& motion, MotionRowsX& motion_dx, MotionRowsU& motion_du) {
  const dynamics::Data& d = p.data;
  const Vec6& vel = d.velocity[body];
  const Vec3 omega = vel.tail<3>();
  motion.head<3>() = vel.head<3>() + omega.cross(point_base_m);
  motion.tail<3>() = omega;
  // Through the base twist: v_P = v_b + ω_b × P (+ joints), ω = ω_b (+ joints).
  motion_dx.topRows<3>() = p.base_twist_dx.topRows<3>() - skew(point_base_m) * p.base_twist_dx.bottomRows<3>();
  motion_dx.bottomRows<3>() = p.base_twist_dx.bottomRows<3>();
  // v_b does not depend on the forces (base_twist_du's force columns are zero).
  constexpr int kNuj = kNu - kUJointVelocity;
  motion_du.leftCols<kUJointVelocity>().setZero();
  motion_du.block<3, kNuj>(0, kUJointVelocity) = p.base_twist_du.block<3, kNuj>(0, kUJointVelocity) -
                                                skew(point_base_m) * p.base_twist_du.block<3, kNuj>(3, kUJointVelocity);
  motion_du.block<3, kNuj>(3, kUJointVelocity) = p.base_twist_du.block<3, kNuj>(3, kUJointVelocity);
  for (int a = body; a > 0; a = model.bodies[a].parent) {
    const int k = a - 1;
    if (k >= kNumMpcJoints) continue;
    const Vec6& s = d.motion_subspace[a];
    const Vec6 dv = dynamics::cross_motion(s, vel - d.velocity[model.bodies[a].parent]);
    const Vec3 dpoint = s.head<3>() + s.tail<3>().cross(point_base_m);
    motion_dx.block<3, 1>(0, kXJoints + k) += dv.head<3>() + dv.tail<3>().cross(point_base_m) + omega.cross(dpoint);
    motion_dx.block<3, 1>(3, kXJoints + k) += dv.tail<3>();
    motion_du.block<3, 1>(0, kUJointVelocity + k) += dpoint;
    motion_du.block<3, 1>(3, kUJointVelocity + k) += s.tail<3>();
  }
}

void centroidal_evaluate(const model::Model& model, const StateVector& x, const InputVector& u,
                         const HeadVector& head_rad, CentroidalPoint& p) {
  dynamics::Data& d = p.data;
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  q[6] = 1.0;
  q.segment<kNumMpcJoints>(7) = x.segment<kNumMpcJoints>(kXJoints);
  q.segment<2>(7 + kNumMpcJoints) = head_rad;
  dynamics::forward_kinematics(model, d, q);
  // Composite inertias and the momentum matrix at the base origin (base axes): crba() without
  // the joint-space mass matrix, which the MPC never reads.
  for (int b = 0; b < model::kNumBodies; ++b) d.composite[b] = d.inertia[b];
  for (int b = model::kNumBodies - 1; b > 0; --b) {
    d.composite[model.bodies[b].parent] += d.composite[b];
    d.momentum_matrix_ref.col(5 + b) = d.composite[b] * d.motion_subspace[b];
  }
  d.momentum_matrix_ref.leftCols<6>() = d.composite[0].matrix();  // base twist columns (R = I)
  d.total_mass_kg = d.composite[0].mass;
  const double m = d.total_mass_kg;
  p.mass_kg = m;
  const Vec3 c = d.composite[0].first_moment / m;
  p.com_base_m = c;
  // A_G in base axes: moment shifted from the base origin to the CoM.
  d.centroidal_matrix.topRows<3>() = d.momentum_matrix_ref.topRows<3>();
  d.centroidal_matrix.bottomRows<3>() = d.momentum_matrix_ref.bottomRows<3>() - skew(c) * d.momentum_matrix_ref.topRows<3>();

  orientation_terms(x.segment<3>(kXEuler), p);
  const Mat3& r = p.rotation;
  const Vec3 com_vel = x.segment<3>(kXComVelocity);
  const Vec3 h = x.segment<3>(kXMomentum);
  const auto uj = u.segment<kNumMpcJoints>(kUJointVelocity);

  // Base twist from the momentum.
  // A_b⁻¹ explicitly: six fixed-size products below are cheaper than LU solves with many
  // right-hand sides. A_b = [m I, −m[c]×; ·, ·] is well conditioned (m, I_G of a 55 kg robot).
  const dynamics::Mat6 ab_inv = dynamics::Mat6(d.centroidal_matrix.leftCols<6>()).inverse();
  const auto aj = d.centroidal_matrix.block<6, kNumMpcJoints>(0, 6);
  Vec6 rhs;
  rhs.head<3>() = m * (r.transpose() * com_vel);
  rhs.tail<3>() = r.transpose() * h;
  rhs.noalias() -= aj * uj;
  p.base_twist.noalias() = ab_inv * rhs;

  // Body velocities and subtree momenta at v = [v_b; q̇_j; head 0].
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v.head<6>() = p.base_twist;
  v.segment<kNumMpcJoints>(6) = uj;
  dynamics::forward_velocities(model, d, v);
  for (int b = 0; b < model::kNumBodies; ++b) p.subtree_momentum[b] = d.inertia[b] * d.velocity[b];
  for (int b = model::kNumBodies - 1; b > 0; --b) p.subtree_momentum[model.bodies[b].parent] += p.subtree_momentum[b];
  const Vec3 l = p.subtree_momentum[0].head<3>();
  for (int j = 0; j < kNumMpcJoints; ++j) {
    const int b = j + 1;
    const Vec6& s = d.motion_subspace[b];
    const Vec6 dh_o = dynamics::cross_force(s, p.subtree_momentum[b]) -
                      d.composite[b] * dynamics::cross_motion(s, d.velocity[model.bodies[b].parent]);
    const Vec3 dc = d.momentum_matrix_ref.block<3, 1>(0, 5 + b) / m;
    p.momentum_dq.block<3, 1>(0, j) = dh_o.head<3>();
    p.momentum_dq.block<3, 1>(3, j) = dh_o.tail<3>() - dc.cross(l) - c.cross(dh_o.head<3>());
  }

  // ∂v_b.
  auto& tdx = p.base_twist_dx;
  auto& tdu = p.base_twist_du;
  // Base-position columns of tdx and force columns of tdu are zero: never written here, so
  // they keep the zeros of the point's construction (no per-call clearing).
  tdx.block<6, 3>(0, kXComVelocity).noalias() = ab_inv.leftCols<3>() * (m * r.transpose());
  tdx.block<6, 3>(0, kXMomentum).noalias() = ab_inv.rightCols<3>() * r.transpose();
  for (int i = 0; i < 3; ++i) {
    Vec6 col;
    col.head<3>() = m * (p.rotation_derivative[i].transpose() * com_vel);
    col.tail<3>() = p.rotation_derivative[i].transpose() * h;
    tdx.col(kXEuler + i).noalias() = ab_inv * col;
  }
  tdx.block<6, kNumMpcJoints>(0, kXJoints).noalias() = -ab_inv * p.momentum_dq;
  tdu.block<6, kNumMpcJoints>(0, kUJointVelocity).noalias() = -ab_inv * aj;

  // f and its Jacobians.
  // fx and fu are mostly structural zeros (rows of ṙ, the joints; the joint-velocity columns of
  // ṙ, ḣ; the force columns of q̇_j). Every call writes the same blocks below, the rest keeps the
  // zeros of the point's construction: only ḣ's accumulated block is cleared.
  p.f.setZero();
  p.fx.block<3, kNx>(kXMomentum, 0).setZero();
  Vec3 force_sum = Vec3::Zero();
  Mat3 force_skew_sum = Mat3::Zero();
  Eigen::Matrix<double, 3, kNumMpcJoints> jp;
  for (int i = 0; i < kNumPoints; ++i) {
    const Vec3 fi = u.segment<3>(kUForces + 3 * i);
    const int body = model.frames[i].body;
    const Vec3 point = dynamics::frame_position(model, d, i);
    const Vec3 arm_b = point - c;
    const Vec3 arm_w = r * arm_b;
    force_sum += fi;
    p.f.segment<3>(kXMomentum) += arm_w.cross(fi);
    p.fu.block<3, 3>(kXComVelocity, kUForces + 3 * i) = Mat3::Identity() / m;
    p.fu.block<3, 3>(kXMomentum, kUForces + 3 * i) = skew(arm_w);
    const Mat3 sf = skew(fi);
    force_skew_sum += sf;
    for (int e = 0; e < 3; ++e) p.fx.block<3, 1>(kXMomentum, kXEuler + e) -= sf * (p.rotation_derivative[e] * arm_b);
    point_position_jacobian(model, p, body, point, jp);
    // jp is zero but in the columns of the body's chain: a leg's six contiguous joints.
    const int lo = leg_chain_first_column(model, body);
    if (lo >= 0) {
      p.fx.block<3, kLegChain>(kXMomentum, kXJoints + lo).noalias() -= sf * (r * jp.middleCols<kLegChain>(lo));
    } else {
      p.fx.block<3, kNumMpcJoints>(kXMomentum, kXJoints).noalias() -= sf * (r * jp);
    }
  }
  // − Σ skew(fᵢ) R (−J_c): the CoM moves with the joints too.
  p.fx.block<3, kNumMpcJoints>(kXMomentum, kXJoints).noalias() +=
      force_skew_sum * (r * (d.momentum_matrix_ref.block<3, kNumMpcJoints>(0, 6) / m));
  p.f.segment<3>(kXComVelocity) = force_sum / m - model::kGravity_m_s2 * Vec3::UnitZ();

  const Vec3 v_lin = p.base_twist.head<3>();
  const Vec3 omega = p.base_twist.tail<3>();
  p.f.segment<3>(kXBasePosition) = r * v_lin;
  p.fx.block<3, kNx>(kXBasePosition, 0).noalias() = r * tdx.topRows<3>();
  p.fu.block<3, kNu>(kXBasePosition, 0).noalias() = r * tdu.topRows<3>();
  p.f.segment<3>(kXEuler) = p.euler_rate_map * omega;
  p.fx.block<3, kNx>(kXEuler, 0).noalias() = p.euler_rate_map * tdx.bottomRows<3>();
  p.fu.block<3, kNu>(kXEuler, 0).noalias() = p.euler_rate_map * tdu.bottomRows<3>();
  for (int e = 0; e < 3; ++e) {
    p.fx.block<3, 1>(kXBasePosition, kXEuler + e) += p.rotation_derivative[e] * v_lin;
    p.fx.block<3, 1>(kXEuler, kXEuler + e) += p.euler_rate_map_derivative[e] * omega;
  }
  p.f.segment<kNumMpcJoints>(kXJoints) = uj;
  p.fu.block<kNumMpcJoints, kNumMpcJoints>(kXJoints, kUJointVelocity).diagonal().setOnes();
}

void state_from_configuration(const model::Model& model, dynamics::Data& data, const dynamics::ConfigVector& q,
                              const dynamics::VelocityVector& v, StateVector& x) {
  dynamics::forward_kinematics(model, data, q);
  dynamics::forward_velocities(model, data, v);
  Vec6 momentum = Vec6::Zero();  // at the base origin, world axes
  Vec3 first_moment = Vec3::Zero();
  double mass = 0.0;
  for (int b = 0; b < model::kNumBodies; ++b) {
    momentum += data.inertia[b] * data.velocity[b];
    first_moment += data.inertia[b].first_moment;
    mass += data.inertia[b].mass;
  }
  const Vec3 c = first_moment / mass;
  x.segment<3>(kXComVelocity) = momentum.head<3>() / mass;
  x.segment<3>(kXMomentum) = momentum.tail<3>() - c.cross(momentum.head<3>());
  x.segment<3>(kXBasePosition) = q.head<3>();
  x.segment<3>(kXEuler) = wbc::euler_zyx_from_rotation(data.rotation[0]);
  x.segment<kNumMpcJoints>(kXJoints) = q.segment<kNumMpcJoints>(7);
}

dynamics::ConfigVector configuration_from_state(const StateVector& x, const HeadVector& head_rad) {
  dynamics::ConfigVector q;
  q.head<3>() = x.segment<3>(kXBasePosition);
  const Eigen::Quaterniond o(wbc::rotation_from_euler_zyx(x.segment<3>(kXEuler)));
  q[3] = o.x();
  q[4] = o.y();
  q[5] = o.z();
  q[6] = o.w();
  q.segment<kNumMpcJoints>(7) = x.segment<kNumMpcJoints>(kXJoints);
  q.segment<2>(7 + kNumMpcJoints) = head_rad;
  return q;
}

}  // namespace kuavo::mpc
