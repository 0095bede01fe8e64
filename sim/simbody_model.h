// The Kuavo 4Pro as a Simbody multibody system, built from the same generated
// tables as our own model (model::Model). Used as the simulator plant and as the
// independent oracle for controllers/dynamics. Not real-time code.
#pragma once

#include <Simbody.h>

#include <array>

#include "controllers/dynamics/data.h"
#include "controllers/model/model.h"
#include "sim/plant_dynamics.h"

namespace kuavo::sim {

class SimbodyRobot {
 public:
  // gravity: add a uniform gravity force (-z, model::kGravity_m_s2).
  SimbodyRobot(const model::Model& model, bool gravity);
  SimbodyRobot(const SimbodyRobot&) = delete;
  SimbodyRobot& operator=(const SimbodyRobot&) = delete;

  SimTK::MultibodySystem& system() { return system_; }
  const SimTK::SimbodyMatterSubsystem& matter() const { return matter_; }
  SimTK::GeneralForceSubsystem& forces() { return forces_; }
  const SimTK::MobilizedBody& body(int index) const { return bodies_[index]; }

  // Writes our (q, v) (conventions.h) into a Simbody state; realizes to Velocity.
  void set_state(SimTK::State& state, const dynamics::ConfigVector& q,
                 const dynamics::VelocityVector& v) const;
  // Reads our (q, v) back from a Simbody state (state at least at Position).
  void get_state(const SimTK::State& state, dynamics::ConfigVector& q, dynamics::VelocityVector& v) const;

  // Simbody's generalized speeds u relate to ours by u = T(q)·v (T is orthogonal
  // on the base block: our base twist is in base axes and linear-first, Simbody's
  // Free mobilizer uses ground axes and angular-first). Index map for u.
  int u_index_of_joint(int joint) const { return joint_u_index_[joint]; }
  int base_u_index() const { return base_u_index_; }

 private:
  SimTK::MultibodySystem system_;
  SimTK::SimbodyMatterSubsystem matter_;
  SimTK::GeneralForceSubsystem forces_;
  std::array<SimTK::MobilizedBody, model::kNumBodies> bodies_;
  std::array<int, model::kNumJoints> joint_u_index_{};
  int base_u_index_ = 0;
};

// Where each body's coordinates sit in a state of this robot (PlantDynamics reads
// Simbody's [q; u] through it). Needs realizeTopology().
SimbodyLayout simbody_layout(const SimbodyRobot& robot, const SimTK::State& state);

}  // namespace kuavo::sim
