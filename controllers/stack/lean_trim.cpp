#include "controllers/stack/lean_trim.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace kuavo::stack {

const char* lean_trim_validate(const LeanTrimConfig& c) {
  if (!(c.observer_gain_1_s > 0.0 && c.observer_gain_1_s <= 100.0)) return "lean trim observer gain outside (0, 100] 1/s";
  if (!(c.time_constant_s >= 0.1 && c.time_constant_s <= 100.0)) return "lean trim time constant outside 0.1..100 s";
  if (!(c.opening_time_constant_s >= 0.1 && c.opening_time_constant_s <= 100.0)) {
    return "lean trim opening time constant outside 0.1..100 s";
  }
  if (c.learn != LeanTrimLearn::kAlways && c.learn != LeanTrimLearn::kOpening) return "lean trim learning phase unknown";
  if (!(c.max_rad > 0.0 && c.max_rad <= 0.1)) return "lean trim bound outside (0, 0.1] rad";
  if (!(c.residual_gate_N > 0.0 && c.residual_gate_N <= 1000.0)) return "lean trim residual gate outside (0, 1000] N";
  if (!(c.residual_deadband_N >= 0.0 && c.residual_deadband_N < c.residual_gate_N)) {
    return "lean trim dead band outside [0, residual gate) N";
  }
  if (!(c.min_load_share >= 0.0 && c.min_load_share <= 1.0)) return "lean trim load share outside 0..1";
  if (!(c.quasi_static_force_N > 0.0 && c.quasi_static_force_N <= 1e4)) return "lean trim quasi-static force outside (0, 1e4] N";
  if (!(c.quasi_static_speed_m_s > 0.0 && c.quasi_static_speed_m_s <= 10.0)) {
    return "lean trim quasi-static speed outside (0, 10] m/s";
  }
  if (!(c.quasi_static_hold_s >= 0.0 && c.quasi_static_hold_s <= 10.0)) return "lean trim quasi-static hold outside 0..10 s";
  return nullptr;
}

void lean_trim_reset(LeanTrimState& state) { state = LeanTrimState{}; }

void lean_trim_apply_rt(const LeanTrimConfig& config, const LeanTrimState& state, dynamics::ConfigVector& q) {
  if (!config.enabled || state.theta_rad.isZero(0.0)) return;
  const Eigen::Quaterniond trim = Eigen::AngleAxisd(state.theta_rad.x(), Eigen::Vector3d::UnitX()) *
                                  Eigen::AngleAxisd(state.theta_rad.y(), Eigen::Vector3d::UnitY());
  Eigen::Quaterniond r(q[6], q[3], q[4], q[5]);
  r = (trim * r).normalized();
  q.segment<4>(3) = r.coeffs();
}

void lean_trim_note_plan_rt(const LeanTrimConfig& config, LeanTrimState& state, const planner::ContactFlags& planned) {
  if (!config.enabled) return;
  for (const bool in_contact : planned) state.opening_over = state.opening_over || !in_contact;
}

void lean_trim_update_rt(const LeanTrimConfig& config, LeanTrimState& s, const dynamics::Data& data,
                         const wbc::ForceVector& point_position_m, const wbc::ForceVector& force_N,
                         const dynamics::VelocityVector& v, bool wbc_ok, double gravity_m_s2, double dt_s) {
  if (!config.enabled) return;
  const bool opening = config.learn == LeanTrimLearn::kOpening;
  if (opening && s.opening_over) return;  // learned: the trim holds
  const double mass = data.total_mass_kg;
  const Eigen::Vector2d momentum = (data.momentum_matrix_ref.topRows<2>() * v);
  Eigen::Vector2d force = Eigen::Vector2d::Zero();
  double normal_N = 0.0;
  double lowest_z = data.com_m.z();
  constexpr int kPoints = wbc::ForceVector::RowsAtCompileTime / 3;
  for (int p = 0; p < kPoints; ++p) {
    force += force_N.segment<2>(3 * p);
    normal_N += force_N[3 * p + 2];
    lowest_z = std::min(lowest_z, point_position_m[3 * p + 2]);
  }
  if (!wbc_ok || !(dt_s > 0.0) || !momentum.allFinite() || !force.allFinite()) {
    // The forces were not a plan the drives carried out: the observer starts again.
    s.primed = false;
    return;
  }
  if (!s.primed) {
    s.momentum0_Ns = momentum;
    s.integral_Ns.setZero();
    s.residual_N.setZero();
    s.last_force_N = force;
    s.primed = true;
    return;
  }
  s.integral_Ns += dt_s * (s.last_force_N + s.residual_N);
  s.residual_N = config.observer_gain_1_s * (momentum - s.momentum0_Ns - s.integral_Ns);
  s.last_force_N = force;
  const bool quiet = force.norm() <= config.quasi_static_force_N &&
                     momentum.norm() <= config.quasi_static_speed_m_s * mass;
  s.quiet_s = quiet ? s.quiet_s + dt_s : 0.0;

  const double height_m = data.com_m.z() - lowest_z;
  if (!(normal_N >= config.min_load_share * mass * gravity_m_s2) || !(s.residual_N.norm() <= config.residual_gate_N) ||
      !(height_m > 0.2) || !(s.quiet_s >= config.quasi_static_hold_s)) {
    return;
  }
  // δ = r·h/(m·g); θ moves by dt/τ · δ/h, so h cancels.
  const double tau = opening ? config.opening_time_constant_s : config.time_constant_s;
  // What joint friction may hold is not learned: the residual shrunk by the dead band.
  const double r = s.residual_N.norm();
  const double kept = r > config.residual_deadband_N ? 1.0 - config.residual_deadband_N / r : 0.0;
  const Eigen::Vector2d rate = kept * s.residual_N / (mass * gravity_m_s2 * tau);
  s.theta_rad.x() -= dt_s * rate.y();
  s.theta_rad.y() += dt_s * rate.x();
  ++s.integrated_ticks;
  const Eigen::Vector2d bounded = s.theta_rad.cwiseMax(-config.max_rad).cwiseMin(config.max_rad);
  if (bounded != s.theta_rad) {
    s.theta_rad = bounded;
    ++s.saturated_ticks;
  }
}

}  // namespace kuavo::stack
