// Base state estimator (issue 6; Leju's default KalmanFilterEstimate, FACTS.md §6).
//
// Orientation and angular rate are not estimated: they come from the IMU (its
// quaternion as is, the gyro low-passed at 20 Hz); the IMU sits at the base
// origin with base axes (FACTS.md §5.3). A linear Kalman filter (linear_kf.h)
// over base position, base velocity (world) and the 8 sole corners fuses the
// low-passed (12 Hz) accelerometer with leg kinematics; contact flags come
// from the caller's plan, less the corners whose kinematic velocity the other
// stance corners contradict (the contact gate, EstimatorConfig below). Output
// follows conventions.h: v[0:3] in BASE axes.
//
// Usage: EstimatorState lives in static storage (~50 KB). estimator_init once,
// estimator_reset at start-up with the robot standing, then estimator_step_rt
// every control tick. Only estimator_step_rt runs in the real-time loop.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "controllers/dynamics/data.h"
#include "controllers/estimator/linear_kf.h"
#include "controllers/estimator/low_pass.h"
#include "controllers/hal/types.h"
#include "controllers/model/model.h"

namespace kuavo::estimator {

using ContactFlags = std::array<bool, model::kNumContactPoints>;

inline constexpr double kMaxStanceSink_m = 0.05;

struct EstimatorConfig {
  // Leju's task.info kalmanFilter (FACTS.md §6). Process noise is scaled per
  // step as in legged_control: position dt/20, velocity dt·9.81/20, points dt.
  double imu_process_noise_position = 0.02;
  double imu_process_noise_velocity = 0.02;
  double foot_process_noise_position = 0.9;
  double foot_sensor_noise_position = 0.5;   // variance of a relative position row
  double foot_sensor_noise_velocity = 1.0;   // variance of a relative velocity row
  double foot_height_sensor_noise = 0.005;   // variance of a stance-height row
  double non_contact_noise_scale = 1000.0;   // FACTS.md §6: swing points are ×1000
  // Contact gate: a corner the plan holds in contact whose velocity relative to the base,
  // from leg kinematics, differs by more than this from the most consistent stance corner's
  // (each against the filter's predicted base velocity) is not fixed -- its foot left the
  // ground before the plan, slips or pivots -- and its rows get the swing noise for that tick.
  // A planted corner's kinematic velocity noise is a few cm/s (encoder rates times the
  // 0.8 m leg). With the plan's flags alone, a foot that left the ground for 0.36 s of a
  // planned double support, moving at 0.5-0.8 m/s relative to the base, pulled the base
  // velocity estimate 0.3 m/s off (perfume, show campaign seed 10: 14 cm of position error
  // by 2.4 s, a fall at 3.7 s that the true state does not have). The most consistent corner
  // is never gated, so a wrong prediction, which every corner contradicts alike, gates
  // nothing. Show campaigns (100 seeds each): the base velocity error's median RMS per run
  // 0.020 / 0.034 / 0.033 → 0.014 / 0.022 / 0.022 m/s (perfume / cmu_05_07 / cmu_05_20).
  // 0: off (Leju's filter).
  double contact_velocity_gate_m_s = 0.3;
  // World-frame acceleration bias (linear_kf.h): its variance at reset, (m/s²)² -- the
  // MTi's 0.2° tilt (1σ) is 0.034 m/s², so σ 0.1 covers 0.6°; with σ 0.05 the bias had
  // reached 65 % of the true tilt leak after 6 s standing, with 0.1 88 % -- and its random
  // walk, (m/s²)²/s (σ grows 1 mm/s² per √s: a tilt error that wanders over minutes, and
  // the yaw turning a body-fixed part of it). Both 0: no bias state, Leju's filter exactly.
  double initial_accel_bias_variance_m2_s4 = 1e-2;
  double accel_bias_random_walk_m2_s5 = 1e-6;
  // Initial covariance at reset: the pose is known from kinematics, the velocity is not.
  double initial_position_variance_m2 = 1e-4;
  double initial_velocity_variance_m2_s2 = 0.1;
  // IMU low-pass corners (FACTS.md §5.3) and gravity (the model's; Leju uses 9.785).
  double gyro_cutoff_hz = 20.0;
  double accel_cutoff_hz = 12.0;
  double gravity_m_s2 = model::kGravity_m_s2;
  double ground_height_m = 0.0;  // stance heights are measured against this plane
  // How deep a loaded sole rests below that plane: 0 on a hard floor; on a soft stage surface
  // (carpet, foam) its sink under the standing robot, measured when the stage is set up. The
  // stance height rows (and the reset) put the soles there. The plan's ground stays the
  // surface: swings still aim at it. Left at 0 on the simulator's carpet (1.5 cm under the
  // standing robot, sim/ground_contact.h), the soles are put at the surface, the base reads
  // 1.6-2.6 cm high (cmu_05_07, show seed 47), every swing aims that much into the carpet and
  // meets it early. Show campaign's 16 falling runs (carpet, `show` set, 10 N·s push): with
  // 0.015 m 6 fall; with the true base height and vertical velocity instead of the estimate's,
  // 6; on a stiff ground of the carpet's friction, 4. The whole show campaign (400 runs, the
  // same motions): 7 falls with 0.015 m, 16 without. Range 0..kMaxStanceSink_m.
  double stance_sink_m = 0.0;
  // dt outside this range is clamped (and reported): 10 kHz … 50 Hz.
  double dt_min_s = 1e-4;
  double dt_max_s = 0.02;
  // IMU plausibility: MTi ranges 2000 °/s and 10 g (FACTS.md §5.3); a quaternion
  // whose norm is off by more than this is not a rotation.
  double gyro_max_rad_s = 34.9;
  double accel_max_m_s2 = 98.1;
  double quaternion_norm_tolerance = 0.05;
  // det(P_xy) bound of the horizontal-position guard (kf_bound_horizontal_rt) [m⁴];
  // Cheetah's and legged_control's value.
  double horizontal_covariance_det_limit_m4 = 1e-6;
  // Divergence watchdog: trace(P) beyond this is reported as kDiverged.
  double covariance_trace_limit = 10.0;
};

// Stable numbers; never reuse. A step reports the most severe that applied.
enum class EstimatorStatus : std::uint8_t {
  kOk = 0,
  kDtClamped = 1,       // dt outside [dt_min_s, dt_max_s]: clamped
  kJointsRejected = 2,  // a joint sample invalid or not finite: prediction only, last joints held
  kImuRejected = 3,     // IMU invalid, not finite or out of range: last good IMU values held
  kDiverged = 4,        // trace(P) over the limit, or a non-finite state (filter re-seeded)
  kNotInitialized = 5,  // no reset yet and no usable sample to reset from: output is not an estimate
};
const char* to_string(EstimatorStatus s);

struct EstimateOutput {
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  Eigen::Vector3d base_velocity_world_m_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias_world_m_s2 = Eigen::Vector3d::Zero();  // the filter's b_a
  EstimatorStatus status = EstimatorStatus::kNotInitialized;
  // Watchdog diagnostics: ‖y − C x‖ over the in-contact rows before the update
  // (mixed m and m/s), and trace(P) after it.
  double innovation_norm = 0.0;
  double covariance_trace = 0.0;
};

// The workspace: preallocated once, in static storage.
struct EstimatorState {
  EstimatorConfig config{};
  KfVector x = KfVector::Zero();
  KfCovariance p = KfCovariance::Identity();
  KfVector process_variance = KfVector::Zero();
  KfMeasurementVector y = KfMeasurementVector::Zero();
  KfMeasurementVector measurement_variance = KfMeasurementVector::Ones();
  KfMeasurementVector innovation = KfMeasurementVector::Zero();
  LowPass3 gyro{}, accel{};
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // last accepted, base -> world
  dynamics::JointVector joint_position_rad = dynamics::JointVector::Zero();  // last accepted
  dynamics::JointVector joint_velocity_rad_s = dynamics::JointVector::Zero();
  // Kinematics about the base origin (base position and linear velocity zero).
  dynamics::ConfigVector q_relative = dynamics::ConfigVector::Zero();
  dynamics::VelocityVector v_relative = dynamics::VelocityVector::Zero();
  dynamics::Data data;
  bool initialized = false;
  std::uint64_t imu_rejects = 0, joint_rejects = 0, dt_clamps = 0, divergences = 0, horizontal_resets = 0;
  // Corner-ticks the contact gate (contact_velocity_gate_m_s) took out of contact.
  std::uint64_t gated_corner_ticks = 0;
};

// Validates the configuration once: returns false (and keeps the defaults) if a
// noise, cutoff or limit is not finite and positive. Clears the filter.
bool estimator_init(const EstimatorConfig& config, EstimatorState& state);

// Start-up: the robot stands with all 8 sole corners on the ground plane (sunk by
// stance_sink_m). Puts the base at base_xy_m and at the height leg kinematics give over
// the lowest corner, the corners where kinematics put them, velocity zero. Needs a usable
// IMU and joint sample (else kNotInitialized, nothing changed).
EstimatorStatus estimator_reset(const model::Model& model, EstimatorState& state, const hal::SensorFrame& sensors,
                                const Eigen::Vector2d& base_xy_m);

// The filter's current estimate without a step (e.g. right after estimator_reset, so a
// planner started before the first tick plans from the robot, not from a stale or zero
// output). status kOk if initialized, else kNotInitialized with out unchanged.
void estimator_output(const EstimatorState& state, EstimateOutput& out);

// One tick. contact: the plan's contact flags per sole corner (frame order).
// If no reset happened yet it resets at the origin first. Real-time safe: no
// allocation, no exceptions, no I/O; output always finite.
void estimator_step_rt(const model::Model& model, EstimatorState& state, const hal::SensorFrame& sensors,
                       const ContactFlags& contact, double dt_s, EstimateOutput& out);

}  // namespace kuavo::estimator
