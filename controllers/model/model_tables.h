// Plain constexpr tables describing one Kuavo 4Pro variant, as emitted by
// tools/urdf2model from Leju's URDF plus the limit files. Sizes are fixed at
// compile time and are the same for both arm variants (only numbers differ).
// The runtime Model (model.h) is built from these once, at start-up.
#pragma once

namespace kuavo::model {

inline constexpr int kNumJoints = 28;          // L-leg 1-6, R-leg 1-6, L-arm 1-7, R-arm 1-7, head yaw, pitch
inline constexpr int kNumBodies = kNumJoints + 1;  // body 0 is the floating base (base_link)
inline constexpr int kNumContactPoints = 8;    // 4 sole corners per foot
inline constexpr int kNumFrames = 12;          // 8 contact points, 2 hands, camera, lidar
inline constexpr int kNq = 7 + kNumJoints;     // base position, base quaternion, joints
inline constexpr int kNv = 6 + kNumJoints;     // base twist, joint rates

// Index ranges inside the 28 joints (controller order, FACTS.md §2.1).
inline constexpr int kLeftLegFirst = 0;
inline constexpr int kRightLegFirst = 6;
inline constexpr int kLeftArmFirst = 12;
inline constexpr int kRightArmFirst = 19;
inline constexpr int kHeadFirst = 26;
inline constexpr int kLegJoints = 6;
inline constexpr int kArmJoints = 7;
// Inside a leg: hip roll, hip yaw, hip pitch, knee, ankle pitch, ankle roll.
inline constexpr int kAnklePitchInLeg = 4;  // ankle roll follows it

// Frame ids: contact points first, in this order per foot: toe +y, toe -y, heel +y, heel -y.
inline constexpr int kFrameLeftHand = 8;
inline constexpr int kFrameRightHand = 9;
inline constexpr int kFrameCamera = 10;
inline constexpr int kFrameLidar = 11;

struct Vec3Table {
  double x, y, z;
};

// A body and the revolute joint that connects it to its parent. Body 0 has no joint.
struct BodyTable {
  const char* link_name;
  const char* joint_name;  // "" for the base
  int parent;              // -1 for the base
  Vec3Table joint_xyz_m;   // joint origin in the parent body frame
  Vec3Table joint_rpy_rad; // fixed roll-pitch-yaw (URDF convention) of the joint origin
  Vec3Table axis;          // unit joint axis in the child frame
  double mass_kg;
  Vec3Table com_m;         // centre of mass in the body frame
  double inertia_kgm2[6];  // about the CoM, body axes: ixx iyy izz ixy ixz iyz
};

struct JointLimitTable {
  double position_min_rad;
  double position_max_rad;
  double velocity_rad_s;         // continuous limit the controller plans within
  double torque_Nm;              // limit the WBC plans within
  double peak_velocity_rad_s;    // hard trip
  double peak_torque_Nm;         // hard trip
};

struct FrameTable {
  const char* name;
  int body;
  Vec3Table xyz_m;
  Vec3Table rpy_rad;
};

struct ModelTables {
  const char* variant;           // "s45" or "s42"
  const char* source_urdf;       // path below shared/robot the tables came from
  double urdf_total_mass_kg;     // as published, before the torso rescale
  BodyTable bodies[kNumBodies];
  JointLimitTable limits[kNumJoints];
  FrameTable frames[kNumFrames];
};

}  // namespace kuavo::model
