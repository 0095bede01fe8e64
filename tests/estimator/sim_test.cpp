// The estimator against the simulator's ground truth: the Simbody plant standing
// under the standing controller, sensors from the seeded MTi-class sensor model
// (noise, bias, 0.2° tilt error), a 10 N·s push at 2 s. The estimator runs
// beside the controller (which does not use it) and is compared with the truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "controllers/estimator/estimator.h"
#include "controllers/standing/standing_controller.h"
#include "sim/plant.h"
#include "sim/sensor_model.h"

namespace kuavo::test {
namespace {

using estimator::EstimatorStatus;

constexpr double kDt_s = 0.002;
constexpr estimator::ContactFlags kAllContact = {true, true, true, true, true, true, true, true};

model::Model g_robot;
control::StandingState g_controller;
estimator::EstimatorState g_state;

struct ErrorStats {
  double sum_sq = 0.0, max = 0.0;
  int n = 0;
  void add(double e) {
    sum_sq += e * e;
    max = std::max(max, e);
    ++n;
  }
  double rms() const { return n > 0 ? std::sqrt(sum_sq / n) : 0.0; }
};

struct RunResult {
  ErrorStats velocity_standing, velocity_push, velocity_base_axes;
  double drift_xy_m = 0.0, drift_z_m = 0.0, max_drift_xy_m = 0.0, max_drift_z_m = 0.0;
  double peak_speed_m_s = 0.0;
  int bad_status = 0;
  // At the end: the filter's acceleration bias and what the IMU's tilt error really tips
  // into the world-frame acceleration, (R_measured R_trueᵀ − I)·g·ẑ, from the sensor frame
  // and the plant's truth (horizontal components).
  Eigen::Vector2d bias_m_s2 = Eigen::Vector2d::Zero(), tilt_leak_m_s2 = Eigen::Vector2d::Zero();
  ErrorStats velocity_late;  // the last 2 s
};

// Stands duration_s with a push at 2 s; velocity errors in world axes, split into
// standing (0.5–2 s) and push (2–4 s) windows.
RunResult run(const sim::GroundParams& ground, const sim::Vec3& push_force_N, double duration_s, std::uint64_t seed,
              const estimator::EstimatorConfig& config = {}, const sim::SensorNoise& noise = {}) {
  EXPECT_EQ(model::build_model(model::Variant::kS45, 55.0, g_robot), model::ModelError::kOk);
  control::standing_init(g_robot, control::StandingConfig{}, g_controller);
  sim::PlantConfig plant_config;
  plant_config.ground = ground;
  sim::Plant plant(g_robot, plant_config);
  dynamics::ConfigVector q0 = dynamics::neutral_configuration(g_robot);
  q0.tail<model::kNumJoints>() = g_controller.pose_rad;
  control::place_on_ground(g_robot, g_controller.data, q0);
  plant.reset(q0, dynamics::VelocityVector::Zero());
  sim::Push push;
  push.start_s = 2.0;
  push.duration_s = 0.1;
  push.force_N = push_force_N;
  plant.set_push(push);

  sim::SensorModel sensors(seed, noise);
  hal::SensorFrame frame;
  hal::CommandFrame command;
  sensors.sample(plant.truth(), 0, frame);
  EXPECT_TRUE(estimator::estimator_init(config, g_state));
  EXPECT_EQ(estimator::estimator_reset(g_robot, g_state, frame, q0.head<2>()), EstimatorStatus::kOk);

  RunResult r;
  estimator::EstimateOutput out;
  const int steps = static_cast<int>(std::lround(duration_s / kDt_s));
  for (int n = 0; n < steps; ++n) {
    const double t_s = n * kDt_s;
    sensors.sample(plant.truth(), static_cast<hal::TimeNs>(n) * 2'000'000, frame);
    control::standing_step_rt(g_robot, g_controller, frame, command);
    plant.set_command(command);
    estimator::estimator_step_rt(g_robot, g_state, frame, kAllContact, kDt_s, out);
    if (out.status != EstimatorStatus::kOk) ++r.bad_status;

    // The truth the sensors sampled, world axes.
    const sim::PlantTruth& truth = plant.truth();
    const Eigen::Matrix3d rotation = Eigen::Quaterniond(truth.q.segment<4>(3)).toRotationMatrix();
    const Eigen::Vector3d v_world_m_s = rotation * truth.v.head<3>();
    const double v_error = (out.base_velocity_world_m_s - v_world_m_s).norm();
    if (t_s >= 0.5 && t_s < 2.0) r.velocity_standing.add(v_error);
    if (t_s >= 2.0 && t_s < 4.0) r.velocity_push.add(v_error);
    if (t_s >= 0.5) r.velocity_base_axes.add((out.v.head<3>() - truth.v.head<3>()).norm());
    r.peak_speed_m_s = std::max(r.peak_speed_m_s, v_world_m_s.norm());
    if (t_s >= duration_s - 2.0) r.velocity_late.add(v_error);
    const auto& o = frame.imu.orientation_xyzw;
    const Eigen::Matrix3d measured = Eigen::Quaterniond(o[3], o[0], o[1], o[2]).normalized().toRotationMatrix();
    const Eigen::Vector3d leak = (measured * rotation.transpose() - Eigen::Matrix3d::Identity()) *
                                 Eigen::Vector3d(0.0, 0.0, model::kGravity_m_s2);
    r.tilt_leak_m_s2 = leak.head<2>();
    r.bias_m_s2 = out.accel_bias_world_m_s2.head<2>();
    const Eigen::Vector3d p_error = out.q.head<3>() - truth.q.head<3>();
    r.drift_xy_m = p_error.head<2>().norm();
    r.drift_z_m = std::abs(p_error.z());
    r.max_drift_xy_m = std::max(r.max_drift_xy_m, r.drift_xy_m);
    r.max_drift_z_m = std::max(r.max_drift_z_m, r.drift_z_m);

    if (plant.advance(kDt_s) != sim::PlantError::kOk) {
      ADD_FAILURE() << plant.last_error();
      break;
    }
  }
  std::printf(
      "%s push (%.0f, %.0f) N: peak speed %.3f m/s | v err RMS standing %.4f (max %.4f), push %.4f (max %.4f) m/s, "
      "base axes %.4f, last 2 s %.4f | drift at %.0f s: xy %.4f z %.4f m (max xy %.4f z %.4f) | accel bias (%.4f, %.4f), "
      "tilt leak (%.4f, %.4f) m/s2\n",
      ground.name, push_force_N.x(), push_force_N.y(), r.peak_speed_m_s, r.velocity_standing.rms(),
      r.velocity_standing.max, r.velocity_push.rms(), r.velocity_push.max, r.velocity_base_axes.rms(),
      r.velocity_late.rms(), duration_s, r.drift_xy_m, r.drift_z_m, r.max_drift_xy_m, r.max_drift_z_m, r.bias_m_s2.x(),
      r.bias_m_s2.y(), r.tilt_leak_m_s2.x(), r.tilt_leak_m_s2.y());
  return r;
}

TEST(EstimatorAgainstSimulator, StandingAndPushOnFloor) {
  // Measured (seed 1): v RMS 0.012 m/s standing, 0.020 m/s over the push (peak
  // speed 0.25 m/s); drift 14 mm xy after 6 s, ≤ 1.3 mm z. The xy drift is the
  // price of Leju's horizontal-covariance guard (0.7 mm with it disabled, at the
  // cost of an unbounded P). The standing velocity error is mostly a
  // bias: the sensor model's 0.2° tilt error leaks g·sin(0.2°) ≈ 0.03 m/s² into
  // the horizontal acceleration, which Leju's noise values correct only slowly.
  const RunResult r = run(sim::kFloor, sim::Vec3(100.0, 0.0, 0.0), 6.0, 1);
  EXPECT_EQ(r.bad_status, 0);
  EXPECT_GT(r.peak_speed_m_s, 0.15);  // it was a real push
  EXPECT_LT(r.velocity_standing.rms(), 0.02);
  EXPECT_LT(r.velocity_push.rms(), 0.035);
  EXPECT_LT(r.velocity_base_axes.rms(), 0.025);
  EXPECT_LT(r.max_drift_xy_m, 0.025);
  EXPECT_LT(r.max_drift_z_m, 0.005);
}

TEST(EstimatorAgainstSimulator, StandingAndPushOnCarpet) {
  // The carpet lets the soles sink 1–2 cm while the stance-height measurement
  // says 0: the height estimate carries that offset, velocity is unaffected.
  const RunResult r = run(sim::kCarpet, sim::Vec3(-100.0, 0.0, 0.0), 6.0, 1);
  EXPECT_EQ(r.bad_status, 0);
  EXPECT_GT(r.peak_speed_m_s, 0.15);
  EXPECT_LT(r.velocity_standing.rms(), 0.02);
  EXPECT_LT(r.velocity_push.rms(), 0.035);
  EXPECT_LT(r.max_drift_xy_m, 0.025);
  EXPECT_LT(r.max_drift_z_m, 0.03);
}

TEST(EstimatorAgainstSimulator, StanceSinkPutsTheBaseAtItsHeightOnCarpet) {
  // The oracle is the carpet's law, f = k·d^n: the standing robot's weight over its 8 sole
  // corners sinks each d = (m·g / 8k)^(1/n), 1.50 cm. With stance_sink_m = d the height
  // estimate is the plant's; without it the base reads about d high. 3 s standing, no push.
  const sim::GroundParams& g = sim::kCarpet;
  const double sink_m = std::pow(55.0 * model::kGravity_m_s2 / 8.0 / g.normal_stiffness, 1.0 / g.normal_exponent);
  estimator::EstimatorConfig sunk;
  sunk.stance_sink_m = sink_m;
  const RunResult surface = run(g, sim::Vec3::Zero(), 3.0, 1);
  const RunResult told = run(g, sim::Vec3::Zero(), 3.0, 1, sunk);
  std::printf("carpet sink %.4f m: z error at 3 s %.4f m at the surface, %.4f m with the sink\n", sink_m,
              surface.drift_z_m, told.drift_z_m);
  EXPECT_EQ(told.bad_status, 0);
  EXPECT_GT(surface.drift_z_m, 0.7 * sink_m);
  EXPECT_LT(told.drift_z_m, 0.2 * sink_m);
  EXPECT_LT(told.velocity_standing.rms(), 0.02);
}

TEST(EstimatorAgainstSimulator, StandingErrorIsTheImuTiltBias) {
  // Without the 0.2° tilt error the standing velocity error all but vanishes
  // (measured 0.6 mm/s RMS against 12 mm/s with it): the filter itself is not
  // the floor of the error above. (Trusting the kinematic velocity more,
  // foot_sensor_noise_velocity 0.01 instead of Leju's 1.0, gave 2.2 mm/s with
  // the tilt error; the defaults stay Leju's.) No push: 3 s standing.
  sim::SensorNoise no_tilt;
  no_tilt.tilt_bias_rad = 0.0;
  const RunResult r = run(sim::kFloor, sim::Vec3::Zero(), 3.0, 1, {}, no_tilt);
  EXPECT_EQ(r.bad_status, 0);
  EXPECT_LT(r.velocity_standing.rms(), 0.002);
  EXPECT_LT(r.max_drift_xy_m, 0.005);
}

TEST(EstimatorAgainstSimulator, AccelerationBiasStateTakesUpTheTiltError) {
  // 8 s standing (seed 1, whose tilt error leaks 0.07 m/s² into the horizontal): the
  // filter's bias converges on the leak computed from the true and the measured
  // orientation, and the velocity error of the last 2 s falls to a fraction of what the
  // same filter without the bias state (Leju's) leaves.
  const RunResult with = run(sim::kFloor, sim::Vec3::Zero(), 8.0, 1);
  estimator::EstimatorConfig leju;
  leju.initial_accel_bias_variance_m2_s4 = leju.accel_bias_random_walk_m2_s5 = 0.0;
  const RunResult without = run(sim::kFloor, sim::Vec3::Zero(), 8.0, 1, leju);
  EXPECT_EQ(with.bad_status, 0);
  ASSERT_GT(with.tilt_leak_m_s2.norm(), 0.03);  // the case is real
  EXPECT_LT((with.bias_m_s2 - with.tilt_leak_m_s2).norm(), 0.2 * with.tilt_leak_m_s2.norm());
  EXPECT_EQ(without.bias_m_s2.norm(), 0.0);
  EXPECT_LT(with.velocity_late.rms(), 0.35 * without.velocity_late.rms());
  EXPECT_LT(with.max_drift_xy_m, without.max_drift_xy_m);
}

}  // namespace
}  // namespace kuavo::test
