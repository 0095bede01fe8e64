#include "controllers/dynamics/rigid_body.h"

#include <algorithm>
#include <cmath>

namespace kuavo::dynamics {
namespace {

constexpr int kBase = 0;

// Spatial motion of the base for a base-axis twist [v; ω]: both rotate to world.
inline Vec6 base_motion(const Mat3& r, const Vec6& twist_base) {
  Vec6 m;
  m.head<3>() = r * twist_base.head<3>();
  m.tail<3>() = r * twist_base.tail<3>();
  return m;
}

// Transpose of base_motion: a world force at the reference point -> base axes.
inline Vec6 base_force(const Mat3& r, const Vec6& f) {
  Vec6 out;
  out.head<3>() = r.transpose() * f.head<3>();
  out.tail<3>() = r.transpose() * f.tail<3>();
  return out;
}

// Gravity as a fictitious upward acceleration of the base (Featherstone's trick).
inline Vec6 gravity_offset() {
  Vec6 a = Vec6::Zero();
  a.z() = model::kGravity_m_s2;
  return a;
}

}  // namespace

ConfigVector neutral_configuration(const Model& model) {
  ConfigVector q = ConfigVector::Zero();
  q[6] = 1.0;  // w
  // With straight legs every sole corner hangs at the same depth below the base.
  // Walk the chain of the first contact frame at q = 0 (all joint rotations identity).
  const model::Frame& f = model.frames[0];
  Vec3 p = f.position_m;
  for (int b = f.body; b > kBase; b = model.bodies[b].parent) {
    p = model.bodies[b].joint_position_m + model.bodies[b].joint_rotation * p;
  }
  q[2] = -p.z();
  return q;
}

ConfigVector integrate(const ConfigVector& q, const VelocityVector& v, double dt_s) {
  ConfigVector out = q;
  const Eigen::Quaterniond quat(q[6], q[3], q[4], q[5]);
  const Mat3 r = quat.toRotationMatrix();
  const Vec3 vel = v.head<3>() * dt_s;
  const Vec3 omega = v.segment<3>(3) * dt_s;
  const double theta = omega.norm();
  // SE(3) exponential of the local twist: translation = V(ω)·v.
  Mat3 v_mat = Mat3::Identity();
  Mat3 rot_delta = Mat3::Identity();
  if (theta > 1e-12) {
    const Mat3 w = skew(omega);
    const double a = std::sin(theta) / theta;
    const double b = (1.0 - std::cos(theta)) / (theta * theta);
    const double c = (theta - std::sin(theta)) / (theta * theta * theta);
    rot_delta = Mat3::Identity() + a * w + b * w * w;
    v_mat = Mat3::Identity() + b * w + c * w * w;
  } else {
    const Mat3 w = skew(omega);
    rot_delta = Mat3::Identity() + w + 0.5 * w * w;
    v_mat = Mat3::Identity() + 0.5 * w + (1.0 / 6.0) * w * w;
  }
  out.head<3>() = q.head<3>() + r * (v_mat * vel);
  Eigen::Quaterniond qn(r * rot_delta);
  qn.normalize();
  out[3] = qn.x();
  out[4] = qn.y();
  out[5] = qn.z();
  out[6] = qn.w();
  out.tail<kNumJoints>() = q.tail<kNumJoints>() + v.tail<kNumJoints>() * dt_s;
  return out;
}

namespace {

// The base's pose from q; the reference point at its origin.
void place_base(Data& data, const ConfigVector& q) {
  const Eigen::Quaterniond quat(q[6], q[3], q[4], q[5]);
  data.rotation[kBase] = quat.toRotationMatrix();
  data.position_m[kBase] = q.head<3>();
  data.reference_point_m = q.head<3>();
}

// Body b's pose and joint motion subspace from its parent's (placed before it).
inline void place_body(const Model& model, Data& data, const ConfigVector& q, int b) {
  const model::Body& body = model.bodies[b];
  const int p = body.parent;
  const Mat3 r_joint = data.rotation[p] * body.joint_rotation;
  data.position_m[b] = data.position_m[p] + data.rotation[p] * body.joint_position_m;
  data.rotation[b] = r_joint * axis_rotation(body.axis, q[7 + b - 1]);
  const Vec3 axis_world = r_joint * body.axis;
  const Vec3 r = data.position_m[b] - data.reference_point_m;
  data.motion_subspace[b].head<3>() = r.cross(axis_world);
  data.motion_subspace[b].tail<3>() = axis_world;
}

}  // namespace

void forward_kinematics(const Model& model, Data& data, const ConfigVector& q) {
  place_base(data, q);
  const Vec3 origin = data.reference_point_m;
  for (int b = 0; b < kNumBodies; ++b) {
    const model::Body& body = model.bodies[b];
    if (b > kBase) place_body(model, data, q, b);
    // Body inertia in world axes about the reference point.
    const Mat3& rb = data.rotation[b];
    const Vec3 c = data.position_m[b] - origin + rb * body.com_m;
    SpatialInertia& in = data.inertia[b];
    in.mass = body.mass_kg;
    in.first_moment = body.mass_kg * c;
    in.rotational = rb * body.inertia_com_kgm2 * rb.transpose() +
                    body.mass_kg * (c.squaredNorm() * Mat3::Identity() - c * c.transpose());
  }
}

void forward_kinematics_chain(const Model& model, Data& data, const ConfigVector& q, int first_body, int last_body) {
  place_base(data, q);
  for (int b = std::max(first_body, kBase + 1); b <= last_body && b < kNumBodies; ++b) place_body(model, data, q, b);
}

void forward_velocities(const Model& model, Data& data, const VelocityVector& v) {
  data.velocity[kBase] = base_motion(data.rotation[kBase], v.head<6>());
  for (int b = 1; b < kNumBodies; ++b) {
    data.velocity[b] = data.velocity[model.bodies[b].parent] + data.motion_subspace[b] * v[5 + b];
  }
}

Vec3 frame_position(const Model& model, const Data& data, int frame) {
  const model::Frame& f = model.frames[frame];
  return data.position_m[f.body] + data.rotation[f.body] * f.position_m;
}

Mat3 frame_rotation(const Model& model, const Data& data, int frame) {
  const model::Frame& f = model.frames[frame];
  return data.rotation[f.body] * f.rotation;
}

void point_jacobian(const Model& model, const Data& data, int body, const Vec3& point_world_m,
                    FrameJacobian& jacobian) {
  jacobian.setZero();
  const Vec3 r = point_world_m - data.reference_point_m;
  const Mat3& rb = data.rotation[kBase];
  jacobian.block<3, 3>(0, 0) = rb;
  jacobian.block<3, 3>(0, 3) = -skew(r) * rb;
  jacobian.block<3, 3>(3, 3) = rb;
  for (int b = body; b > kBase; b = model.bodies[b].parent) {
    const Vec6& s = data.motion_subspace[b];
    jacobian.block<3, 1>(0, 5 + b) = s.head<3>() + s.tail<3>().cross(r);
    jacobian.block<3, 1>(3, 5 + b) = s.tail<3>();
  }
}

void frame_jacobian(const Model& model, const Data& data, int frame, FrameJacobian& jacobian) {
  point_jacobian(model, data, model.frames[frame].body, frame_position(model, data, frame), jacobian);
}

void bias_accelerations(const Model& model, Data& data) {
  data.acceleration[kBase].setZero();
  for (int b = 1; b < kNumBodies; ++b) {
    const int p = model.bodies[b].parent;
    // The joint axis moves with the body: Ṡ·q̇ = V ×m (S·q̇).
    data.acceleration[b] = data.acceleration[p] + cross_motion(data.velocity[b], data.velocity[b] - data.velocity[p]);
  }
}

Vec6 frame_velocity(const Model& model, const Data& data, int frame) {
  const int b = model.frames[frame].body;
  const Vec3 r = frame_position(model, data, frame) - data.reference_point_m;
  const Vec6& v = data.velocity[b];
  Vec6 out;
  out.head<3>() = v.head<3>() + v.tail<3>().cross(r);
  out.tail<3>() = v.tail<3>();
  return out;
}

Vec6 frame_bias_acceleration(const Model& model, const Data& data, int frame) {
  const int b = model.frames[frame].body;
  const Vec3 r = frame_position(model, data, frame) - data.reference_point_m;
  const Vec6& v = data.velocity[b];
  const Vec6& a = data.acceleration[b];
  const Vec3 omega = v.tail<3>();
  const Vec3 v_point = v.head<3>() + omega.cross(r);
  Vec6 out;
  out.head<3>() = a.head<3>() + a.tail<3>().cross(r) + omega.cross(v_point);
  out.tail<3>() = a.tail<3>();
  return out;
}

void crba(const Model& model, Data& data) {
  for (int b = 0; b < kNumBodies; ++b) data.composite[b] = data.inertia[b];
  MassMatrix& m = data.mass_matrix;
  const Mat3& rb = data.rotation[kBase];
  for (int b = kNumBodies - 1; b > kBase; --b) {
    data.composite[model.bodies[b].parent] += data.composite[b];
    const Vec6 f = data.composite[b] * data.motion_subspace[b];
    data.momentum_matrix_ref.col(5 + b) = f;
    const int col = 5 + b;
    for (int a = b; a > kBase; a = model.bodies[a].parent) {
      const double mij = data.motion_subspace[a].dot(f);
      m(5 + a, col) = mij;
      m(col, 5 + a) = mij;
    }
    const Vec6 fb = base_force(rb, f);
    m.block<6, 1>(0, col) = fb;
    m.block<1, 6>(col, 0) = fb.transpose();
  }
  const SpatialInertia& total = data.composite[kBase];
  for (int k = 0; k < 6; ++k) {
    Vec6 twist = Vec6::Zero();
    twist[k] = 1.0;
    data.momentum_matrix_ref.col(k) = total * base_motion(rb, twist);
  }
  for (int k = 0; k < 6; ++k) m.block<6, 1>(0, k) = base_force(rb, data.momentum_matrix_ref.col(k));
  data.total_mass_kg = total.mass;
  data.com_m = data.reference_point_m + total.first_moment / total.mass;
}

void rnea(const Model& model, Data& data, const VelocityVector& a, bool with_gravity) {
  data.acceleration[kBase] = base_motion(data.rotation[kBase], a.head<6>());
  if (with_gravity) data.acceleration[kBase] += gravity_offset();
  for (int b = 0; b < kNumBodies; ++b) {
    if (b > kBase) {
      const int p = model.bodies[b].parent;
      const Vec6& s = data.motion_subspace[b];
      const Vec6 joint_vel = data.velocity[b] - data.velocity[p];
      data.acceleration[b] = data.acceleration[p] + s * a[5 + b] + cross_motion(data.velocity[b], joint_vel);
    }
    const SpatialInertia& in = data.inertia[b];
    data.force[b] = in * data.acceleration[b] + cross_force(data.velocity[b], in * data.velocity[b]);
  }
  for (int b = kNumBodies - 1; b > kBase; --b) {
    data.tau[5 + b] = data.motion_subspace[b].dot(data.force[b]);
    data.force[model.bodies[b].parent] += data.force[b];
  }
  data.tau.head<6>() = base_force(data.rotation[kBase], data.force[kBase]);
}

// A_G, I_G and Ȧ_G·v from the composite inertia and the momentum rate at the
// reference point for v̇ = 0 without gravity (Ȧ_G·v: ċ × l = 0, so only the moment shifts).
static void finish_centroidal(Data& data, const Vec6& momentum_rate_ref) {
  const SpatialInertia& total = data.composite[kBase];
  const Vec3 c = total.first_moment / total.mass;  // CoM relative to the reference point
  data.centroidal_matrix.topRows<3>() = data.momentum_matrix_ref.topRows<3>();
  data.centroidal_matrix.bottomRows<3>() =
      data.momentum_matrix_ref.bottomRows<3>() - skew(c) * data.momentum_matrix_ref.topRows<3>();
  data.centroidal_inertia_kgm2 =
      total.rotational - total.mass * (c.squaredNorm() * Mat3::Identity() - c * c.transpose());
  data.centroidal_bias.head<3>() = momentum_rate_ref.head<3>();
  data.centroidal_bias.tail<3>() = momentum_rate_ref.tail<3>() - c.cross(momentum_rate_ref.head<3>());
}

void centroidal_dynamics(const Model& model, Data& data) {
  bias_accelerations(model, data);
  Vec6 momentum_rate = Vec6::Zero();
  for (int b = 0; b < kNumBodies; ++b) {
    const SpatialInertia& in = data.inertia[b];
    momentum_rate += in * data.acceleration[b] + cross_force(data.velocity[b], in * data.velocity[b]);
  }
  finish_centroidal(data, momentum_rate);
}

void com_jacobian(const Data& data, ComJacobian& jacobian) {
  jacobian = data.momentum_matrix_ref.topRows<3>() / data.total_mass_kg;
}

void compute_all_terms(const Model& model, Data& data, const ConfigVector& q, const VelocityVector& v) {
  forward_kinematics(model, data, q);
  forward_velocities(model, data, v);
  crba(model, data);
  rnea(model, data, VelocityVector::Zero(), true);
  // The root force of that pass is ḣ plus gravity's share, Σ I_i·g_offset = I_composite·g_offset;
  // removing it saves a second pass.
  finish_centroidal(data, data.force[kBase] - data.composite[kBase] * gravity_offset());
}

}  // namespace kuavo::dynamics
