#include "sim/simbody_model.h"

namespace kuavo::sim {
namespace {

SimTK::Vec3 to_simtk(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

SimTK::Rotation to_simtk(const Eigen::Matrix3d& r) {
  SimTK::Mat33 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = r(i, j);
  return SimTK::Rotation(m, true);
}

SimTK::Body::Rigid rigid_body(const model::Body& b) {
  const Eigen::Matrix3d& i = b.inertia_com_kgm2;
  const SimTK::Inertia about_com(i(0, 0), i(1, 1), i(2, 2), i(0, 1), i(0, 2), i(1, 2));
  // Simbody wants the inertia about the body origin.
  const SimTK::Vec3 com = to_simtk(b.com_m);
  return SimTK::Body::Rigid(
      SimTK::MassProperties(b.mass_kg, com, about_com.shiftFromMassCenter(com, b.mass_kg)));
}

}  // namespace

SimbodyRobot::SimbodyRobot(const model::Model& model, bool gravity)
    : matter_(system_), forces_(system_) {
  if (gravity) {
    SimTK::Force::UniformGravity(forces_, matter_, SimTK::Vec3(0, 0, -model::kGravity_m_s2));
  }
  bodies_[0] = SimTK::MobilizedBody::Free(matter_.Ground(), SimTK::Transform(),
                                          rigid_body(model.bodies[0]), SimTK::Transform());
  for (int b = 1; b < model::kNumBodies; ++b) {
    const model::Body& body = model.bodies[b];
    // A Pin turns about its frames' common z: align z with the joint axis
    // (given in the child frame) on both sides.
    const SimTK::Rotation align(SimTK::UnitVec3(to_simtk(body.axis)), SimTK::ZAxis);
    const SimTK::Transform x_pf(to_simtk(body.joint_rotation) * align, to_simtk(body.joint_position_m));
    const SimTK::Transform x_bm(align, SimTK::Vec3(0));
    bodies_[b] = SimTK::MobilizedBody::Pin(bodies_[body.parent], x_pf, rigid_body(body), x_bm);
  }
  system_.realizeTopology();
  const SimTK::State& s = system_.getDefaultState();
  base_u_index_ = bodies_[0].getFirstUIndex(s);
  for (int j = 0; j < model::kNumJoints; ++j) joint_u_index_[j] = bodies_[j + 1].getFirstUIndex(s);
}

void SimbodyRobot::set_state(SimTK::State& state, const dynamics::ConfigVector& q,
                             const dynamics::VelocityVector& v) const {
  const Eigen::Quaterniond quat(q[6], q[3], q[4], q[5]);
  const Eigen::Matrix3d r = quat.toRotationMatrix();
  bodies_[0].setQToFitTransform(state, SimTK::Transform(to_simtk(r), to_simtk(Eigen::Vector3d(q.head<3>()))));
  for (int j = 0; j < model::kNumJoints; ++j) bodies_[j + 1].setOneQ(state, 0, q[7 + j]);
  const Eigen::Vector3d v_world = r * v.head<3>();
  const Eigen::Vector3d w_world = r * v.segment<3>(3);
  bodies_[0].setUToFitVelocity(state, SimTK::SpatialVec(to_simtk(w_world), to_simtk(v_world)));
  for (int j = 0; j < model::kNumJoints; ++j) bodies_[j + 1].setOneU(state, 0, v[6 + j]);
  system_.realize(state, SimTK::Stage::Velocity);
}

void SimbodyRobot::get_state(const SimTK::State& state, dynamics::ConfigVector& q,
                             dynamics::VelocityVector& v) const {
  const SimTK::Transform& x = bodies_[0].getBodyTransform(state);
  const SimTK::Quaternion quat = x.R().convertRotationToQuaternion();  // (w, x, y, z)
  q.head<3>() << x.p()[0], x.p()[1], x.p()[2];
  q.segment<4>(3) << quat[1], quat[2], quat[3], quat[0];
  const SimTK::SpatialVec& vel = bodies_[0].getBodyVelocity(state);  // ground axes, at body origin
  const SimTK::Vec3 w_base = ~x.R() * vel[0];
  const SimTK::Vec3 v_base = ~x.R() * vel[1];
  for (int k = 0; k < 3; ++k) {
    v[k] = v_base[k];
    v[3 + k] = w_base[k];
  }
  for (int j = 0; j < model::kNumJoints; ++j) {
    q[7 + j] = bodies_[j + 1].getOneQ(state, 0);
    v[6 + j] = bodies_[j + 1].getOneU(state, 0);
  }
}

SimbodyLayout simbody_layout(const SimbodyRobot& r, const SimTK::State& s) {
  SimbodyLayout l;
  l.num_q = s.getNQ();
  l.num_u = s.getNU();
  l.base_q = r.body(0).getFirstQIndex(s);
  l.base_u = r.body(0).getFirstUIndex(s);
  for (int j = 0; j < model::kNumJoints; ++j) {
    l.joint_q[j] = r.body(j + 1).getFirstQIndex(s);
    l.joint_u[j] = r.body(j + 1).getFirstUIndex(s);
  }
  return l;
}

}  // namespace kuavo::sim
