// Geometric motion retargeting (the paper's per-frame weighted QP).
//
// Per 100 Hz frame, a few Gauss–Newton iterations of
//   minimize  Σᵢ ‖Jᵢ Δv − eᵢ‖²_Wᵢ + λ‖Δv‖²   subject to joint position and velocity bounds
// over the generalized velocity step Δv (kNv = 34, conventions.h), warm-started from the
// previous frame. eᵢ is the se(3) error of keypoint i: [p_target − p; log(R_target Rᵀ)] in
// world axes, which is log₆(T⁻¹ T_target) expressed in the local-world-aligned axes our frame
// Jacobians use (rigid_body.h), so the Jacobian and the error agree to first order. Bounds:
//   max(q_min − q, q_prev − q − v_max·dt) ≤ Δq ≤ min(q_max − q, q_prev − q + v_max·dt)
// (kuavo.json continuous velocity limits); the base is free. A bound that is active is
// counted and reported, never hidden.
//
// Contacts (no sliding, no penetration, no floating):
//  - the schedule's stance phases are planned as foot poses (mean human ankle over the phase,
//    sole flat on z = 0, heading clamped to the hip-yaw range); within kPinBlend_s of a phase
//    a free foot is drawn toward that pose, so it arrives flat and in place;
//  - when the schedule says stance the foot lands where it is (flat onto the floor) and locks
//    once it is there: from then on its x, y and yaw are held exactly; the robot's contact
//    labels (the ones written to the motion file) start at that real touchdown;
//  - after the weighted iterations, a minimum-norm projection under the same bounds puts
//    locked feet exactly on their pins and lifts any sole corner of a free foot out of the
//    floor (a weighted objective alone leaves millimetres of compromise whenever a velocity
//    bound is active); free feet near the floor are drawn flat.
// The first frame starts cold: a homotopy from the zero pose to the first targets.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "tools/mocap/contacts.h"
#include "tools/mocap/human_targets.h"

namespace kuavo::mocap {

using dynamics::ConfigVector;

struct RetargetWeights {
  // Squared-norm weights (1/m² and 1/rad²): pelvis and feet high, intermediate joints low.
  double pelvis_position = 20.0, pelvis_rotation = 3.0;
  double ankle = 20.0, toe = 10.0;
  double knee = 2.0, shoulder = 1.0, elbow = 2.0, wrist = 4.0, hand = 2.0, head = 0.5, thumb = 1.0;
  double stance_position = 2.0e4, stance_rotation = 2.0e3;
  double ground = 2.0e4;
  double swing_flat = 500.0;  // free foot near the floor: flat at the human heading
  // Joint motion from the previous frame and change of joint velocity between frames
  // (1/rad²): they damp the frame-to-frame chatter where targets leave joints nearly free
  // (wrist roll, head yaw, a shoulder near gimbal lock with the arm held out sideways) or
  // fight a velocity bound. On the shared clips they cut velocity reversals at more than
  // 1 rad/s by 10–30× for 1–3 mm more mean keypoint error.
  double joint_smoothness = 0.1;
  double joint_acceleration = 1.0;
};

struct RetargetOptions {
  RetargetWeights weights;
  int iterations = 3;               // Gauss–Newton iterations per frame (warm start)
  int first_frame_iterations = 60;  // the first frame starts from the zero pose
  int projection_iterations = 2;    // stance feet put exactly on their pins afterwards
  double damping = 1e-6;            // Levenberg–Marquardt λ
  double step_tolerance = 1e-12;    // stop iterating when ‖Δv‖ is below this
  bool pin_stance_feet = true;
  bool ground_rows = true;  // floor handling: free feet flatten near it, corners stay above it
  bool velocity_limits = true;
};

// Pinned pose of each foot for one frame (from the contact schedule). Within
// kPinBlend_s of a stance phase a free foot is also drawn toward that phase's pose with
// weight blend⁴ × stance weight (blend rises toward touchdown, falls after liftoff; both
// when a short swing sits between two stances), so the foot arrives flat and in place
// instead of jumping there on the touchdown frame.
inline constexpr double kPinBlend_s = 0.12;
struct FootPose2d {
  Vec3 ankle_position_m = Vec3::Zero();  // foot body origin (sole flat on z = 0)
  double yaw_rad = 0.0;
  double blend = 0.0;  // 1 when pinned
};
struct FootPins {
  std::array<bool, 2> pinned{};         // left, right
  std::array<FootPose2d, 2> stance{};   // pinned pose (blend 1) or the approaching stance's
  std::array<FootPose2d, 2> release{};  // the stance just left, while blending out
};
// yaw_clamped_phases (optional) counts stance phases whose heading was limited.
std::vector<FootPins> plan_foot_pins(const HumanTargets& targets, const std::vector<ContactLabel>& labels,
                                     const model::Model& robot, double rate_hz, int* yaw_clamped_phases = nullptr);

struct FrameLimits {
  int position_bounds_active = 0;  // joints ending the frame at a position limit
  int velocity_bounds_active = 0;  // joints ending the frame at the velocity limit
};

// One-frame solver with a preallocated workspace: no allocation per frame.
class Retargeter {
 public:
  Retargeter(const model::Model& robot, const RetargetOptions& options, double rate_hz);
  ~Retargeter();
  Retargeter(const Retargeter&) = delete;
  Retargeter& operator=(const Retargeter&) = delete;

  // Restarts from the zero pose placed on the first target's pelvis.
  void reset();
  FrameLimits step(const TargetFrame& target, const std::array<bool, kNumKeypoints>& present, const FootPins& pins);
  const ConfigVector& q() const { return q_; }
  // The robot's contact state after the last step: feet locked on the floor.
  ContactLabel contact_label() const { return make_label(locked_[0], locked_[1]); }
  // Joints at a bound in the last step (true per joint), for the report.
  const std::array<bool, model::kNumJoints>& at_position_bound() const { return at_position_bound_; }
  const std::array<bool, model::kNumJoints>& at_velocity_bound() const { return at_velocity_bound_; }

 private:
  struct Workspace;
  // Gauss–Newton iterations (then the stance/ground projection) from q_, bounds about q_prev_.
  void solve(const TargetFrame& target, const std::array<bool, kNumKeypoints>& present, const FootPins& pins,
             int iterations, bool velocity_bounds, bool cold_start, bool smooth);
  double keypoint_cost(const TargetFrame& target, const std::array<bool, kNumKeypoints>& present);
  const model::Model& robot_;
  RetargetOptions options_;
  double dt_s_;
  double ankle_height_m_;
  std::array<RobotKeypoint, kNumKeypoints> keypoints_;
  std::array<double, kNumKeypoints> position_weight_{};
  ConfigVector q_, q_prev_, q_prev2_;
  bool started_ = false;
  std::array<bool, 2> locked_{};  // stance foot pinned where it landed
  std::array<FootPose2d, 2> locked_pose_{};
  std::array<int, 2> locked_frames_{};
  std::array<bool, model::kNumJoints> at_position_bound_{}, at_velocity_bound_{};
  std::unique_ptr<Workspace> ws_;
};

struct RetargetReport {
  int frames = 0;
  double duration_s = 0.0;
  double keypoint_error_mean_m = 0.0, keypoint_error_max_m = 0.0;
  double foot_slide_max_m_s = 0.0;  // sole corners of stance feet, horizontal
  double penetration_max_m = 0.0;
  double float_max_m = 0.0;        // highest sole corner of a pinned (stance) foot
  int joint_limit_violations = 0;  // (frame, joint) samples outside the position limits
  int velocity_limit_violations = 0;
  int contact_phases = 0;             // of the robot's labels (feet locked on the floor)
  int schedule_phases = 0;            // of the schedule the retargeting was given
  int stance_yaw_clamped_phases = 0;  // stance headings limited to the hip-yaw range
  long position_bound_active_samples = 0, velocity_bound_active_samples = 0;
  std::array<int, model::kNumJoints> position_bound_active_per_joint{}, velocity_bound_active_per_joint{};
};

struct RetargetResult {
  std::vector<ConfigVector> q;
  std::vector<ContactLabel> contacts;  // the robot's: a foot counts from its real touchdown
  RetargetReport report;
};

// The whole clip: pins from the labels, one step per frame, then the evaluation.
void retarget_motion(const model::Model& robot, const HumanTargets& targets, const std::vector<ContactLabel>& labels,
                     const RetargetOptions& options, RetargetResult& out);

// Metrics of a finished motion against its targets (independent of the solver's own view).
void evaluate_motion(const model::Model& robot, const HumanTargets& targets, RetargetResult& result);

}  // namespace kuavo::mocap
