// The independent feasibility oracle of a motion: what the full rigid-body model says about
// it, frame by frame, not the trajectory optimization's own linearization.
//
// q̇ and q̈ come from the frames by finite differences (zero at the two end frames: motions
// start and end at rest); the RNEA gives the generalized force the motion needs. Its base
// rows are the wrench the contacts must supply:
//  - with the optimization's contact forces: joint torques τ = RNEA_joints − J_cᵀf, and the
//    base-wrench residual RNEA_base − J_c,baseᵀf (the centroidal consistency of the forces);
//  - without forces (the geometric motion): the least-norm forces of the stance corners that
//    supply that wrench, then the same; a frame in flight or with the wrench out of the
//    corners' reach keeps a residual.
// Friction pyramids (μ, the MPC's) and unilaterality per stance corner, and the ZMP of the
// contact wrench against the support polygon of the stance corners. Offline; allocates.
#pragma once

#include <array>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/contact_label.h"

namespace kuavo::mocap {

using ForceVector = Eigen::Matrix<double, 3 * model::kNumContactPoints, 1>;

// A force this far outside a friction pyramid is counted as a violation [N] (the optimization's
// relaxed barrier has δ = 1 N).
inline constexpr double kFrictionTolerance_N = 1.0;

struct DynamicsCheck {
  int frames = 0;
  // (frame, joint) samples with |τ| above the model's limit; the ankle pitch and roll slots
  // count their motors A and B against the drives' clamps (drivers/transmission/ankle_motors.h)
  int torque_violations = 0;
  // Where they are: per slot (the ankle pitch / roll slots: motor A / motor B of that ankle
  // when ankle_slots_are_motors), the frames with at least one, and the samples of frames on
  // one foot (where the contact wrench is fixed by the motion: no force distribution helps).
  std::array<int, model::kNumJoints> torque_violations_by_slot{};
  int torque_violation_frames = 0;
  int torque_violations_single_support = 0;
  bool ankle_slots_are_motors = false;
  int friction_violations = 0;  // (frame, stance corner) samples outside the pyramid
  double zmp_outside_m_max = 0.0;
  double max_torque_ratio = 0.0;  // max over frames and joints (ankles: motors) of |τ| / limit
  int max_torque_ratio_joint = -1;
  double base_force_residual_N_max = 0.0, base_force_residual_N_mean = 0.0;
  double base_moment_residual_Nm_max = 0.0, base_moment_residual_Nm_mean = 0.0;
  std::vector<Eigen::Matrix<double, model::kNumJoints, 1>> tau_Nm;  // per frame
  std::vector<Eigen::Vector2d> zmp_m;                              // per frame (NaN without support)
  std::vector<double> zmp_outside_m;                               // per frame, ≥ 0
  std::vector<ForceVector> forces_N;                               // per frame (given or distributed)
};

// forces: one per frame, or nullptr (least-norm distribution). friction_coefficient: the
// pyramid's μ.
void check_dynamics(const model::Model& robot, const std::vector<dynamics::ConfigVector>& q,
                    const std::vector<ContactLabel>& contacts, double rate_hz, const std::vector<ForceVector>* forces,
                    double friction_coefficient, DynamicsCheck& out);

// The generalized velocity taking qa to qb in dt (conventions.h: base twist in qa's base axes;
// the rotation the short way round).
dynamics::VelocityVector config_rate(const dynamics::ConfigVector& qa, const dynamics::ConfigVector& qb, double dt);

// Generalized velocities and accelerations of frames by finite differences (as above).
void frame_rates(const std::vector<dynamics::ConfigVector>& q, double rate_hz,
                 std::vector<dynamics::VelocityVector>& v, std::vector<dynamics::VelocityVector>& a);

}  // namespace kuavo::mocap
