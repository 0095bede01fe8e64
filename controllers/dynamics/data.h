// Preallocated workspace for the rigid-body algorithms (Pinocchio-style Data).
// ~40 KB: keep one in static storage per user (never on a real-time stack).
#pragma once

#include <Eigen/Core>
#include <array>

#include "controllers/dynamics/spatial.h"
#include "controllers/model/model_tables.h"

namespace kuavo::dynamics {

using model::kNq;
using model::kNv;
using model::kNumBodies;
using model::kNumJoints;
using model::kNumFrames;

using ConfigVector = Eigen::Matrix<double, kNq, 1>;
using VelocityVector = Eigen::Matrix<double, kNv, 1>;
using JointVector = Eigen::Matrix<double, kNumJoints, 1>;
using MassMatrix = Eigen::Matrix<double, kNv, kNv>;
using FrameJacobian = Eigen::Matrix<double, 6, kNv>;
using CentroidalMatrix = Eigen::Matrix<double, 6, kNv>;
using ComJacobian = Eigen::Matrix<double, 3, kNv>;

struct Data {
  // Filled by forward_kinematics(q).
  Vec3 reference_point_m = Vec3::Zero();           // the base origin (see conventions.h)
  std::array<Mat3, kNumBodies> rotation{};         // body axes in world
  std::array<Vec3, kNumBodies> position_m{};       // body origin in world
  std::array<Vec6, kNumBodies> motion_subspace{};  // joint axis as a spatial motion (body 0 unused)
  std::array<SpatialInertia, kNumBodies> inertia{};

  // Filled by forward_kinematics(q, v) and the passes that need velocities.
  std::array<Vec6, kNumBodies> velocity{};
  std::array<Vec6, kNumBodies> acceleration{};  // spatial; bias_accelerations() leaves v̇ = 0, no gravity
  std::array<Vec6, kNumBodies> force{};

  // CRBA / centroidal.
  std::array<SpatialInertia, kNumBodies> composite{};
  MassMatrix mass_matrix = MassMatrix::Zero();
  CentroidalMatrix momentum_matrix_ref = CentroidalMatrix::Zero();  // at the reference point
  CentroidalMatrix centroidal_matrix = CentroidalMatrix::Zero();    // A_G
  Vec6 centroidal_bias = Vec6::Zero();                               // Ȧ_G v
  Vec3 com_m = Vec3::Zero();
  Mat3 centroidal_inertia_kgm2 = Mat3::Zero();
  double total_mass_kg = 0.0;

  VelocityVector tau = VelocityVector::Zero();  // rnea() output
};

}  // namespace kuavo::dynamics
