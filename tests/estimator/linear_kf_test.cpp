// The sequential sparse update against the textbook batch Kalman update, and the
// structured prediction against A P Aᵀ + Q with dense matrices.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "controllers/estimator/linear_kf.h"

namespace kuavo::estimator {
namespace {

using Eigen::MatrixXd;

MatrixXd measurement_matrix() {
  MatrixXd c = MatrixXd::Zero(kMeasurementDim, kStateDim);
  for (int i = 0; i < model::kNumContactPoints; ++i) {
    for (int k = 0; k < 3; ++k) {
      c(kPositionRows + 3 * i + k, point_index(i, k)) = 1.0;
      c(kPositionRows + 3 * i + k, k) = -1.0;
      c(kVelocityRows + 3 * i + k, 3 + k) = -1.0;
    }
    c(kHeightRows + i, point_index(i, 2)) = 1.0;
  }
  return c;
}

struct Problem {
  KfVector x;
  KfCovariance p;
  KfMeasurementVector y, variance;
};

// Zeroes P's cross-axis entries (state i is axis i mod 3), as the estimator's P always has
// them: the diagonal blocks of a positive definite matrix, so still positive definite.
KfCovariance axis_separated(const KfCovariance& p) {
  KfCovariance out = p;
  for (int j = 0; j < kStateDim; ++j) {
    for (int i = 0; i < kStateDim; ++i) {
      if (i % 3 != j % 3) out(i, j) = 0.0;
    }
  }
  return out;
}

Problem random_problem(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.01, 2.0);
  Problem pr;
  MatrixXd a(kStateDim, kStateDim);
  for (int i = 0; i < a.size(); ++i) a(i) = n(rng);
  pr.p = a * a.transpose() / kStateDim + 0.1 * MatrixXd::Identity(kStateDim, kStateDim);
  for (int i = 0; i < kStateDim; ++i) pr.x[i] = n(rng);
  for (int i = 0; i < kMeasurementDim; ++i) {
    pr.y[i] = n(rng);
    pr.variance[i] = u(rng);
  }
  return pr;
}

TEST(EstimatorLinearKf, SequentialUpdateEqualsBatchUpdate) {
  const MatrixXd c = measurement_matrix();
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    Problem pr = random_problem(seed);
    pr.p = axis_separated(pr.p);  // kf_update_rt's precondition
    ASSERT_TRUE(kf_axes_separated(pr.p));
    // Textbook: S = C P Cᵀ + R, K = P Cᵀ S⁻¹, x += K(y − Cx), P = (I − K C) P.
    const MatrixXd s = c * pr.p * c.transpose() + MatrixXd(pr.variance.asDiagonal());
    const MatrixXd k = pr.p * c.transpose() * s.inverse();
    const Eigen::VectorXd innovation_ref = pr.y - c * pr.x;
    const Eigen::VectorXd x_ref = pr.x + k * innovation_ref;
    const MatrixXd p_ref = (MatrixXd::Identity(kStateDim, kStateDim) - k * c) * pr.p;

    KfMeasurementVector innovation;
    kf_update_rt(pr.x, pr.p, pr.y, pr.variance, innovation);
    EXPECT_LT((innovation - innovation_ref).norm(), 1e-12);
    EXPECT_LT((pr.x - x_ref).norm(), 1e-9 * (1.0 + x_ref.norm())) << "seed " << seed;
    EXPECT_LT((pr.p - p_ref).norm(), 1e-9 * (1.0 + p_ref.norm())) << "seed " << seed;
    EXPECT_EQ((pr.p - pr.p.transpose()).norm(), 0.0);  // symmetrised exactly
    EXPECT_TRUE(kf_axes_separated(pr.p)) << "seed " << seed;
  }
}

// The precondition's check sees a single cross-axis entry; prediction and the horizontal
// guard keep an axis-separated P axis-separated (exactly, as the estimator relies on).
TEST(EstimatorLinearKf, AxisSeparationIsCheckedAndPreserved) {
  Problem pr = random_problem(11);
  EXPECT_FALSE(kf_axes_separated(pr.p));
  KfCovariance p = axis_separated(pr.p);
  EXPECT_TRUE(kf_axes_separated(p));
  for (int i : {0, 4, 17, 32}) {
    for (int j : {1, 2, 6, 31}) {
      if (i % 3 == j % 3) continue;
      KfCovariance q = p;
      q(i, j) = 1e-300;
      EXPECT_FALSE(kf_axes_separated(q)) << i << ", " << j;
    }
  }
  KfVector variance;
  for (int i = 0; i < kStateDim; ++i) variance[i] = 1e-3 * (i + 1);
  for (int n = 0; n < 10; ++n) {
    kf_predict_rt(pr.x, p, Eigen::Vector3d(0.3, -0.2, 1.1), variance, 0.002);
    KfMeasurementVector innovation;
    kf_update_rt(pr.x, p, pr.y, pr.variance, innovation);
  }
  EXPECT_TRUE(kf_axes_separated(p));
  p.topLeftCorner<2, 2>() *= 1e6;
  EXPECT_TRUE(kf_bound_horizontal_rt(p, 1e-6));
  EXPECT_TRUE(kf_axes_separated(p));
}

TEST(EstimatorLinearKf, PredictionEqualsDenseForm) {
  Problem pr = random_problem(7);
  const double dt_s = 0.002;
  const Eigen::Vector3d a(0.3, -0.2, 1.1);
  KfVector q;
  for (int i = 0; i < kStateDim; ++i) q[i] = 1e-3 * (i + 1);
  MatrixXd big_a = MatrixXd::Identity(kStateDim, kStateDim);
  big_a.block(0, 3, 3, 3) = dt_s * Eigen::Matrix3d::Identity();
  // The bias enters as −b: ½dt² into the position, dt into the velocity.
  big_a.block(0, kBiasIndex, 3, 3) = -0.5 * dt_s * dt_s * Eigen::Matrix3d::Identity();
  big_a.block(3, kBiasIndex, 3, 3) = -dt_s * Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, kStateDim, 3> b = Eigen::Matrix<double, kStateDim, 3>::Zero();
  b.topRows<3>() = 0.5 * dt_s * dt_s * Eigen::Matrix3d::Identity();
  b.middleRows<3>(3) = dt_s * Eigen::Matrix3d::Identity();
  const Eigen::VectorXd x_ref = big_a * pr.x + b * a;
  const MatrixXd p_ref = big_a * pr.p * big_a.transpose() + MatrixXd(q.asDiagonal());
  kf_predict_rt(pr.x, pr.p, a, q, dt_s);
  EXPECT_LT((pr.x - x_ref).norm(), 1e-13);
  EXPECT_LT((pr.p - p_ref).norm(), 1e-12);
}

TEST(EstimatorLinearKf, HorizontalGuardDecorrelatesAndShrinksOnlyPastTheLimit) {
  Problem pr = random_problem(9);
  KfCovariance p = pr.p * 1e-4;  // det(P_xy) well below 1e-6
  const KfCovariance small = p;
  EXPECT_FALSE(kf_bound_horizontal_rt(p, 1e-6));
  EXPECT_EQ((p - small).norm(), 0.0);
  p = pr.p;  // det(P_xy) of order 1e-2
  const KfCovariance big = p;
  EXPECT_TRUE(kf_bound_horizontal_rt(p, 1e-6));
  EXPECT_LT((p.topLeftCorner<2, 2>() - big.topLeftCorner<2, 2>() / 10.0).norm(), 1e-15);
  EXPECT_EQ((p.topRightCorner<2, kStateDim - 2>().norm()), 0.0);
  EXPECT_EQ((p.bottomLeftCorner<kStateDim - 2, 2>().norm()), 0.0);
  const KfCovariance diff = p - big;
  EXPECT_EQ((diff.bottomRightCorner<kStateDim - 2, kStateDim - 2>().norm()), 0.0);
}

}  // namespace
}  // namespace kuavo::estimator
