// One estimator step (IMU filter, prediction, leg kinematics, 56 measurements)
// and its parts, plus the textbook batch update it replaces.
// Run pinned: taskset -c 1 build/bench/estimator_bench
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <random>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/estimator/estimator.h"

namespace {

using namespace kuavo;

constexpr double kDt_s = 0.002;

struct Fixture {
  model::Model robot;
  estimator::EstimatorState state;
  std::array<hal::SensorFrame, 16> frames;
  Fixture() {
    model::build_model(model::Variant::kS45, 55.0, robot);
    std::mt19937_64 rng(1);
    std::normal_distribution<double> n(0.0, 1.0);
    const dynamics::ConfigVector q = dynamics::neutral_configuration(robot);
    for (auto& f : frames) {
      for (int j = 0; j < model::kNumJoints; ++j) {
        f.joints[j].position_rad = q[7 + j] + 0.01 * n(rng);
        f.joints[j].velocity_rad_s = 0.05 * n(rng);
        f.joints[j].valid = true;
      }
      Eigen::Quaterniond o(1.0, 0.01 * n(rng), 0.01 * n(rng), 0.01 * n(rng));
      o.normalize();
      f.imu.orientation_xyzw = {o.x(), o.y(), o.z(), o.w()};
      f.imu.angular_rate_rad_s = {0.02 * n(rng), 0.02 * n(rng), 0.02 * n(rng)};
      f.imu.acceleration_m_s2 = {0.1 * n(rng), 0.1 * n(rng), 9.81 + 0.1 * n(rng)};
      f.imu.valid = true;
    }
    estimator::estimator_init(estimator::EstimatorConfig{}, state);
    estimator::estimator_reset(robot, state, frames[0], Eigen::Vector2d::Zero());
  }
};

Fixture& fixture() {
  static Fixture f;  // static storage, as in the firmware
  return f;
}

void BM_EstimatorStep(benchmark::State& st) {
  auto& f = fixture();
  static estimator::EstimateOutput out;
  estimator::ContactFlags contact;
  contact.fill(true);
  int i = 0;
  for (auto _ : st) {
    contact[4] = contact[5] = contact[6] = contact[7] = (i & 64) == 0;  // stance changes now and then
    estimator::estimator_step_rt(f.robot, f.state, f.frames[i++ & 15], contact, kDt_s, out);
    benchmark::DoNotOptimize(out.v[0]);
  }
}
BENCHMARK(BM_EstimatorStep);

void BM_KfPredict(benchmark::State& st) {
  auto& f = fixture();
  const Eigen::Vector3d a(0.1, 0.0, 0.0);
  for (auto _ : st) {
    estimator::kf_predict_rt(f.state.x, f.state.p, a, f.state.process_variance, kDt_s);
    benchmark::DoNotOptimize(f.state.p(0, 0));
  }
}
BENCHMARK(BM_KfPredict);

// The 56 sequential scalar updates (what the step uses).
void BM_KfUpdateSequential(benchmark::State& st) {
  auto& f = fixture();
  static estimator::KfCovariance p0;
  static estimator::KfVector x0;
  p0 = f.state.p;
  x0 = f.state.x;
  for (auto _ : st) {
    f.state.p = p0;
    f.state.x = x0;
    estimator::kf_update_rt(f.state.x, f.state.p, f.state.y, f.state.measurement_variance, f.state.innovation);
    benchmark::DoNotOptimize(f.state.p(0, 0));
  }
}
BENCHMARK(BM_KfUpdateSequential);

// Textbook batch update with fixed-size 56×56 matrices (Leju's/legged_control's
// form: S = C P Cᵀ + R, LU solves), for comparison only.
void BM_KfUpdateBatchReference(benchmark::State& st) {
  using estimator::kMeasurementDim;
  using estimator::kStateDim;
  auto& f = fixture();
  static Eigen::Matrix<double, kMeasurementDim, kStateDim> c, sc;
  static Eigen::Matrix<double, kMeasurementDim, kMeasurementDim> s;
  static Eigen::Matrix<double, kStateDim, kMeasurementDim> pct;
  static Eigen::PartialPivLU<Eigen::Matrix<double, kMeasurementDim, kMeasurementDim>> lu;
  static estimator::KfCovariance p, p0;
  static estimator::KfVector x, x0;
  c.setZero();
  for (int i = 0; i < model::kNumContactPoints; ++i) {
    for (int k = 0; k < 3; ++k) {
      c(3 * i + k, estimator::point_index(i, k)) = 1.0;
      c(3 * i + k, k) = -1.0;
      c(estimator::kVelocityRows + 3 * i + k, 3 + k) = -1.0;
    }
    c(estimator::kHeightRows + i, estimator::point_index(i, 2)) = 1.0;
  }
  p0 = f.state.p;
  x0 = f.state.x;
  for (auto _ : st) {
    p = p0;
    x = x0;
    pct.noalias() = p * c.transpose();
    s.noalias() = c * pct;
    s.diagonal() += f.state.measurement_variance;
    lu.compute(s);
    x.noalias() += pct * lu.solve(f.state.y - c * x);
    sc = lu.solve(c);
    p.noalias() -= pct * (sc * p);
    benchmark::DoNotOptimize(p(0, 0));
  }
}
BENCHMARK(BM_KfUpdateBatchReference);

}  // namespace

BENCHMARK_MAIN();
