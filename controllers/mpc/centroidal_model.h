// The MPC's model: full centroidal dynamics (centroidal momentum + full kinematics, OCS2's
// "centroidalModelType 0", FACTS.md §4.2) with analytic first derivatives.
//
// State x (kNx = 38), world axes:
//   [0:3)   ṙ   CoM velocity [m/s]
//   [3:6)   h   angular momentum about the CoM [N·m·s]
//   [6:9)   base_link origin [m]
//   [9:12)  base orientation, ZYX Euler (yaw, pitch, roll) [rad] (wbc_reference.h)
//   [12:38) the 26 body joints (legs, arms; controller order) [rad]; the head is not modelled
//           as a state: its angles are a per-stage parameter, its rates taken as zero.
// Input u (kNu = 50):
//   [0:24)  forces at the 8 sole corners, world axes [N]
//   [24:50) joint velocities of the 26 body joints [rad/s]
// Dynamics f(x, u):
//   r̈ = g + Σf/m,  ḣ = Σ (cᵢ − r) × fᵢ,
//   base twist (base axes) v_b = A_b⁻¹ (Rᵀ[mṙ; h] − A_j q̇_j) with A_G = [A_b A_j] in base
//   axes (the momentum expressed in base axes; base position does not enter),
//   ṗ = R v_b,lin,  ė = E_B(e)⁻¹ ω_b,  q̇_j = u_j.
//
// Derivatives are analytic. Everything is computed with the base at the origin in base axes;
// for joint k (body b) with motion subspace S_k and parent velocity V_λ(k):
//   ∂V_i/∂q_k = S_k ×ₘ (V_i − V_λ(k))          (i in k's subtree)
//   ∂h_O/∂q_k = S_k ×* h_sub(k) − I^c_sub(k) (S_k ×ₘ V_λ(k))
// then shifted to the CoM (∂c/∂q_k = CoM Jacobian column) and rotated by R(e). Each pass is
// O(bodies · depth). tests/mpc/centroidal_model_test.cpp checks them against central finite
// differences and the values against the rigid-body library's A_G (world, quaternion base).
#pragma once

#include <Eigen/Core>
#include <array>

#include "controllers/dynamics/data.h"
#include "controllers/dynamics/rigid_body.h"

namespace kuavo::mpc {

using dynamics::Mat3;
using dynamics::Vec3;
using dynamics::Vec6;

inline constexpr int kNumMpcJoints = 26;  // legs 0–11, arms 12–25; head 26, 27 outside
inline constexpr int kNx = 38;
inline constexpr int kNu = 50;
inline constexpr int kXComVelocity = 0;
inline constexpr int kXMomentum = 3;
inline constexpr int kXBasePosition = 6;
inline constexpr int kXEuler = 9;
inline constexpr int kXJoints = 12;
inline constexpr int kUForces = 0;
inline constexpr int kUJointVelocity = 24;
inline constexpr int kNumPoints = model::kNumContactPoints;
inline constexpr int kPointsPerFoot = 4;

using StateVector = Eigen::Matrix<double, kNx, 1>;
using InputVector = Eigen::Matrix<double, kNu, 1>;
using StateJacobian = Eigen::Matrix<double, kNx, kNx>;
using InputJacobian = Eigen::Matrix<double, kNx, kNu>;
using MotionRowsX = Eigen::Matrix<double, 6, kNx>;
using MotionRowsU = Eigen::Matrix<double, 6, kNu>;
using HeadVector = Eigen::Vector2d;

// The model evaluated at one (x, u). ~40 KB with the scratch Data: static storage only.
// centroidal_evaluate writes the same blocks of base_twist_dx/du, fx and fu every call and
// relies on the rest (structural zeros) keeping the zeros of construction: do not write them.
struct CentroidalPoint {
  dynamics::Data data;  // kinematics with the base at the origin, identity orientation
  std::array<Vec6, model::kNumBodies> subtree_momentum{};  // Σ I_i V_i over the subtree
  double mass_kg = 0.0;
  Mat3 rotation = Mat3::Identity();                 // R(e), base -> world
  std::array<Mat3, 3> rotation_derivative{};        // ∂R/∂(yaw, pitch, roll)
  Mat3 euler_rate_map = Mat3::Identity();           // E_B⁻¹: ė = E_B⁻¹ ω_b
  std::array<Mat3, 3> euler_rate_map_derivative{};  // ∂E_B⁻¹/∂(yaw, pitch, roll)
  Vec3 com_base_m = Vec3::Zero();                   // CoM − base origin, base axes
  Vec6 base_twist = Vec6::Zero();                   // v_b = [v; ω], base axes
  MotionRowsX base_twist_dx = MotionRowsX::Zero();
  MotionRowsU base_twist_du = MotionRowsU::Zero();
  // ∂(A_G v)/∂q_j at fixed v, base axes (CoM moment): the hard term, kept for the tests.
  Eigen::Matrix<double, 6, kNumMpcJoints> momentum_dq = Eigen::Matrix<double, 6, kNumMpcJoints>::Zero();
  StateVector f = StateVector::Zero();
  StateJacobian fx = StateJacobian::Zero();
  InputJacobian fu = InputJacobian::Zero();
};

// Fills p for (x, u) with the given head angles. Real-time safe.
void centroidal_evaluate(const model::Model& model, const StateVector& x, const InputVector& u,
                         const HeadVector& head_rad, CentroidalPoint& p);

// Motion of a point fixed on `body` (position in base axes relative to the base origin, as
// dynamics::frame_position() returns from p.data): rows [linear velocity of the point;
// angular velocity of the body], base axes, and their total derivatives with respect to x and
// u (through v_b too). Requires centroidal_evaluate on p.
void point_motion(const model::Model& model, const CentroidalPoint& p, int body, const Vec3& point_base_m,
                  Vec6& motion, MotionRowsX& motion_dx, MotionRowsU& motion_du);

// The first MPC joint of body's chain when the chain is kLegChain contiguous MPC joints (a
// foot: point_position_jacobian's only nonzero columns are then [lo, lo + kLegChain)), else −1.
inline constexpr int kLegChain = 6;
int leg_chain_first_column(const model::Model& model, int body);

// ∂(point position, base axes)/∂q_j: 3 × 26.
void point_position_jacobian(const model::Model& model, const CentroidalPoint& p, int body,
                             const Vec3& point_base_m, Eigen::Matrix<double, 3, kNumMpcJoints>& jacobian);

// Conversions between (q, v) of conventions.h and the MPC state. state_from_configuration
// uses data as scratch (world kinematics). Real-time safe.
void state_from_configuration(const model::Model& model, dynamics::Data& data, const dynamics::ConfigVector& q,
                              const dynamics::VelocityVector& v, StateVector& x);
dynamics::ConfigVector configuration_from_state(const StateVector& x, const HeadVector& head_rad);

}  // namespace kuavo::mpc
