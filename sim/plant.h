// The simulated robot: Simbody multibody dynamics built from the generated model
// tables, ground contact at the 8 sole corners, the drives' PD law with torque
// saturation, gravity and push disturbances. Integrated by SUNDIALS CVODE (BDF,
// for the stiff contact) with derivatives from our own O(n) dynamics over
// Simbody's state (plant_dynamics.h says what runs where; Simbody re-checks them
// live), or by Simbody's own Runge-Kutta-Merson integrator as a cross-check. Deterministic: no clocks, no
// threads, no randomness here (sensor noise lives in sensor_model.h).
// This header does not include <Simbody.h>, so C++20 code can use it.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "controllers/dynamics/data.h"
#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "sim/ground_contact.h"
#include "sim/perturbation.h"
#include "sim/plant_dynamics.h"

namespace kuavo::sim {

// kCvodeBdf: SUNDIALS CVODE, variable-order BDF with Newton and a dense Jacobian;
//   error-controlled, the accuracy reference for the stiff contact.
// kSimbodyRungeKuttaMerson: Simbody's own error-controlled integrator (cross-check).
// kSemiImplicitEuler: fixed substeps of Simbody accelerations, velocity first then
//   position (symplectic); the fast default for closed-loop runs.
enum class Integrator : std::uint8_t { kCvodeBdf = 0, kSimbodyRungeKuttaMerson = 1, kSemiImplicitEuler = 2 };
bool parse_integrator(const char* text, Integrator& out);  // "cvode" | "rkm" | "euler"
const char* to_string(Integrator i);

// Who computes CVODE's state derivative (kCvodeBdf only; the other integrators
// always realize Simbody). kRigidBody: sim/plant_dynamics.h, the project's own
// O(n) algorithms over Simbody's state layout, ~10x cheaper; kSimbody:
// realize(Acceleration), the oracle the first is tested against.
enum class DerivativeEngine : std::uint8_t { kRigidBody = 0, kSimbody = 1 };

struct PlantConfig {
  GroundParams ground = kFloor;
  Integrator integrator = Integrator::kCvodeBdf;
  DerivativeEngine derivatives = DerivativeEngine::kRigidBody;
  double euler_substep_s = 2.0e-4;  // kSemiImplicitEuler only
  // Loose enough for real-time-and-better on one core; tests/sim checks that a
  // 100x tighter run gives the same standing outcome (tilt, height, forces).
  double relative_tolerance = 1e-3;
  double absolute_tolerance = 1e-4;
  bool gravity = true;
  bool contact = true;
  // Model mismatch of the joints (sim/perturbation.h); nullptr: ideal joints. Rotor
  // inertia needs kCvodeBdf with kRigidBody (Simbody's Pin has no armature): advance()
  // refuses it otherwise. Must outlive the plant.
  const JointActuation* actuation = nullptr;
  // The ankle pairs clipped per motor through the linkage (sim/motor_model.h); nullptr: each
  // ankle joint clips at its own peak. Must outlive the plant.
  const drivers::AnkleMotors* ankle_motors = nullptr;
};

// A force on the torso's centre of mass over [start_s, start_s + duration_s):
// a push of impulse force·duration.
struct Push {
  double start_s = 0.0;
  double duration_s = 0.0;
  Vec3 force_N = Vec3::Zero();
};

// Stable numbers.
enum class PlantError : std::uint8_t {
  kOk = 0,
  kIntegratorFailed = 1,  // CVODE or Simbody reported a failure (the message says which)
  kNonFiniteState = 2,
};

struct PlantTruth {
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  std::array<Vec3, model::kNumContactPoints> contact_point_m{};  // sole corners in the world
  std::array<Vec3, model::kNumContactPoints> contact_force_N{};
  // The drive's torque; with a JointActuation, what reaches the joint (Kt error, friction).
  Eigen::Matrix<double, model::kNumJoints, 1> joint_torque_Nm = Eigen::Matrix<double, model::kNumJoints, 1>::Zero();
  Vec3 base_specific_force_m_s2 = Vec3::Zero();  // what an IMU at the base origin measures, base axes
  Vec3 com_m = Vec3::Zero();
  Eigen::Matrix<double, 6, 1> momentum = Eigen::Matrix<double, 6, 1>::Zero();  // [linear; angular about CoM], world
};

class Plant {
 public:
  Plant(const model::Model& model, const PlantConfig& config);
  ~Plant();
  Plant(const Plant&) = delete;
  Plant& operator=(const Plant&) = delete;

  void reset(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v, double time_s = 0.0);
  void set_command(const hal::CommandFrame& command);
  // Torques added to the command's at every force evaluation (see JointTorqueSource in
  // plant_dynamics.h); nullptr: none. The source must outlive its use.
  void set_torque_source(const JointTorqueSource* source);
  void set_push(const Push& push);

  // Integrates over [time, time + dt_s] with the command held; contact anchors
  // update at the end of the interval.
  PlantError advance(double dt_s);

  double time_s() const;
  const PlantTruth& truth() const;  // at time_s()
  std::uint64_t torque_saturations() const;  // drive-ticks that clipped, summed over joints
  std::uint64_t derivative_evaluations() const;
  struct IntegratorStats {
    long steps = 0, jacobian_evaluations = 0, linear_setups = 0, error_test_failures = 0;
    long nonlinear_iterations = 0, nonlinear_failures = 0;
  };
  IntegratorStats integrator_stats() const;  // CVODE counters since construction
  const char* last_error() const;
  // The cross-check of the CVODE derivative (plant_dynamics.h) against Simbody's
  // realize(Acceleration) at the current state, command and contact anchors:
  // max_i |ẏ_i − ẏ_simbody,i| / (1 + |ẏ_simbody,i|) over [q̇; u̇; contact wrench].
  double derivative_mismatch();
  // The largest derivative_mismatch() of the run: with the default derivative and
  // CVODE, the plant computes it every 50 intervals (Simbody watching live).
  double max_derivative_mismatch() const;
  // Contact impulse since reset(): [∫f dt; ∫p×f dt about the world origin], integrated by
  // CVODE as quadrature states (zero with the Simbody integrator).
  Eigen::Matrix<double, 6, 1> contact_impulse() const;

 private:
  PlantError advance_interval(double dt_s);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kuavo::sim
