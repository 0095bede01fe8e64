// The linear Kalman filter behind the state estimator (Leju's KalmanFilterEstimate,
// FACTS.md §6), kept apart from the robot so its algebra can be tested alone.
//
// State x (33), world axes:   [p_base (3); v_base (3); c_0 … c_7 (8×3); b_a (3)]
//   b_a: a constant bias of the world-frame acceleration the IMU gives (R·a_imu − g).
//   Its main source is the IMU's roll/pitch error (0.2° on the MTi): it tips gravity into
//   the horizontal, g·sin 0.2° ≈ 0.034 m/s², which Leju's filter (no bias state) turns into
//   ~1 cm/s of velocity error and a standing robot that walks off (5 cm in 30 s under the
//   MPC). With the feet planted the bias is observable; its variance 0 keeps Leju's filter.
// Measurements y (56):        [c_i − p_base (24); ċ_i − v_base relative (24); c_i,z (8)]
//   rows 0..23   y = c_i,k − p_k        (relative position, leg kinematics)
//   rows 24..47  y = −v_k               (relative velocity of a fixed point: ċ_i = 0)
//   rows 48..55  y = c_i,z              (stance height)
// Every row of C has at most two ±1 entries and R is diagonal, so the update is
// done as sequential scalar updates (the 8 velocity rows per axis fused into
// one, as they share their row of C): mathematically the batch update (tests
// check it against the textbook form), but 35 rank-one updates instead of a 56×56 solve.
// And the three axes are independent filters (see kf_axes_separated): state 3j + k is
// axis k (j = 0 position, 1 velocity, 2..9 points, 10 bias), so the update runs on the
// three 11×11 blocks of P: 9 + 9 + 17 rank-one updates of 11×11 instead of 35 of 33×33,
// the same arithmetic, element for element (the dropped entries are exact zeros).
#pragma once

#include <Eigen/Core>

#include "controllers/model/model_tables.h"

namespace kuavo::estimator {

inline constexpr int kBiasIndex = 6 + 3 * model::kNumContactPoints;  // 30
inline constexpr int kStateDim = kBiasIndex + 3;                     // 33
inline constexpr int kMeasurementDim = 7 * model::kNumContactPoints;  // 56
inline constexpr int kPositionRows = 0;
inline constexpr int kVelocityRows = 3 * model::kNumContactPoints;
inline constexpr int kHeightRows = 6 * model::kNumContactPoints;
inline constexpr int kAxisStates = kStateDim / 3;                    // 11 per axis

using KfVector = Eigen::Matrix<double, kStateDim, 1>;
using KfCovariance = Eigen::Matrix<double, kStateDim, kStateDim>;
using KfMeasurementVector = Eigen::Matrix<double, kMeasurementDim, 1>;

// Index of contact point i, axis k in the state.
constexpr int point_index(int i, int k) { return 6 + 3 * i + k; }

// With ā = a − b_a: p += v·dt + ½ā·dt², v += ā·dt, points and bias constant;
// P = A P Aᵀ + diag(q). A is the identity plus three small blocks (dt, −½dt², −dt), so
// A P Aᵀ is row and column axpys, not a product.
void kf_predict_rt(KfVector& x, KfCovariance& p, const Eigen::Vector3d& a_world_m_s2,
                   const KfVector& process_variance, double dt_s);

// Applies all 56 measurements (variance per row, diagonal R), then symmetrises P.
// Variances must be positive (the estimator's config validation ensures it).
// P must be axis-separated (kf_axes_separated; the estimator's P always is): only the
// three per-axis blocks are read and written.
// innovation receives y − C x before the update (for the watchdog).
void kf_update_rt(KfVector& x, KfCovariance& p, const KfMeasurementVector& y,
                  const KfMeasurementVector& measurement_variance, KfMeasurementVector& innovation);

// Cheetah's / legged_control's guard (FACTS.md §6): the horizontal base position
// is unobservable, so its variance grows without bound; once det(P_xy) exceeds
// det_limit, decorrelate it from the rest of the state and divide it by 10.
// Returns true when it acted.
bool kf_bound_horizontal_rt(KfCovariance& p, double det_limit_m4);

// True when every cross-axis entry of P (state i is axis i mod 3; i mod 3 ≠ j mod 3) is
// zero. Nothing in the filter couples two axes (A is the identity plus per-axis blocks, Q
// and R are diagonal, every row of C involves one axis, the seed P is diagonal, the
// horizontal guard only zeroes entries), so the estimator's P always is.
bool kf_axes_separated(const KfCovariance& p);

// C x: what the state predicts for the measurements.
KfMeasurementVector kf_predicted_measurement(const KfVector& x);

}  // namespace kuavo::estimator
