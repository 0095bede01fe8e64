// The runtime robot model: built once at start-up from the generated tables,
// then only read (const) by every algorithm. Pinocchio-style split: this is
// the Model; controllers/dynamics/data.h is the preallocated workspace.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "controllers/model/model_tables.h"

namespace kuavo::model {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

enum class Variant : std::uint8_t { kS45 = 0, kS42 = 1 };

// Leju's build rescales only the torso so the total equals the weighed mass
// (FACTS.md §3.2); the product sheet mass is the default.
inline constexpr double kDefaultTotalMass_kg = 55.0;
// Gravity used by the model and the simulator (standard gravity).
inline constexpr double kGravity_m_s2 = 9.81;

struct Body {
  int parent = -1;
  Mat3 joint_rotation = Mat3::Identity();  // child axes in the parent at q = 0
  Vec3 joint_position_m = Vec3::Zero();    // child origin in the parent frame
  Vec3 axis = Vec3::UnitZ();               // joint axis in the child frame
  double mass_kg = 0.0;
  Vec3 com_m = Vec3::Zero();
  Mat3 inertia_com_kgm2 = Mat3::Zero();
};

struct Frame {
  int body = 0;
  Mat3 rotation = Mat3::Identity();
  Vec3 position_m = Vec3::Zero();
};

struct JointLimits {
  Eigen::Matrix<double, kNumJoints, 1> position_min_rad, position_max_rad;
  Eigen::Matrix<double, kNumJoints, 1> velocity_rad_s, torque_Nm;
  Eigen::Matrix<double, kNumJoints, 1> peak_velocity_rad_s, peak_torque_Nm;
};

struct Model {
  Variant variant = Variant::kS45;
  const ModelTables* tables = nullptr;  // names and provenance
  std::array<Body, kNumBodies> bodies{};
  std::array<Frame, kNumFrames> frames{};
  JointLimits limits{};
  double total_mass_kg = 0.0;
};

enum class ModelError : std::uint8_t {
  kOk = 0,
  kUnknownVariant = 1,
  kMassTooSmall = 2,  // the requested total leaves no positive torso mass
  kMassNotFinite = 3,
};

const char* to_string(ModelError e);
const char* to_string(Variant v);
// Parses "s45" / "s42"; returns false for anything else.
bool parse_variant(const char* text, Variant& out);
const ModelTables& tables_for(Variant v);

// Builds the model; the torso (body 0) mass is set so the total is total_mass_kg,
// torso CoM and inertia unchanged (as Leju's update_mass.sh does).
ModelError build_model(Variant v, double total_mass_kg, Model& out);

// The sole corners (contact frames 0..7, four per foot) moved in toward their sole's centre
// by inset_m in the foot's x and y (the corners' mean; a half-width below inset_m ends on the
// centre line). The planners' narrower soles (StackConfig::planner_sole_inset_m, the offline
// TO's support_margin_m). Load time; inset_m >= 0.
void inset_sole_corners(Model& m, double inset_m);

// Convenience names.
inline const char* joint_name(const Model& m, int joint) { return m.tables->bodies[joint + 1].joint_name; }
inline const char* frame_name(const Model& m, int frame) { return m.tables->frames[frame].name; }

}  // namespace kuavo::model
