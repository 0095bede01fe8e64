// Our heap-free rigid-body algorithms against Simbody, an independent
// implementation, on the same robot (built from the same generated tables).
#include <gtest/gtest.h>

#include <memory>

#include "sim/simbody_model.h"
#include "tests/dynamics/random_state.h"

namespace kuavo::test {
namespace {

using dynamics::ConfigVector;
using dynamics::VelocityVector;
using Mat = Eigen::Matrix<double, model::kNv, model::kNv>;

constexpr int kSamples = 200;
constexpr double kTolerance = 1e-9;  // relative, per the issue

class SimbodyOracle : public ::testing::TestWithParam<model::Variant> {
 protected:
  void SetUp() override {
    ASSERT_EQ(model::build_model(GetParam(), 55.0, robot_), model::ModelError::kOk);
    sim_ = std::make_unique<sim::SimbodyRobot>(robot_, true);
    state_ = sim_->system().getDefaultState();
  }

  // u_sim = T v (see SimbodyRobot).
  Mat speed_map(const ConfigVector& q) const {
    const Eigen::Matrix3d r = Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix();
    Mat t = Mat::Zero();
    const int b = sim_->base_u_index();
    t.block<3, 3>(b, 3) = r;  // Simbody: angular velocity in ground first
    t.block<3, 3>(b + 3, 0) = r;
    for (int j = 0; j < model::kNumJoints; ++j) t(sim_->u_index_of_joint(j), 6 + j) = 1.0;
    return t;
  }
  // d/dt(T) v: for v̇ = 0 the base's ground-frame linear speed still turns with it.
  Eigen::Matrix<double, model::kNv, 1> speed_map_rate_times_v(const ConfigVector& q, const VelocityVector& v) const {
    const Eigen::Matrix3d r = Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix();
    Eigen::Matrix<double, model::kNv, 1> out = Eigen::Matrix<double, model::kNv, 1>::Zero();
    const Eigen::Vector3d w = r * v.segment<3>(3), lin = r * v.head<3>();
    out.segment<3>(sim_->base_u_index() + 3) = w.cross(lin);
    return out;
  }
  static Eigen::MatrixXd to_eigen(const SimTK::Matrix& m) {
    Eigen::MatrixXd out(m.nrow(), m.ncol());
    for (int i = 0; i < m.nrow(); ++i)
      for (int j = 0; j < m.ncol(); ++j) out(i, j) = m(i, j);
    return out;
  }
  static Eigen::VectorXd to_eigen(const SimTK::Vector& v) {
    Eigen::VectorXd out(v.size());
    for (int i = 0; i < v.size(); ++i) out[i] = v[i];
    return out;
  }
  static Eigen::Matrix<double, 6, 1> linear_first(const SimTK::SpatialVec& s) {
    Eigen::Matrix<double, 6, 1> out;
    out << s[1][0], s[1][1], s[1][2], s[0][0], s[0][1], s[0][2];
    return out;
  }

  model::Model robot_;
  std::unique_ptr<sim::SimbodyRobot> sim_;
  SimTK::State state_;
  dynamics::Data data_;
};

TEST_P(SimbodyOracle, MassMatrixBiasForcesAndInverseDynamics) {
  std::mt19937_64 rng(20261121);
  double worst_m = 0, worst_b = 0, worst_id = 0;
  for (int n = 0; n < kSamples; ++n) {
    const ConfigVector q = random_configuration(robot_, rng);
    const VelocityVector v = random_velocity(rng);
    const VelocityVector a = random_velocity(rng, 3.0);
    sim_->set_state(state_, q, v);
    const Mat t = speed_map(q);

    dynamics::forward_kinematics(robot_, data_, q);
    dynamics::forward_velocities(robot_, data_, v);
    dynamics::crba(robot_, data_);
    SimTK::Matrix m_sim;
    sim_->matter().calcM(state_, m_sim);
    const Mat m_expected = t.transpose() * to_eigen(m_sim) * t;
    worst_m = std::max(worst_m, relative_error(data_.mass_matrix, m_expected));

    sim_->system().realize(state_, SimTK::Stage::Dynamics);
    const auto& gravity = sim_->system().getRigidBodyForces(state_, SimTK::Stage::Dynamics);
    const SimTK::Vector mobility(model::kNv, 0.0);
    for (int with_accel = 0; with_accel < 2; ++with_accel) {
      const VelocityVector acc = with_accel ? a : VelocityVector::Zero();
      const Eigen::VectorXd udot = t * acc + speed_map_rate_times_v(q, v);
      SimTK::Vector known_udot(model::kNv), residual;
      for (int i = 0; i < model::kNv; ++i) known_udot[i] = udot[i];
      sim_->matter().calcResidualForceIgnoringConstraints(state_, mobility, gravity, known_udot, residual);
      const VelocityVector tau_expected = t.transpose() * to_eigen(residual);
      dynamics::rnea(robot_, data_, acc, true);
      (with_accel ? worst_id : worst_b) =
          std::max(with_accel ? worst_id : worst_b, relative_error(data_.tau, tau_expected));
    }
  }
  std::printf("worst M %.3g b %.3g id %.3g\n", worst_m, worst_b, worst_id);
  EXPECT_LE(worst_m, kTolerance);
  EXPECT_LE(worst_b, kTolerance);
  EXPECT_LE(worst_id, kTolerance);
}

TEST_P(SimbodyOracle, PosesComMomentumJacobiansAndBias) {
  std::mt19937_64 rng(7);
  double worst_pose = 0, worst_com = 0, worst_h = 0, worst_j = 0, worst_jdot = 0, worst_mass = 0;
  for (int n = 0; n < kSamples; ++n) {
    const ConfigVector q = random_configuration(robot_, rng);
    const VelocityVector v = random_velocity(rng);
    sim_->set_state(state_, q, v);
    sim_->system().realize(state_, SimTK::Stage::Acceleration);
    const Mat t = speed_map(q);
    dynamics::compute_all_terms(robot_, data_, q, v);
    dynamics::bias_accelerations(robot_, data_);

    for (int b = 0; b < model::kNumBodies; ++b) {
      const SimTK::Transform& x = sim_->body(b).getBodyTransform(state_);
      Eigen::Matrix3d r;
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) r(i, k) = x.R().asMat33()(i, k);
      const Eigen::Vector3d p(x.p()[0], x.p()[1], x.p()[2]);
      worst_pose = std::max({worst_pose, relative_error(data_.rotation[b], r), relative_error(data_.position_m[b], p)});
    }
    const SimTK::Vec3 com = sim_->matter().calcSystemMassCenterLocationInGround(state_);
    worst_com = std::max(worst_com, relative_error(data_.com_m, Eigen::Vector3d(com[0], com[1], com[2])));
    worst_mass = std::max(worst_mass, std::abs(data_.total_mass_kg - sim_->matter().calcSystemMass(state_)));
    const Eigen::Matrix<double, 6, 1> h = data_.centroidal_matrix * v;
    worst_h = std::max(worst_h, relative_error(h, linear_first(sim_->matter().calcSystemCentralMomentum(state_))));

    for (int f = 0; f < model::kNumFrames; ++f) {
      const model::Frame& frame = robot_.frames[f];
      const SimTK::Vec3 station(frame.position_m.x(), frame.position_m.y(), frame.position_m.z());
      const SimTK::MobilizedBodyIndex mbx = sim_->body(frame.body).getMobilizedBodyIndex();
      SimTK::Matrix j_sim;
      sim_->matter().calcFrameJacobian(state_, mbx, station, j_sim);
      Eigen::Matrix<double, 6, model::kNv> j_expected;
      const Eigen::MatrixXd j_e = to_eigen(j_sim);
      j_expected.topRows<3>() = j_e.bottomRows(3) * t;
      j_expected.bottomRows<3>() = j_e.topRows(3) * t;
      dynamics::FrameJacobian j;
      dynamics::frame_jacobian(robot_, data_, f, j);
      worst_j = std::max(worst_j, relative_error(j, j_expected));

      const Eigen::Matrix<double, 6, 1> bias_sim = linear_first(sim_->matter().calcBiasForFrameJacobian(state_, mbx, station));
      const Eigen::Matrix<double, 6, 1> jdot_v_expected = bias_sim + j_expected * (t.transpose() * speed_map_rate_times_v(q, v));
      worst_jdot = std::max(worst_jdot, relative_error(dynamics::frame_bias_acceleration(robot_, data_, f), jdot_v_expected));
    }
  }
  std::printf("worst pose %.3g com %.3g h %.3g J %.3g Jdot %.3g\n", worst_pose, worst_com, worst_h, worst_j, worst_jdot);
  EXPECT_LE(worst_pose, kTolerance);
  EXPECT_LE(worst_com, kTolerance);
  EXPECT_LE(worst_mass, 1e-12);
  EXPECT_LE(worst_h, kTolerance);
  EXPECT_LE(worst_j, kTolerance);
  EXPECT_LE(worst_jdot, kTolerance);
}

INSTANTIATE_TEST_SUITE_P(BothVariants, SimbodyOracle,
                         ::testing::Values(model::Variant::kS45, model::Variant::kS42),
                         [](const auto& info) { return std::string(model::to_string(info.param)); });

}  // namespace
}  // namespace kuavo::test
