// The second simulator: MuJoCo (Debian's 2.2.2) running Leju's own MJCF of the 4Pro
// (sim/mujoco_model.h), with MuJoCo's contact between the soles' collision spheres and a
// floor plane. Neither the robot's tables nor the contact model are ours, so a motion that
// works in both simulators does not lean on either one's idealisations.
//
// Same interface as sim::Plant where the closed loops use it (the loops are templates over
// the plant; no virtual calls): the same HAL command through the same drive law
// (sim/motor_model.h, the joints' peak torques of our model), the same PlantTruth for the
// same sensor model, in our conventions (controllers/dynamics/conventions.h): MuJoCo's
// free joint stores (x, y, z, qw, qx, qy, qz) with its linear velocity in world axes, ours
// (x, y, z, qx, qy, qz, qw) with base axes; joints are matched by name, never by index.
//
// What is Leju's and stays: the MJCF's inertials (its fixed links lumped into their parents),
// its joint damping of 0.2 N·m·s/rad and its joint ranges as limits (our Simbody plant has
// neither), and the small spheres at the hands, which touch the floor only after a fall
// (their forces are not among the sole corners').
//
// Fixed step of 0.5 ms, MuJoCo's semi-implicit Euler: the drive law is evaluated at each
// step from the step's start state, which is what the real drives do at their 2 kHz
// (ARCHITECTURE.md, rates). Deterministic: one thread, no clocks, no randomness.
// This header does not include <mujoco/mujoco.h>.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "controllers/hal/types.h"
#include "controllers/model/model.h"
#include "sim/ground_contact.h"
#include "sim/mujoco_model.h"
#include "sim/plant.h"

namespace kuavo::sim {

struct MujocoPlantConfig {
  // Only the flat floor: MuJoCo's contact stands in for our floor's springs; the friction
  // coefficient is the surface's (ground.friction_coefficient). A foam carpet or a terrain
  // would need their own MuJoCo parameters, which nothing here validates: refused.
  GroundParams ground = kFloor;
  double timestep_s = 5.0e-4;
  bool gravity = true;
  bool contact = true;
  const drivers::AnkleMotors* ankle_motors = nullptr;  // as PlantConfig::ankle_motors
};

// Why a ground is refused (nullptr: accepted).
const char* mujoco_ground_refusal(const GroundParams& ground);

class MujocoPlant {
 public:
  // Loads the generated MJCF; ok() says whether it did, last_error() why not. Installs a
// silent MuJoCo warning handler (process-wide: MuJoCo's default prints to stdout and
// writes MUJOCO_LOG.TXT); advance() reads the warning counters instead.
  MujocoPlant(const model::Model& model, const MujocoPlantConfig& config);
  ~MujocoPlant();
  MujocoPlant(const MujocoPlant&) = delete;
  MujocoPlant& operator=(const MujocoPlant&) = delete;
  bool ok() const;

  void reset(const dynamics::ConfigVector& q, const dynamics::VelocityVector& v, double time_s = 0.0);
  void set_command(const hal::CommandFrame& command);
  void set_push(const Push& push);
  // dt_s must be a whole number of time steps.
  PlantError advance(double dt_s);

  double time_s() const;
  // contact_point_m: the lowest point of the collision sphere at each of our 8 sole
  // corners; contact_force_N: the force of MuJoCo's contacts on the sole, the middle
  // spheres' (between two corners) shared between those corners by their position, so
  // each foot's total force and centre of pressure are MuJoCo's.
  const PlantTruth& truth() const;
  std::uint64_t torque_saturations() const;     // drive-ticks that clipped, summed over joints
  std::uint64_t derivative_evaluations() const;  // MuJoCo steps (one forward dynamics each)
  Plant::IntegratorStats integrator_stats() const;
  const char* last_error() const;
  // The contact spheres' radius [m]: MuJoCo's soles are this much below our corners.
  double sole_sphere_radius_m() const;
  double total_mass_kg() const;  // MuJoCo's, after the torso rescale

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Raises q's base so the lowest contact sphere just touches the floor, then resets the
// plant there at rest. Our corners sit at the spheres' centres: place_on_ground puts the
// centres on the floor, which would start the spheres a radius deep.
void reset_on_floor(MujocoPlant& plant, dynamics::ConfigVector& q);

}  // namespace kuavo::sim
