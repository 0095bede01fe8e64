#include "sim/sensor_model.h"

#include <Eigen/Geometry>
#include <cmath>

namespace kuavo::sim {

SensorModel::SensorModel(std::uint64_t seed, const SensorNoise& noise) : rng_(seed), noise_(noise) {
  gyro_bias_ = Eigen::Vector3d(gauss(noise_.gyro_bias_rad_s), gauss(noise_.gyro_bias_rad_s), gauss(noise_.gyro_bias_rad_s));
  accel_bias_ = Eigen::Vector3d(gauss(noise_.accel_bias_m_s2), gauss(noise_.accel_bias_m_s2), gauss(noise_.accel_bias_m_s2));
  tilt_bias_ = Eigen::Vector3d(gauss(noise_.tilt_bias_rad), gauss(noise_.tilt_bias_rad), 0.0);
}

double SensorModel::gauss(double sigma) { return sigma * normal_(rng_); }

void SensorModel::sample(const PlantTruth& truth, hal::TimeNs stamp_ns, hal::SensorFrame& out) {
  for (int j = 0; j < model::kNumJoints; ++j) {
    hal::JointSample& s = out.joints[j];
    const double res = noise_.encoder_resolution_rad;
    s.position_rad = res > 0.0 ? std::round(truth.q[7 + j] / res) * res : truth.q[7 + j];
    s.velocity_rad_s = truth.v[6 + j] + gauss(noise_.joint_velocity_noise_rad_s);
    s.torque_Nm = truth.joint_torque_Nm[j];
    s.stamp_ns = stamp_ns;
    s.valid = true;
  }
  // Orientation: the true one rotated by a small random tilt.
  const Eigen::Quaterniond q_true(truth.q[6], truth.q[3], truth.q[4], truth.q[5]);
  const Eigen::Vector3d tilt = tilt_bias_ + Eigen::Vector3d(gauss(noise_.tilt_noise_rad), gauss(noise_.tilt_noise_rad), 0.0);
  Eigen::Quaterniond q_meas = q_true;
  if (tilt.norm() > 0.0) q_meas = Eigen::Quaterniond(Eigen::AngleAxisd(tilt.norm(), tilt.normalized())) * q_true;
  q_meas.normalize();
  hal::ImuSample& imu = out.imu;
  imu.orientation_xyzw = {q_meas.x(), q_meas.y(), q_meas.z(), q_meas.w()};
  for (int k = 0; k < 3; ++k) {
    imu.angular_rate_rad_s[k] = truth.v[3 + k] + gyro_bias_[k] + gauss(noise_.gyro_noise_rad_s);
    imu.acceleration_m_s2[k] = truth.base_specific_force_m_s2[k] + accel_bias_[k] + gauss(noise_.accel_noise_m_s2);
  }
  if (errors_ != nullptr) {
    for (int j = 0; j < model::kNumJoints; ++j) out.joints[j].position_rad += errors_->encoder_offset_rad[j];
    for (int k = 0; k < 3; ++k) {
      imu.angular_rate_rad_s[k] = errors_->gyro_scale[k] * imu.angular_rate_rad_s[k] + errors_->gyro_bias_rad_s[k];
      imu.acceleration_m_s2[k] = errors_->accel_scale[k] * imu.acceleration_m_s2[k] + errors_->accel_bias_m_s2[k];
    }
  }
  imu.stamp_ns = stamp_ns;
  imu.valid = true;
}

}  // namespace kuavo::sim
