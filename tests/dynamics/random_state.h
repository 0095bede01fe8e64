// Seeded random robot states for the dynamics tests.
#pragma once

#include <random>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::test {

inline dynamics::ConfigVector random_configuration(const model::Model& m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  dynamics::ConfigVector q;
  q.head<3>() << u(rng), u(rng), 0.9 + 0.3 * u(rng);
  Eigen::Quaterniond quat(u(rng), u(rng), u(rng), u(rng));
  quat.normalize();
  q.segment<4>(3) << quat.x(), quat.y(), quat.z(), quat.w();
  for (int j = 0; j < model::kNumJoints; ++j) {
    const double lo = m.limits.position_min_rad[j], hi = m.limits.position_max_rad[j];
    q[7 + j] = lo + (hi - lo) * 0.5 * (u(rng) + 1.0);
  }
  return q;
}

inline dynamics::VelocityVector random_velocity(std::mt19937_64& rng, double scale = 1.0) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  dynamics::VelocityVector v;
  for (int i = 0; i < 3; ++i) v[i] = scale * u(rng);
  for (int i = 3; i < 6; ++i) v[i] = 2.0 * scale * u(rng);
  for (int i = 6; i < model::kNv; ++i) v[i] = 3.0 * scale * u(rng);
  return v;
}

// max|a - b| / max(1, max|b|): the relative error the oracle tests bound.
template <typename A, typename B>
double relative_error(const A& a, const B& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

}  // namespace kuavo::test
