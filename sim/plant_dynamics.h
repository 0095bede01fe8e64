// The plant's state derivative ẏ = f(t, y) for CVODE, computed with the project's
// own O(n) rigid-body algorithms (controllers/dynamics: forward kinematics, CRBA,
// RNEA; verified against Simbody in tests/dynamics/simbody_oracle_test.cpp) and
// the same force laws Simbody is given (drive PD with saturation, sole-corner
// contact, the push, gravity).
//
// Why not Simbody's realize(Acceleration) here: it costs ~37 µs an evaluation and
// CVODE needs 10–20 evaluations per 2 ms tick; this costs ~8 µs. What runs where:
// - Simbody builds the multibody system and fixes the state layout (y is Simbody's
//   [q; u], read through SimbodyLayout); it sets and projects the state (reset,
//   quaternion drift); it runs the reference integrator (--integrator rkm) and the
//   Euler option end to end; with PlantConfig::derivatives = kSimbody it is CVODE's
//   derivative and computes the truth, as before.
// - With CVODE and the default kRigidBody: this file computes ẏ and the end-of-
//   interval truth; Simbody re-computes ẏ every 50 intervals and the plant keeps the
//   worst difference (Plant::max_derivative_mismatch()).
// - tests/sim/plant_dynamics_test.cpp holds the two to 1e-8 of (1 + |ẏ|) at
//   contact states (rounding reaches ~2e-10) and along a CVODE trajectory.
//
// Simbody's state, for reference: the base is a Free mobilizer, q = [quaternion
// (w, x, y, z), unnormalised; origin position], u = [angular velocity; origin
// velocity], both in ground axes; each joint a Pin with one q and one u.
// No <Simbody.h> here.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "controllers/dynamics/data.h"
#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "sim/ground_contact.h"

namespace kuavo::sim {

struct Push;
struct PlantTruth;
struct JointActuation;
}  // namespace kuavo::sim
namespace kuavo::drivers {
struct AnkleMotors;  // drivers/transmission/ankle_motors.h
}  // namespace kuavo::drivers
namespace kuavo::sim {

// Where our quantities sit in Simbody's y = [q; u] (filled from the built system).
struct SimbodyLayout {
  int num_q = 0;
  int num_u = 0;
  int base_q = 0;  // quaternion (4) then position (3)
  int base_u = 0;  // angular velocity (3) then linear velocity (3), ground axes
  std::array<int, model::kNumJoints> joint_q{};
  std::array<int, model::kNumJoints> joint_u{};
};

// Actuators whose law the hal::JointCommand cannot express (a drive's PD in motor
// space behind a closed-chain transmission): evaluated at every force evaluation
// from the instantaneous joint state, like a drive's fast loop. Must be
// deterministic, noexcept and heap-free; it adds to tau (joint space).
class JointTorqueSource {
 public:
  virtual ~JointTorqueSource() = default;
  virtual void add_joint_torques(const std::array<double, model::kNumJoints>& q_rad,
                                 const std::array<double, model::kNumJoints>& v_rad_s,
                                 std::array<double, model::kNumJoints>& tau_Nm) const noexcept = 0;
};

// Everything the forces read besides the state; the plant updates it between intervals.
struct PlantForceInputs {
  GroundParams ground = kFloor;
  bool contact = true;
  bool gravity = true;
  hal::CommandFrame command{};
  const JointTorqueSource* torque_source = nullptr;  // added to the command's torques
  // Model mismatch (sim/perturbation.h): torque-constant error and friction on the drive
  // torque, rotor inertia on M's diagonal. nullptr: ideal joints.
  const JointActuation* actuation = nullptr;
  const drivers::AnkleMotors* ankle_motors = nullptr;  // PlantConfig::ankle_motors
  std::array<ContactPointState, model::kNumContactPoints> points{};
  const Push* push = nullptr;
};

class PlantDynamics {
 public:
  PlantDynamics(const model::Model& model, const SimbodyLayout& layout);
  ~PlantDynamics();
  PlantDynamics(const PlantDynamics&) = delete;
  PlantDynamics& operator=(const PlantDynamics&) = delete;

  // ẏ for y = Simbody's [q; u] (num_q + num_u values each). contact_wrench_out:
  // [Σf; Σ p×f about the world origin] of the ground forces. Returns false when ẏ
  // is not finite.
  bool derivative(double t_s, const double* y, const PlantForceInputs& in, double* ydot,
                  Eigen::Matrix<double, 6, 1>& contact_wrench_out);

  // The plant's truth at (t, y), from one derivative evaluation: pose and speeds in
  // our conventions, sole corners (and their velocities, for the contact anchors),
  // ground forces, drive torques, the IMU's specific force, CoM and centroidal
  // momentum. Adds the drives that clip to *saturations. Returns false when not finite.
  bool truth(double t_s, const double* y, const PlantForceInputs& in, PlantTruth& out,
             std::array<Vec3, model::kNumContactPoints>& contact_velocity_m_s, std::uint64_t& saturations);

 private:
  const model::Model& model_;
  SimbodyLayout layout_;
  struct Work;
  std::unique_ptr<Work> work_;  // ~50 KB of workspace, allocated once
};

}  // namespace kuavo::sim
