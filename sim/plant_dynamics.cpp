#include "sim/plant_dynamics.h"

#include <cmath>

#include "controllers/dynamics/rigid_body.h"
#include "sim/joint_stop.h"
#include "sim/motor_model.h"
#include "sim/perturbation.h"
#include "sim/plant.h"

namespace kuavo::sim {

using dynamics::Mat3;
using dynamics::Vec6;

constexpr int kMaxY = model::kNq + model::kNv;

struct PlantDynamics::Work {
  dynamics::Data data;
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  dynamics::VelocityVector rhs = dynamics::VelocityVector::Zero();
  std::array<Vec6, model::kNumBodies> external{};  // world axes, at the reference point
  std::array<int, model::kNv> parent_dof{};  // λ(i) < i, −1 at the root
  // Of the last derivative() call.
  std::array<Vec3, model::kNumContactPoints> contact_p{}, contact_v{}, contact_f{};
  Vec3 base_acceleration_world = Vec3::Zero();
  Eigen::Matrix<double, kMaxY, 1> ydot = Eigen::Matrix<double, kMaxY, 1>::Zero();
};

namespace {

// M = LᵀL exploiting branch-induced sparsity (Featherstone, RBDA §6.5): M(i, j) ≠ 0
// only when one DoF is an ancestor of the other, so the factor fills in nowhere else
// and costs O(n·depth²) instead of O(n³). The base's six DoFs are a chain at the
// root. L overwrites the lower triangle of m (row i, ancestor columns).
void factor_ltl(dynamics::MassMatrix& m, const std::array<int, model::kNv>& parent) {
  for (int k = model::kNv - 1; k >= 0; --k) {
    const double d = std::sqrt(m(k, k));
    m(k, k) = d;
    for (int i = parent[k]; i >= 0; i = parent[i]) m(k, i) /= d;
    for (int i = parent[k]; i >= 0; i = parent[i]) {
      for (int j = i; j >= 0; j = parent[j]) m(i, j) -= m(k, i) * m(k, j);
    }
  }
}

// x ← M⁻¹x with M = LᵀL from factor_ltl.
void solve_ltl(const dynamics::MassMatrix& l, const std::array<int, model::kNv>& parent, dynamics::VelocityVector& x) {
  for (int i = model::kNv - 1; i >= 0; --i) {  // Lᵀy = x
    x[i] /= l(i, i);
    for (int j = parent[i]; j >= 0; j = parent[j]) x[j] -= l(i, j) * x[i];
  }
  for (int i = 0; i < model::kNv; ++i) {  // L·x = y
    for (int j = parent[i]; j >= 0; j = parent[j]) x[i] -= l(i, j) * x[j];
    x[i] /= l(i, i);
  }
}

// The torque source's joint torques at the state (q: base 7 then joints, v: base 6 then joints).
template <class Q, class V>
std::array<double, model::kNumJoints> source_torques(const PlantForceInputs& in, const Q& q, const V& v) {
  std::array<double, model::kNumJoints> qj{}, vj{}, tau{};
  for (int j = 0; j < model::kNumJoints; ++j) {
    qj[j] = q[7 + j];
    vj[j] = v[6 + j];
  }
  in.torque_source->add_joint_torques(qj, vj, tau);
  return tau;
}

// The drives' torques at (q, v) (sim/motor_model.h) with the joints' mismatch applied;
// returns the drives that clipped.
template <class Q, class V>
int drive_torques_at(const model::Model& model, const PlantForceInputs& in, const Q& q, const V& v, JointValues& tau) {
  JointValues qj{}, vj{};
  for (int j = 0; j < model::kNumJoints; ++j) {
    qj[j] = q[7 + j];
    vj[j] = v[6 + j];
  }
  const int clipped = drive_torques(in.command, model, qj, vj, in.ankle_motors, tau);
  if (in.actuation != nullptr) {
    for (int j = 0; j < model::kNumJoints; ++j) tau[j] = actuated_torque(*in.actuation, j, tau[j], vj[j]);
  }
  return clipped;
}

}  // namespace

PlantDynamics::PlantDynamics(const model::Model& model, const SimbodyLayout& layout)
    : model_(model), layout_(layout), work_(std::make_unique<Work>()) {
  for (int i = 0; i < 6; ++i) work_->parent_dof[i] = i - 1;
  for (int b = 1; b < model::kNumBodies; ++b) {
    const int p = model.bodies[b].parent;
    work_->parent_dof[5 + b] = p == 0 ? 5 : 5 + p;  // bodies are numbered parents first
  }
}

PlantDynamics::~PlantDynamics() = default;

bool PlantDynamics::derivative(double t_s, const double* y, const PlantForceInputs& in, double* ydot,
                               Eigen::Matrix<double, 6, 1>& contact_wrench_out) {
  Work& w = *work_;
  dynamics::Data& d = w.data;
  const SimbodyLayout& L = layout_;
  const double* yq = y;
  const double* yu = y + L.num_q;

  // Simbody's state -> ours (conventions.h). Simbody turns the quaternion into a
  // rotation after normalising it; so do we.
  const double* quat = yq + L.base_q;  // w, x, y, z
  const double inv_norm = 1.0 / std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
  w.q.head<3>() << yq[L.base_q + 4], yq[L.base_q + 5], yq[L.base_q + 6];
  w.q.segment<4>(3) << quat[1] * inv_norm, quat[2] * inv_norm, quat[3] * inv_norm, quat[0] * inv_norm;
  for (int j = 0; j < model::kNumJoints; ++j) w.q[7 + j] = yq[L.joint_q[j]];
  dynamics::forward_kinematics(model_, d, w.q);
  const Mat3& r = d.rotation[0];
  const Vec3 omega_world(yu[L.base_u], yu[L.base_u + 1], yu[L.base_u + 2]);
  const Vec3 vel_world(yu[L.base_u + 3], yu[L.base_u + 4], yu[L.base_u + 5]);
  w.v.head<3>() = r.transpose() * vel_world;
  w.v.segment<3>(3) = r.transpose() * omega_world;
  for (int j = 0; j < model::kNumJoints; ++j) w.v[6 + j] = yu[L.joint_u[j]];
  dynamics::forward_velocities(model_, d, w.v);

  // M and the bias b(q, v) including gravity: M v̇ = τ − b.
  dynamics::crba(model_, d);
  dynamics::rnea(model_, d, dynamics::VelocityVector::Zero(), in.gravity);
  w.rhs = -d.tau;
  JointValues drive{};
  drive_torques_at(model_, in, w.q, w.v, drive);
  for (int j = 0; j < model::kNumJoints; ++j) w.rhs[6 + j] += drive[j];
  if (in.actuation != nullptr) {
    // A rotor spinning N times faster adds N²·I_rotor to its joint's diagonal only (its
    // gyroscopic coupling to the carrier is neglected, as in MuJoCo's armature).
    for (int j = 0; j < model::kNumJoints; ++j) d.mass_matrix(6 + j, 6 + j) += in.actuation->armature_kgm2[j];
  }
  if (in.torque_source != nullptr) {
    const std::array<double, model::kNumJoints> extra = source_torques(in, w.q, w.v);
    for (int j = 0; j < model::kNumJoints; ++j) w.rhs[6 + j] += extra[j];
  }
  for (int j = 0; j < model::kNumJoints; ++j) {
    w.rhs[6 + j] += joint_stop_torque(w.q[7 + j], w.v[6 + j], model_.limits.position_min_rad[j], model_.limits.position_max_rad[j]);
  }

  // External point forces as spatial forces at the reference point, summed per body.
  for (auto& f : w.external) f.setZero();
  const Vec3& origin = d.reference_point_m;
  auto apply = [&](int body, const Vec3& point, const Vec3& force) {
    w.external[body].head<3>() += force;
    w.external[body].tail<3>() += (point - origin).cross(force);
  };
  contact_wrench_out.setZero();
  for (auto& f : w.contact_f) f.setZero();
  if (in.contact) {
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      const model::Frame& f = model_.frames[c];
      const Vec3 p = d.position_m[f.body] + d.rotation[f.body] * f.position_m;
      const Vec6& vb = d.velocity[f.body];
      const Vec3 pv = vb.head<3>() + vb.tail<3>().cross(p - origin);
      const Vec3 force = contact_force(in.ground, p, pv, in.points[c]);
      w.contact_p[c] = p;
      w.contact_v[c] = pv;
      w.contact_f[c] = force;
      if (force.z() > 0.0) {
        apply(f.body, p, force);
        contact_wrench_out.head<3>() += force;
        contact_wrench_out.tail<3>() += p.cross(force);
      }
    }
  }
  if (in.push != nullptr) {
    const Push& push = *in.push;
    if (push.duration_s > 0.0 && t_s >= push.start_s && t_s < push.start_s + push.duration_s) {
      apply(0, d.position_m[0] + r * model_.bodies[0].com_m, push.force_N);
    }
  }
  // τ_ext = Σ Jᵀ f: accumulate the spatial forces towards the root, project on each joint axis.
  for (int b = model::kNumBodies - 1; b > 0; --b) {
    w.rhs[5 + b] += d.motion_subspace[b].dot(w.external[b]);
    w.external[model_.bodies[b].parent] += w.external[b];
  }
  w.rhs.head<3>() += r.transpose() * w.external[0].head<3>();
  w.rhs.segment<3>(3) += r.transpose() * w.external[0].tail<3>();

  factor_ltl(d.mass_matrix, w.parent_dof);  // in place: M is rebuilt at the next evaluation
  solve_ltl(d.mass_matrix, w.parent_dof, w.rhs);
  const dynamics::VelocityVector& vdot = w.rhs;

  // Ours -> Simbody's u̇ and q̇. d/dt(R·v_b) = R·v̇_b + ω×(R·v_b); d/dt(R·ω_b) = R·ω̇_b.
  double* qdot = ydot;
  double* udot = ydot + L.num_q;
  const Vec3 alpha_world = r * vdot.segment<3>(3);
  const Vec3 acc_world = r * vdot.head<3>() + omega_world.cross(vel_world);
  w.base_acceleration_world = acc_world;
  for (int k = 0; k < 3; ++k) {
    udot[L.base_u + k] = alpha_world[k];
    udot[L.base_u + 3 + k] = acc_world[k];
    qdot[L.base_q + 4 + k] = vel_world[k];
  }
  // Quaternion rate for an angular velocity in the parent (ground) frame, from the
  // unnormalised quaternion as Simbody does: ė = ½(e₀ω + ω×e), ė₀ = −½ω·e.
  const Vec3 e(quat[1], quat[2], quat[3]);
  const Vec3 e_dot = 0.5 * (quat[0] * omega_world + omega_world.cross(e));
  qdot[L.base_q] = -0.5 * omega_world.dot(e);
  qdot[L.base_q + 1] = e_dot.x();
  qdot[L.base_q + 2] = e_dot.y();
  qdot[L.base_q + 3] = e_dot.z();
  for (int j = 0; j < model::kNumJoints; ++j) {
    qdot[L.joint_q[j]] = w.v[6 + j];
    udot[L.joint_u[j]] = vdot[6 + j];
  }
  bool finite = true;
  for (int i = 0; i < L.num_q + L.num_u; ++i) finite = finite && std::isfinite(ydot[i]);
  return finite;
}

bool PlantDynamics::truth(double t_s, const double* y, const PlantForceInputs& in, PlantTruth& out,
                          std::array<Vec3, model::kNumContactPoints>& contact_velocity_m_s,
                          std::uint64_t& saturations) {
  Work& w = *work_;
  Eigen::Matrix<double, 6, 1> wrench;
  if (!derivative(t_s, y, in, w.ydot.data(), wrench)) return false;
  const dynamics::Data& d = w.data;
  out.q = w.q;
  if (out.q[6] < 0.0) out.q.segment<4>(3) *= -1.0;  // the same rotation; w ≥ 0 as Simbody reports it
  out.v = w.v;
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    if (!in.contact) {  // derivative() skipped the corners
      const model::Frame& f = model_.frames[c];
      w.contact_p[c] = d.position_m[f.body] + d.rotation[f.body] * f.position_m;
      const Vec6& vb = d.velocity[f.body];
      w.contact_v[c] = vb.head<3>() + vb.tail<3>().cross(w.contact_p[c] - d.reference_point_m);
    }
    out.contact_point_m[c] = w.contact_p[c];
    out.contact_force_N[c] = w.contact_f[c];
    contact_velocity_m_s[c] = w.contact_v[c];
  }
  JointValues drive{};
  saturations += drive_torques_at(model_, in, w.q, w.v, drive);
  for (int j = 0; j < model::kNumJoints; ++j) out.joint_torque_Nm[j] = drive[j];
  if (in.torque_source != nullptr) {
    const std::array<double, model::kNumJoints> extra = source_torques(in, w.q, w.v);
    for (int j = 0; j < model::kNumJoints; ++j) out.joint_torque_Nm[j] += extra[j];
  }
  const Vec3 g(0.0, 0.0, in.gravity ? -model::kGravity_m_s2 : 0.0);
  out.base_specific_force_m_s2 = d.rotation[0].transpose() * (w.base_acceleration_world - g);
  out.com_m = d.com_m;
  // Momentum about the reference point, Σ I·V, then its moment moved to the CoM.
  Vec6 h = Vec6::Zero();
  for (int b = 0; b < model::kNumBodies; ++b) h += d.inertia[b] * d.velocity[b];
  out.momentum.head<3>() = h.head<3>();
  out.momentum.tail<3>() = h.tail<3>() - (d.com_m - d.reference_point_m).cross(h.head<3>());
  return true;
}

}  // namespace kuavo::sim
