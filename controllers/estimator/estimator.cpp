#include "controllers/estimator/estimator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/finite.h"

namespace kuavo::estimator {

namespace {

constexpr int kPoints = model::kNumContactPoints;

bool finite_positive(double value) { return std::isfinite(value) && value > 0.0; }

bool config_valid(const EstimatorConfig& c) {
  const double positive[] = {c.imu_process_noise_position, c.imu_process_noise_velocity,
                             c.foot_process_noise_position, c.foot_sensor_noise_position,
                             c.foot_sensor_noise_velocity, c.foot_height_sensor_noise,
                             c.non_contact_noise_scale,      c.initial_position_variance_m2,
                             c.initial_velocity_variance_m2_s2, c.gyro_cutoff_hz,
                             c.accel_cutoff_hz,              c.gravity_m_s2,
                             c.dt_min_s,                     c.dt_max_s,
                             c.gyro_max_rad_s,               c.accel_max_m_s2,
                             c.quaternion_norm_tolerance,    c.covariance_trace_limit,
                             c.horizontal_covariance_det_limit_m4};
  for (double v : positive) {
    if (!finite_positive(v)) return false;
  }
  const bool bias_ok = std::isfinite(c.initial_accel_bias_variance_m2_s4) && c.initial_accel_bias_variance_m2_s4 >= 0.0 &&
                       std::isfinite(c.accel_bias_random_walk_m2_s5) && c.accel_bias_random_walk_m2_s5 >= 0.0;
  const bool gate_ok = std::isfinite(c.contact_velocity_gate_m_s) && c.contact_velocity_gate_m_s >= 0.0;
  const bool sink_ok = c.stance_sink_m >= 0.0 && c.stance_sink_m <= kMaxStanceSink_m;  // false for NaN
  return bias_ok && gate_ok && sink_ok && std::isfinite(c.ground_height_m) && c.dt_min_s <= c.dt_max_s;
}

// A usable IMU sample: flagged valid, finite, within the sensor's ranges, and a
// quaternion close to unit norm. Returns the normalised orientation.
bool read_imu(const EstimatorConfig& c, const hal::ImuSample& imu, Eigen::Quaterniond& orientation,
              Eigen::Vector3d& gyro_rad_s, Eigen::Vector3d& accel_m_s2) {
  if (!imu.valid) return false;
  const auto& o = imu.orientation_xyzw;
  const Eigen::Quaterniond quat(o[3], o[0], o[1], o[2]);
  gyro_rad_s = Eigen::Vector3d(imu.angular_rate_rad_s.data());
  accel_m_s2 = Eigen::Vector3d(imu.acceleration_m_s2.data());
  if (!quat.coeffs().allFinite() || !gyro_rad_s.allFinite() || !accel_m_s2.allFinite()) return false;
  if (std::abs(quat.norm() - 1.0) > c.quaternion_norm_tolerance) return false;
  if (gyro_rad_s.norm() > c.gyro_max_rad_s || accel_m_s2.norm() > c.accel_max_m_s2) return false;
  orientation = quat.normalized();
  return true;
}

bool read_joints(const hal::SensorFrame& sensors, dynamics::JointVector& position_rad,
                 dynamics::JointVector& velocity_rad_s) {
  for (const hal::JointSample& j : sensors.joints) {
    if (!j.valid || !std::isfinite(j.position_rad) || !std::isfinite(j.velocity_rad_s)) return false;
  }
  for (int i = 0; i < model::kNumJoints; ++i) {
    position_rad[i] = sensors.joints[i].position_rad;
    velocity_rad_s[i] = sensors.joints[i].velocity_rad_s;
  }
  return true;
}

// Kinematics with the base origin at the world origin and no base linear
// velocity: frame positions are then "point − base" and frame velocities
// "point velocity relative to the base", both in world axes.
void relative_kinematics(const model::Model& model, EstimatorState& s) {
  s.q_relative.head<3>().setZero();
  s.q_relative.segment<4>(3) = s.orientation.coeffs();
  s.q_relative.tail<model::kNumJoints>() = s.joint_position_rad;
  s.v_relative.head<3>().setZero();
  s.v_relative.segment<3>(3) = s.gyro.value;
  s.v_relative.tail<model::kNumJoints>() = s.joint_velocity_rad_s;
  dynamics::forward_kinematics(model, s.data, s.q_relative);
  dynamics::forward_velocities(model, s.data, s.v_relative);
}

// Where a loaded sole rests: the ground plane less the stage surface's sink.
double stance_height_m(const EstimatorConfig& c) { return c.ground_height_m - c.stance_sink_m; }

// Base over the lowest corner at the stance height, corners from kinematics,
// velocity zero. Requires relative_kinematics().
void seed_filter(const model::Model& model, EstimatorState& s, const Eigen::Vector2d& base_xy_m) {
  const EstimatorConfig& c = s.config;
  double lowest_m = 0.0;
  for (int i = 0; i < kPoints; ++i) {
    const double z = dynamics::frame_position(model, s.data, i).z();
    lowest_m = (i == 0 || z < lowest_m) ? z : lowest_m;
  }
  s.x.setZero();
  s.x.head<3>() << base_xy_m, stance_height_m(c) - lowest_m;
  for (int i = 0; i < kPoints; ++i) {
    s.x.segment<3>(point_index(i, 0)) = s.x.head<3>() + dynamics::frame_position(model, s.data, i);
  }
  s.p.setZero();
  s.p.diagonal().setConstant(c.initial_position_variance_m2);
  s.p.diagonal().segment<3>(3).setConstant(c.initial_velocity_variance_m2_s2);
  s.p.diagonal().segment<3>(kBiasIndex).setConstant(c.initial_accel_bias_variance_m2_s4);
  s.initialized = true;
}

// Leju's (legged_control's) per-step process noise; swing points ×1000.
void fill_process_variance(const EstimatorConfig& c, const ContactFlags& contact, double dt_s, KfVector& q) {
  q.head<3>().setConstant(dt_s / 20.0 * c.imu_process_noise_position);
  q.segment<3>(3).setConstant(dt_s * 9.81 / 20.0 * c.imu_process_noise_velocity);
  for (int i = 0; i < kPoints; ++i) {
    const double scale = contact[i] ? 1.0 : c.non_contact_noise_scale;
    q.segment<3>(point_index(i, 0)).setConstant(scale * dt_s * c.foot_process_noise_position);
  }
  q.segment<3>(kBiasIndex).setConstant(dt_s * c.accel_bias_random_walk_m2_s5);
}

// y's relative position and velocity rows from the kinematics (they do not depend on the
// contact flags). Requires relative_kinematics().
void fill_kinematic_rows(const model::Model& model, EstimatorState& s) {
  for (int i = 0; i < kPoints; ++i) {
    s.y.segment<3>(kPositionRows + 3 * i) = dynamics::frame_position(model, s.data, i);
    s.y.segment<3>(kVelocityRows + 3 * i) = dynamics::frame_velocity(model, s.data, i).head<3>();
  }
}

// y's height rows and R from the contact flags. Stance heights are stance_height_m; a swing
// point's height is what the base estimate and kinematics say (so it does not pull the point
// down), with the ×1000 noise anyway. Requires fill_kinematic_rows().
void fill_contact_rows(EstimatorState& s, const ContactFlags& contact) {
  const EstimatorConfig& c = s.config;
  for (int i = 0; i < kPoints; ++i) {
    const double scale = contact[i] ? 1.0 : c.non_contact_noise_scale;
    s.y[kHeightRows + i] = contact[i] ? stance_height_m(c) : s.x[2] + s.y[kPositionRows + 3 * i + 2];
    s.measurement_variance.segment<3>(kPositionRows + 3 * i).setConstant(scale * c.foot_sensor_noise_position);
    s.measurement_variance.segment<3>(kVelocityRows + 3 * i).setConstant(scale * c.foot_sensor_noise_velocity);
    s.measurement_variance[kHeightRows + i] = scale * c.foot_height_sensor_noise;
  }
}

double contact_innovation_norm(const KfMeasurementVector& innovation, const ContactFlags& contact) {
  double sum = 0.0;
  for (int i = 0; i < kPoints; ++i) {
    if (!contact[i]) continue;
    sum += innovation.segment<3>(kPositionRows + 3 * i).squaredNorm() +
           innovation.segment<3>(kVelocityRows + 3 * i).squaredNorm() +
           innovation[kHeightRows + i] * innovation[kHeightRows + i];
  }
  return std::sqrt(sum);
}

// The contact gate (EstimatorConfig::contact_velocity_gate_m_s): each planned stance corner's
// velocity innovation ‖v_rel,i + v_base‖ against the predicted base velocity; corners more
// than the gate beyond the smallest one leave the measurements for this tick. Requires
// fill_kinematic_rows(). Returns the flags the measurements use.
ContactFlags gate_contact(EstimatorState& s, const ContactFlags& planned, const Eigen::Vector3d& v_base_m_s) {
  const double gate = s.config.contact_velocity_gate_m_s;
  if (!(gate > 0.0)) return planned;
  std::array<double, kPoints> innovation{};
  double smallest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kPoints; ++i) {
    if (!planned[i]) continue;
    innovation[i] = (s.y.segment<3>(kVelocityRows + 3 * i) + v_base_m_s).norm();
    smallest = std::min(smallest, innovation[i]);
  }
  ContactFlags used = planned;
  for (int i = 0; i < kPoints; ++i) {
    if (planned[i] && innovation[i] > smallest + gate) {
      used[i] = false;
      ++s.gated_corner_ticks;
    }
  }
  return used;
}

EstimatorStatus worse(EstimatorStatus a, EstimatorStatus b) { return a > b ? a : b; }

void write_output(const EstimatorState& s, EstimateOutput& out) {
  const Eigen::Matrix3d rotation = s.orientation.toRotationMatrix();
  out.q.head<3>() = s.x.head<3>();
  out.q.segment<4>(3) = s.orientation.coeffs();
  out.q.tail<model::kNumJoints>() = s.joint_position_rad;
  out.base_velocity_world_m_s = s.x.segment<3>(3);
  out.accel_bias_world_m_s2 = s.x.segment<3>(kBiasIndex);
  out.v.head<3>() = rotation.transpose() * s.x.segment<3>(3);  // conventions.h: base axes
  out.v.segment<3>(3) = s.gyro.value;                         // IMU axes are base axes
  out.v.tail<model::kNumJoints>() = s.joint_velocity_rad_s;
  out.covariance_trace = s.p.trace();
}

}  // namespace

const char* to_string(EstimatorStatus s) {
  switch (s) {
    case EstimatorStatus::kOk: return "ok";
    case EstimatorStatus::kDtClamped: return "dt outside its range, clamped";
    case EstimatorStatus::kJointsRejected: return "joint sample invalid or not finite: prediction only";
    case EstimatorStatus::kImuRejected: return "IMU sample invalid, not finite or out of range: held";
    case EstimatorStatus::kDiverged: return "filter diverged (covariance over limit or non-finite state)";
    case EstimatorStatus::kNotInitialized: return "not initialized: no usable sample yet";
  }
  return "unknown";
}

bool estimator_init(const EstimatorConfig& config, EstimatorState& state) {
  const bool ok = config_valid(config);
  state.config = ok ? config : EstimatorConfig{};
  state.x.setZero();
  state.p.setIdentity();
  state.gyro = LowPass3{};
  state.accel = LowPass3{};
  state.orientation.setIdentity();
  state.initialized = false;
  state.imu_rejects = state.joint_rejects = state.dt_clamps = state.divergences = state.horizontal_resets = 0;
  state.gated_corner_ticks = 0;
  return ok;
}

EstimatorStatus estimator_reset(const model::Model& model, EstimatorState& state, const hal::SensorFrame& sensors,
                                const Eigen::Vector2d& base_xy_m) {
  Eigen::Quaterniond orientation;
  Eigen::Vector3d gyro_rad_s, accel_m_s2;
  dynamics::JointVector position_rad, velocity_rad_s;
  if (!read_imu(state.config, sensors.imu, orientation, gyro_rad_s, accel_m_s2) ||
      !read_joints(sensors, position_rad, velocity_rad_s) || !base_xy_m.allFinite()) {
    return EstimatorStatus::kNotInitialized;
  }
  state.orientation = orientation;
  state.gyro = LowPass3{};
  state.accel = LowPass3{};
  low_pass_step_rt(state.gyro, gyro_rad_s, state.config.gyro_cutoff_hz, 0.0);
  low_pass_step_rt(state.accel, accel_m_s2, state.config.accel_cutoff_hz, 0.0);
  state.joint_position_rad = position_rad;
  state.joint_velocity_rad_s = velocity_rad_s;
  relative_kinematics(model, state);
  seed_filter(model, state, base_xy_m);
  return EstimatorStatus::kOk;
}

void estimator_output(const EstimatorState& state, EstimateOutput& out) {
  if (!state.initialized) {
    out.status = EstimatorStatus::kNotInitialized;
    return;
  }
  write_output(state, out);
  out.status = EstimatorStatus::kOk;
  out.innovation_norm = 0.0;
}

void estimator_step_rt(const model::Model& model, EstimatorState& s, const hal::SensorFrame& sensors,
                       const ContactFlags& contact, double dt_s, EstimateOutput& out) {
  const EstimatorConfig& c = s.config;
  EstimatorStatus status = EstimatorStatus::kOk;
  out.innovation_norm = 0.0;
  if (!s.initialized && estimator_reset(model, s, sensors, Eigen::Vector2d::Zero()) != EstimatorStatus::kOk) {
    out.status = EstimatorStatus::kNotInitialized;
    return;
  }

  if (!(dt_s >= c.dt_min_s && dt_s <= c.dt_max_s)) {  // also catches NaN
    dt_s = std::isfinite(dt_s) && dt_s > c.dt_max_s ? c.dt_max_s : c.dt_min_s;
    status = EstimatorStatus::kDtClamped;
    ++s.dt_clamps;
  }

  Eigen::Quaterniond orientation;
  Eigen::Vector3d gyro_rad_s, accel_m_s2;
  if (read_imu(c, sensors.imu, orientation, gyro_rad_s, accel_m_s2)) {
    s.orientation = orientation;
    low_pass_step_rt(s.gyro, gyro_rad_s, c.gyro_cutoff_hz, dt_s);
    low_pass_step_rt(s.accel, accel_m_s2, c.accel_cutoff_hz, dt_s);
  } else {
    status = worse(status, EstimatorStatus::kImuRejected);
    ++s.imu_rejects;
  }
  const bool joints_ok = read_joints(sensors, s.joint_position_rad, s.joint_velocity_rad_s);
  if (!joints_ok) {
    status = worse(status, EstimatorStatus::kJointsRejected);
    ++s.joint_rejects;
  }

  // a = R·a_imu + g: the accelerometer measures specific force.
  const Eigen::Vector3d a_world_m_s2 = s.orientation * s.accel.value - c.gravity_m_s2 * Eigen::Vector3d::UnitZ();
  fill_process_variance(c, contact, dt_s, s.process_variance);
  kf_predict_rt(s.x, s.p, a_world_m_s2, s.process_variance, dt_s);

  // The contact gate takes corners that move out of the measurements (their rows get the
  // swing noise); their points keep the stance process noise, so P stays as the plan has it.
  ContactFlags used = contact;
  if (joints_ok) {
    relative_kinematics(model, s);
    fill_kinematic_rows(model, s);
    used = gate_contact(s, contact, s.x.segment<3>(3));
    fill_contact_rows(s, used);
    kf_update_rt(s.x, s.p, s.y, s.measurement_variance, s.innovation);
    out.innovation_norm = contact_innovation_norm(s.innovation, used);
  }
  if (kf_bound_horizontal_rt(s.p, c.horizontal_covariance_det_limit_m4)) ++s.horizontal_resets;

  if (!all_finite(s.x) || !all_finite(s.p)) {
    // Cannot happen with validated inputs; if it does, re-seed around the last
    // finite base position rather than publish NaN.
    const Eigen::Vector2d xy_m = out.q.head<2>().allFinite() ? Eigen::Vector2d(out.q.head<2>()) : Eigen::Vector2d::Zero();
    relative_kinematics(model, s);
    seed_filter(model, s, xy_m);
    status = EstimatorStatus::kDiverged;
    ++s.divergences;
  }
  write_output(s, out);
  if (!(out.covariance_trace <= c.covariance_trace_limit)) {
    status = EstimatorStatus::kDiverged;
    ++s.divergences;
  }
  out.status = status;
}

}  // namespace kuavo::estimator
