// First-order low-pass on a 3-vector, as Leju filters the IMU (gyro 20 Hz,
// accelerometer 12 Hz; FACTS.md §5.3). Discretised per step from the actual dt,
// so a jittery period keeps the same corner frequency. Real-time safe.
#pragma once

#include <Eigen/Core>

namespace kuavo::estimator {

struct LowPass3 {
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
  bool started = false;  // the first sample seeds the state (no start-up transient from zero)
};

// alpha = dt / (dt + 1/(2π f_c)): the exact first-order hold for a small dt.
inline void low_pass_step_rt(LowPass3& f, const Eigen::Vector3d& sample, double cutoff_hz, double dt_s) {
  if (!f.started) {
    f.value = sample;
    f.started = true;
    return;
  }
  constexpr double kTwoPi = 6.283185307179586;
  const double tau_s = 1.0 / (kTwoPi * cutoff_hz);
  f.value += (dt_s / (dt_s + tau_s)) * (sample - f.value);
}

}  // namespace kuavo::estimator
