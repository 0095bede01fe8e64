// Derivative quantities against central finite differences along q ⊕ t·v
// (integrate() moves the base on the screw of its constant local twist, which is
// exactly the motion the analytic J̇·v and Ȧ·v assume).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "tests/dynamics/random_state.h"

namespace kuavo::test {
namespace {

using dynamics::ConfigVector;
using dynamics::VelocityVector;
using Vec6 = Eigen::Matrix<double, 6, 1>;

constexpr double kStep = 1e-6;
constexpr double kFdTolerance = 2e-7;  // central differences: O(h²) truncation + O(eps/h) rounding
constexpr int kSamples = 50;

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

class FiniteDifference : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, robot_), model::ModelError::kOk); }
  model::Model robot_;
  dynamics::Data data_;
};

TEST_F(FiniteDifference, FrameJacobiansMatchPoseDerivative) {
  std::mt19937_64 rng(11);
  double worst = 0;
  for (int n = 0; n < kSamples; ++n) {
    const ConfigVector q = random_configuration(robot_, rng);
    const VelocityVector v = random_velocity(rng);
    for (int f = 0; f < model::kNumFrames; ++f) {
      dynamics::forward_kinematics(robot_, data_, dynamics::integrate(q, v, kStep));
      const Eigen::Vector3d p_plus = dynamics::frame_position(robot_, data_, f);
      const Eigen::Matrix3d r_plus = dynamics::frame_rotation(robot_, data_, f);
      dynamics::forward_kinematics(robot_, data_, dynamics::integrate(q, v, -kStep));
      const Eigen::Vector3d p_minus = dynamics::frame_position(robot_, data_, f);
      const Eigen::Matrix3d r_minus = dynamics::frame_rotation(robot_, data_, f);
      Vec6 fd;
      fd.head<3>() = (p_plus - p_minus) / (2 * kStep);
      fd.tail<3>() = rotation_log(r_plus * r_minus.transpose()) / (2 * kStep);
      dynamics::forward_kinematics(robot_, data_, q);
      dynamics::FrameJacobian j;
      dynamics::frame_jacobian(robot_, data_, f, j);
      worst = std::max(worst, relative_error(Vec6(j * v), fd));
    }
  }
  EXPECT_LE(worst, kFdTolerance);
}

TEST_F(FiniteDifference, JdotTimesVMatchesJacobianRate) {
  std::mt19937_64 rng(12);
  double worst = 0;
  for (int n = 0; n < kSamples; ++n) {
    const ConfigVector q = random_configuration(robot_, rng);
    const VelocityVector v = random_velocity(rng);
    for (int f = 0; f < model::kNumFrames; ++f) {
      dynamics::FrameJacobian j_plus, j_minus;
      dynamics::forward_kinematics(robot_, data_, dynamics::integrate(q, v, kStep));
      dynamics::frame_jacobian(robot_, data_, f, j_plus);
      dynamics::forward_kinematics(robot_, data_, dynamics::integrate(q, v, -kStep));
      dynamics::frame_jacobian(robot_, data_, f, j_minus);
      const Vec6 fd = (j_plus - j_minus) * v / (2 * kStep);
      dynamics::forward_kinematics(robot_, data_, q);
      dynamics::forward_velocities(robot_, data_, v);
      dynamics::bias_accelerations(robot_, data_);
      worst = std::max(worst, relative_error(dynamics::frame_bias_acceleration(robot_, data_, f), fd));
    }
  }
  EXPECT_LE(worst, 10 * kFdTolerance);
}

TEST_F(FiniteDifference, CentroidalMatrixRateAndComJacobian) {
  std::mt19937_64 rng(13);
  double worst_adot = 0, worst_com = 0;
  for (int n = 0; n < kSamples; ++n) {
    const ConfigVector q = random_configuration(robot_, rng);
    const VelocityVector v = random_velocity(rng);
    dynamics::compute_all_terms(robot_, data_, dynamics::integrate(q, v, kStep), v);
    const Vec6 h_plus = data_.centroidal_matrix * v;
    const Eigen::Vector3d c_plus = data_.com_m;
    dynamics::compute_all_terms(robot_, data_, dynamics::integrate(q, v, -kStep), v);
    const Vec6 h_minus = data_.centroidal_matrix * v;
    const Eigen::Vector3d c_minus = data_.com_m;
    dynamics::compute_all_terms(robot_, data_, q, v);
    worst_adot = std::max(worst_adot, relative_error(data_.centroidal_bias, Vec6((h_plus - h_minus) / (2 * kStep))));
    dynamics::ComJacobian jc;
    dynamics::com_jacobian(data_, jc);
    worst_com = std::max(worst_com, relative_error(Eigen::Vector3d(jc * v), Eigen::Vector3d((c_plus - c_minus) / (2 * kStep))));
    // The separate centroidal pass must agree with the fused one.
    const Vec6 fused = data_.centroidal_bias;
    dynamics::centroidal_dynamics(robot_, data_);
    EXPECT_LE(relative_error(data_.centroidal_bias, fused), 1e-12);
  }
  EXPECT_LE(worst_adot, 10 * kFdTolerance);
  EXPECT_LE(worst_com, kFdTolerance);
}

// Closed-form case: one rigid body falling freely has b = [-m Rᵀ g; 0] on the
// base and the centroidal momentum of a point mass at the CoM.
TEST_F(FiniteDifference, ClosedFormTotalsAndGravityWrench) {
  std::mt19937_64 rng(14);
  for (int n = 0; n < 20; ++n) {
    const ConfigVector q = random_configuration(robot_, rng);
    dynamics::compute_all_terms(robot_, data_, q, VelocityVector::Zero());
    EXPECT_NEAR(data_.total_mass_kg, 55.0, 1e-12);
    // With v = 0, b is pure gravity: the base force is m·g in base axes, the base
    // moment is (c - p_base) × m·g in base axes.
    const Eigen::Matrix3d r = Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix();
    const Eigen::Vector3d weight(0, 0, 55.0 * model::kGravity_m_s2);
    EXPECT_LE(relative_error(Eigen::Vector3d(data_.tau.head<3>()), Eigen::Vector3d(r.transpose() * weight)), 1e-12);
    const Eigen::Vector3d moment = r.transpose() * ((data_.com_m - q.head<3>()).cross(weight));
    EXPECT_LE(relative_error(Eigen::Vector3d(data_.tau.segment<3>(3)), moment), 1e-12);
    // Mass matrix: symmetric positive definite; its base linear block is m·I.
    EXPECT_LE(relative_error(data_.mass_matrix, dynamics::MassMatrix(data_.mass_matrix.transpose())), 1e-15);
    EXPECT_GT(data_.mass_matrix.selfadjointView<Eigen::Lower>().eigenvalues().minCoeff(), 0.0);
    EXPECT_LE(relative_error(Eigen::Matrix3d(data_.mass_matrix.topLeftCorner<3, 3>()),
                             Eigen::Matrix3d(55.0 * Eigen::Matrix3d::Identity())), 1e-14);
  }
}

}  // namespace
}  // namespace kuavo::test
