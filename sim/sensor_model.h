// Sensors as the controller sees them: joint encoders quantized, an IMU with the
// Xsens MTi-600-class noise and bias of FACTS.md §5.3. All randomness comes from
// one generator seeded by the caller, so a seed fixes every sample.
#pragma once

#include <cstdint>
#include <random>

#include "controllers/hal/types.h"
#include "sim/perturbation.h"
#include "sim/plant.h"

namespace kuavo::sim {

struct SensorNoise {
  // 17-bit motor encoder behind a 10:1 gear, the coarsest of the 4Pro's joints (FACTS.md §5.1).
  double encoder_resolution_rad = 2.0 * 3.14159265358979323846 / (131072.0 * 10.0);
  double joint_velocity_noise_rad_s = 0.002;
  // MTi: gyro noise density 0.007 °/s/√Hz, accelerometer 60 µg/√Hz, over a 250 Hz band (500 Hz sampling).
  double gyro_noise_rad_s = 0.007 * 3.14159265358979323846 / 180.0 * 15.8;
  double accel_noise_m_s2 = 60e-6 * 9.81 * 15.8;
  // Bias stability: gyro 8 °/h, accelerometer 15 µg; drawn once per run.
  double gyro_bias_rad_s = 8.0 / 3600.0 * 3.14159265358979323846 / 180.0;
  double accel_bias_m_s2 = 15e-6 * 9.81;
  // Orientation: the 0.2° roll/pitch accuracy is an error that wanders slowly, not
  // sample-to-sample noise (the MTi's filter output is smooth): a per-run tilt
  // error of that size plus a little white noise.
  double tilt_bias_rad = 0.2 * 3.14159265358979323846 / 180.0;
  double tilt_noise_rad = 0.01 * 3.14159265358979323846 / 180.0;
};

class SensorModel {
 public:
  SensorModel(std::uint64_t seed, const SensorNoise& noise = SensorNoise{});
  // Fills the frame from the plant's true state at stamp_ns.
  void sample(const PlantTruth& truth, hal::TimeNs stamp_ns, hal::SensorFrame& out);
  // Fixed errors on top of the noise (sim/perturbation.h): encoder offsets, IMU bias and
  // scale (reading = scale·(what the noise model reads) + bias). nullptr: none.
  // Must outlive the model's use.
  void set_errors(const SensorErrors* errors) { errors_ = errors; }
  // A fixed roll/pitch error added to the drawn tilt bias (tests).
  void add_tilt(double roll_rad, double pitch_rad) { tilt_bias_ += Eigen::Vector3d(roll_rad, pitch_rad, 0.0); }

 private:
  double gauss(double sigma);
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  SensorNoise noise_;
  Eigen::Vector3d gyro_bias_, accel_bias_, tilt_bias_;
  const SensorErrors* errors_ = nullptr;
};

}  // namespace kuavo::sim
