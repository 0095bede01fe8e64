#include "tools/mocap/dynamic_retarget.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <cmath>
#include <memory>
#include <type_traits>
#include <utility>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"
#include "drivers/config/drivers_config.h"
#include "drivers/transmission/ankle_motors.h"
#include "tools/mocap/dynamics_check.h"
#include "tools/mocap/leg_ik_lm.h"

namespace kuavo::mocap {
namespace {

using dynamics::ConfigVector;
using dynamics::Mat3;
using dynamics::Vec3;
using dynamics::VelocityVector;
using mpc::InputVector;
using mpc::kNumMpcJoints;
using mpc::kNx;
using mpc::StateVector;

constexpr int kForces = 3 * model::kNumContactPoints;
// Forward-difference step of the torque derivatives in the joints and base angles [rad].
constexpr double kTorqueFdStep_rad = 1e-6;
// Stance foot re-solve: a corner missed by more than this lowers the base (up to
// kMaxBaseDrop_m); what remains is counted and reported [m].
constexpr double kFootholdTolerance_m = 2e-3;
constexpr double kMaxBaseDrop_m = 0.02;
// Half-width of the base drop's envelope [s]: a 2 cm drop comes in over 0.4 s (peak
// vertical acceleration about 0.5 m/s², against 170 m/s² lowered frame by frame).
constexpr double kBaseDropSmoothing_s = 0.2;
// The torque terms act on the 12 leg joints, whose torques the contact forces and the leg
// configuration set within one stage. An arm's torque is its own gravity plus its
// acceleration, which spans two stages' inputs (q̈ = Δu/dt): no stage term can move it, a
// penalty on it only pushes the joint angles with a gradient that has no authority. The
// oracle checks the arms. The gradient is capped (Huber: linear past the cap) so a wild
// warm-start guess at a window's tail cannot throw the step.
constexpr int kLegs = 2 * model::kLegJoints;
constexpr double kTorqueExcessCap_Nm = 20.0;
constexpr double kMinStep = 1.0 / 64.0;
// Cold restarts of one window after a failed QP before the retargeting gives up.
constexpr int kMaxRestarts = 3;
// Step rejection: violation after a step above growth × before + slack (see the loop).
constexpr double kViolationGrowth = 1.5;
constexpr double kViolationSlack = 0.02;

// x with its base Euler angles moved by whole turns onto the branch of `ref`'s (a yaw through
// ±π would otherwise interpolate or average the long way round).
StateVector on_branch_of(StateVector x, const StateVector& ref) {
  for (int e = 0; e < 3; ++e) {
    const int i = mpc::kXEuler + e;
    x[i] += 2.0 * M_PI * std::round((ref[i] - x[i]) / (2.0 * M_PI));
  }
  return x;
}

// Uniform Catmull-Rom between p1 (s = 0) and p2 (s = 1).
template <class V>
V catmull_rom(const V& p0, const V& p1, const V& p2, const V& p3, double s) {
  const double s2 = s * s, s3 = s2 * s;
  return 0.5 * ((2.0 * p1) + (-p0 + p2) * s + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2 +
                (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * s3);
}

void quasi_static_torques(const model::Model& robot, dynamics::Data& data, const ConfigVector& q,
                            const InputVector& u, const planner::ContactFlags& contact,
                            Eigen::Matrix<double, kNumMpcJoints, 1>& tau,
                            Eigen::Matrix<double, kNumMpcJoints, kForces>* d_df) {
  dynamics::forward_kinematics(robot, data, q);
  dynamics::forward_velocities(robot, data, VelocityVector::Zero());
  dynamics::rnea(robot, data, VelocityVector::Zero(), true);
  tau = data.tau.segment<kNumMpcJoints>(6);
  if (d_df) d_df->setZero();
  dynamics::FrameJacobian j;
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    if (!contact[c]) continue;
    dynamics::frame_jacobian(robot, data, c, j);
    const auto jl = j.topRows<3>().middleCols<kNumMpcJoints>(6);
    tau.noalias() -= jl.transpose() * u.segment<3>(mpc::kUForces + 3 * c);
    if (d_df) d_df->middleCols<3>(3 * c) = -jl.transpose();
  }
}


// A stage's stance ankles: which feet stand, the stage's quasi-static torques and their force
// derivatives, and the linkage map at its ankle angles. False: no foot stands, or the map fails.
struct StanceAnkles {
  std::array<bool, 2> stance{};
  Eigen::Matrix<double, kNumMpcJoints, 1> tau;
  Eigen::Matrix<double, kNumMpcJoints, kForces> d_df;
  hal::AnkleMotorLimits map;
};
bool stance_ankles(const model::Model& robot, dynamics::Data& data, const drivers::AnkleMotors& motors,
                   const StateVector& x, const InputVector& u, const mpc::HeadVector& head_rad,
                   const planner::ContactFlags& contact, StanceAnkles& out) {
  out.stance = {};
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    out.stance[c / mpc::kPointsPerFoot] = out.stance[c / mpc::kPointsPerFoot] || contact[c];
  }
  if (!out.stance[0] && !out.stance[1]) return false;
  quasi_static_torques(robot, data, mpc::configuration_from_state(x, head_rad), u, contact, out.tau, &out.d_df);
  std::array<Eigen::Vector2d, 2> ankle_rad;
  for (int leg = 0; leg < 2; ++leg) {
    const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + model::kAnklePitchInLeg;
    ankle_rad[leg] = Eigen::Vector2d(x[mpc::kXJoints + j], x[mpc::kXJoints + j + 1]);
  }
  return drivers::map_ankle_motors_rt(motors, ankle_rad, out.map);
}

// The ankle-motor hinge of one stage (DynamicRetargetConfig::ankle_motor_weight; w_dt its
// weight × the stage length): per stance ankle and motor, ½ w (|τ_motor| − s·L)² above s·L on
// the quasi-static joint torques mapped at the stage's ankle angles, Gauss-Newton on the forces.
using Stage = std::remove_reference_t<decltype(std::declval<mpc::Ocp&>().stages[0])>;
void add_ankle_motor_hinge(const model::Model& robot, dynamics::Data& data, const drivers::AnkleMotors& motors,
                           double w_dt, double share, const StateVector& x, const InputVector& u,
                           const mpc::HeadVector& head_rad, const planner::ContactFlags& contact, Stage& stage) {
  StanceAnkles sa;
  if (!stance_ankles(robot, data, motors, x, u, head_rad, contact, sa)) return;
  const auto& stance = sa.stance;
  const auto& tau = sa.tau;
  const auto& d_df = sa.d_df;
  const auto& map = sa.map;
  for (int leg = 0; leg < 2; ++leg) {
    if (!stance[leg]) continue;
    const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + model::kAnklePitchInLeg;
    for (int m = 0; m < 2; ++m) {
      const double a = map.joint_to_motor[leg](m, 0), b = map.joint_to_motor[leg](m, 1);
      const double motor = a * tau[j] + b * tau[j + 1];
      const double excess = std::abs(motor) - share * map.limit_Nm[leg](m);
      if (excess <= 0.0) continue;
      const Eigen::Matrix<double, kForces, 1> g = a * d_df.row(j).transpose() + b * d_df.row(j + 1).transpose();
      stage.R.topLeftCorner<kForces, kForces>().noalias() += w_dt * g * g.transpose();
      stage.r.head<kForces>().noalias() += (w_dt * excess * (motor > 0.0 ? 1.0 : -1.0)) * g;
    }
  }
}

// The standing pose's ankle loading (DynamicRetargetConfig::ankle_effort_weight): toe_share,
// the share of a sole's normal force its toe corners carry when its centre of pressure lies
// under the standing pose's CoM (4.9 cm ahead of the ankles on the 4Pro), from the planning
// model's own corners; ahead, the sign of the ankle pitch torque beyond standing's that holds
// a centre of pressure ahead of that point (the left foot's weight moved onto its toes).
struct StandingAnkles {
  double toe_share = 0.5;
  double ahead = 1.0;
};
StandingAnkles standing_ankles(const model::Model& robot, dynamics::Data& data) {
  ConfigVector q = dynamics::neutral_configuration(robot);
  q.tail<model::kNumJoints>() = control::centred_standing_pose(robot, data, control::StandingConfig{}.base_height_m);
  control::place_on_ground(robot, data, q);
  dynamics::forward_kinematics(robot, data, q);
  dynamics::crba(robot, data);
  const auto ankle = [&](int leg) { return data.position_m[1 + leg * model::kLegJoints + model::kAnklePitchInLeg]; };
  const Vec3 forward = data.rotation[1 + model::kAnklePitchInLeg + 1] * Vec3::UnitX();
  const double lead = forward.dot(data.com_m - 0.5 * (ankle(0) + ankle(1)));
  double toe_x = 0.0, heel_x = 0.0;  // the left sole's toe and heel corners, in its frame
  for (int k = 0; k < mpc::kPointsPerFoot; ++k) {
    const double x = robot.frames[k].position_m.x();
    (x > 0.0 ? toe_x : heel_x) += x / (0.5 * mpc::kPointsPerFoot);
  }
  StandingAnkles out;
  out.toe_share = std::clamp((lead - heel_x) / (toe_x - heel_x), 0.0, 1.0);
  planner::ContactFlags left{};
  for (int k = 0; k < mpc::kPointsPerFoot; ++k) left[k] = true;
  const double weight = robot.total_mass_kg * 9.81;
  InputVector on_toes = InputVector::Zero(), as_standing = InputVector::Zero();
  for (int k = 0; k < mpc::kPointsPerFoot; ++k) {
    const bool toe = robot.frames[k].position_m.x() > 0.0;
    on_toes[3 * k + 2] = toe ? weight / (0.5 * mpc::kPointsPerFoot) : 0.0;
    as_standing[3 * k + 2] = weight * (toe ? out.toe_share : 1.0 - out.toe_share) / (0.5 * mpc::kPointsPerFoot);
  }
  Eigen::Matrix<double, kNumMpcJoints, 1> tau_toes, tau_standing;
  quasi_static_torques(robot, data, q, on_toes, left, tau_toes, nullptr);
  quasi_static_torques(robot, data, q, as_standing, left, tau_standing, nullptr);
  const int j = model::kLeftLegFirst + model::kAnklePitchInLeg;
  out.ahead = tau_toes[j] - tau_standing[j] > 0.0 ? 1.0 : -1.0;
  return out;
}

// The ankle-effort cost of one stage (w_dt: ankle_effort_weight × the stage length), per stance
// ankle on its quasi-static torques minus those of P f (the foot's normal force spread over its
// corners as in standing, no horizontal force; the foot's own weight cancels): ½ w k_p e_p² on
// the pitch e_p where it holds the centre of pressure ahead of standing's (zero behind it), and
// ½ w k_r e_r² on the roll, k_p and k_r what a unit pitch and a unit roll ask of the two motors
// (Σ a², Σ b² of the linkage map at the stage's ankle angles: ~0.5 and ~2.4). Linear in f:
// Gauss-Newton on the forces is its exact Hessian (the pitch part's is C¹ at zero).
void add_ankle_effort_cost(const model::Model& robot, dynamics::Data& data, const drivers::AnkleMotors& motors,
                           double w_dt, const StandingAnkles& standing, const StateVector& x, const InputVector& u,
                           const mpc::HeadVector& head_rad, const planner::ContactFlags& contact, Stage& stage) {
  StanceAnkles sa;
  if (!stance_ankles(robot, data, motors, x, u, head_rad, contact, sa)) return;
  const auto& stance = sa.stance;
  const auto& d_df = sa.d_df;
  const auto& map = sa.map;
  const Eigen::Matrix<double, kForces, 1> f = u.head<kForces>();
  for (int leg = 0; leg < 2; ++leg) {
    if (!stance[leg]) continue;
    const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + model::kAnklePitchInLeg;
    const int c0 = leg * mpc::kPointsPerFoot;
    for (int axis = 0; axis < 2; ++axis) {  // pitch, roll
      const double k = map.joint_to_motor[leg].col(axis).squaredNorm();
      // (I − P)ᵀ g: P moves the foot's normal forces to the standing spread.
      Eigen::Matrix<double, kForces, 1> gc = d_df.row(j + axis).transpose();
      double spread = 0.0;
      for (int c = c0; c < c0 + mpc::kPointsPerFoot; ++c) {
        const bool toe = robot.frames[c].position_m.x() > 0.0;
        spread += gc[3 * c + 2] * (toe ? standing.toe_share : 1.0 - standing.toe_share) / (0.5 * mpc::kPointsPerFoot);
      }
      for (int c = c0; c < c0 + mpc::kPointsPerFoot; ++c) gc[3 * c + 2] -= spread;
      const double e = gc.dot(f);
      if (axis == 0 && !(standing.ahead * e > 0.0)) continue;
      stage.R.topLeftCorner<kForces, kForces>().noalias() += (w_dt * k) * gc * gc.transpose();
      stage.r.head<kForces>().noalias() += (w_dt * k * e) * gc;
    }
  }
}

}  // namespace

mpc::MpcConfig DynamicRetargetConfig::default_ocp() {
  mpc::MpcConfig c;
  c.plan_output = false;
  c.horizon_s = 1.0;
  // Offline the swing feet follow the reference swing closely (Leju's 500 m⁻²; the online
  // MPC keeps 50 so the robot may step out of trouble).
  c.weight_swing_xy = 2.0e4;
  c.stance_position_gain_1_s = 10.0;
  // Its windows commit stages read at dt_s (and take windows from 0.2 s): a uniform grid.
  c.tail_stride = 1;
  return c;
}

void DynamicRetargetConfig::set_horizon(double horizon_s) {
  ocp.horizon_s = horizon_s;
  const int stages = static_cast<int>(std::lround(horizon_s / ocp.dt_s));
  commit_stages = std::clamp(stages / 4, 1, 10);
}

void stage_torque(const model::Model& robot, dynamics::Data& data, const StateVector& x, const InputVector& u,
                  const mpc::HeadVector& head_rad, const planner::ContactFlags& contact, bool with_derivatives,
                  StageTorque& out) {
  const ConfigVector q = mpc::configuration_from_state(x, head_rad);
  Eigen::Matrix<double, kNumMpcJoints, kForces> d_df;
  quasi_static_torques(robot, data, q, u, contact, out.tau_Nm, with_derivatives ? &d_df : nullptr);
  if (!with_derivatives) return;
  out.d_du.setZero();
  out.d_du.leftCols<kForces>() = d_df;
  out.d_dx.setZero();
  Eigen::Matrix<double, kNumMpcJoints, 1> tau_p;
  const auto column = [&](int i) {
    StateVector xp = x;
    xp[i] += kTorqueFdStep_rad;
    quasi_static_torques(robot, data, mpc::configuration_from_state(xp, head_rad), u, contact, tau_p, nullptr);
    out.d_dx.col(i) = (tau_p - out.tau_Nm) / kTorqueFdStep_rad;
  };
  for (int e = 0; e < 3; ++e) column(mpc::kXEuler + e);
  for (int j = 0; j < kNumMpcJoints; ++j) column(mpc::kXJoints + j);
}

namespace {

// The bilinear weights of point (x, y) of a foot's sole in its four corners (foot frame x-y):
// w[k] ≥ 0, Σ w = 1 and Σ w[k] corner[k] = (x, y) for a point inside the corners' rectangle.
std::array<double, 4> sole_weights(const model::Model& robot, int foot, double x, double y) {
  double x_lo = 1e9, x_hi = -1e9, y_lo = 1e9, y_hi = -1e9;
  for (int k = 0; k < 4; ++k) {
    const Vec3& p = robot.frames[4 * foot + k].position_m;
    x_lo = std::min(x_lo, p.x()), x_hi = std::max(x_hi, p.x());
    y_lo = std::min(y_lo, p.y()), y_hi = std::max(y_hi, p.y());
  }
  const double a = (x - x_lo) / (x_hi - x_lo), b = (y - y_lo) / (y_hi - y_lo);
  std::array<double, 4> w;
  for (int k = 0; k < 4; ++k) {
    const Vec3& p = robot.frames[4 * foot + k].position_m;
    const bool front = p.x() - x_lo > x_hi - p.x(), left = p.y() - y_lo > y_hi - p.y();
    w[k] = (front ? a : 1.0 - a) * (left ? b : 1.0 - b);
  }
  return w;
}

}  // namespace

model::Model planning_model(const model::Model& robot, double support_margin_m) {
  const drivers::AnkleMotors motors = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot));
  model::Model planning = robot;
  for (int leg = 0; leg < 2 && motors.active; ++leg) {
    const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + model::kAnklePitchInLeg;
    for (int k = 0; k < 2; ++k) {
      planning.limits.torque_Nm[j + k] = std::min(planning.limits.torque_Nm[j + k], motors.limit_Nm[leg].minCoeff());
    }
  }
  model::inset_sole_corners(planning, support_margin_m);
  return planning;
}

CornerForces forces_on_robot_corners(const model::Model& robot, const model::Model& planning, const CornerForces& f) {
  CornerForces out = CornerForces::Zero();
  for (int foot = 0; foot < 2; ++foot) {
    for (int i = 0; i < 4; ++i) {
      const Vec3& q = planning.frames[4 * foot + i].position_m;
      const std::array<double, 4> w = sole_weights(robot, foot, q.x(), q.y());
      for (int k = 0; k < 4; ++k) out.segment<3>(3 * (4 * foot + k)) += w[k] * f.segment<3>(3 * (4 * foot + i));
    }
  }
  return out;
}

bool dynamic_retarget(const model::Model& robot_model, const planner::MotionPlan& plan, const DynamicRetargetConfig& cfg,
                      DynamicResult& out, std::string& error) {
  if (!(cfg.support_margin_m >= 0.0 && cfg.support_margin_m <= 0.04)) {
    error = "dynamic retargeting: support_margin_m must be within 0..0.04 m (the sole is 0.095 m wide)";
    return false;
  }
  if (!(cfg.ankle_motor_weight >= 0.0 && std::isfinite(cfg.ankle_motor_weight)) ||
      !(cfg.ankle_motor_share > 0.0 && cfg.ankle_motor_share <= 1.0)) {
    error = "dynamic retargeting: ankle_motor_weight must be finite and >= 0, ankle_motor_share within (0, 1]";
    return false;
  }
  if (!(cfg.ankle_effort_weight >= 0.0 && std::isfinite(cfg.ankle_effort_weight))) {
    error = "dynamic retargeting: ankle_effort_weight must be finite and >= 0";
    return false;
  }
  const model::Model robot = planning_model(robot_model, cfg.support_margin_m);
  const auto t_start = std::chrono::steady_clock::now();
  if (const char* why = mpc::mpc_validate_config(cfg.ocp)) {
    error = std::string("dynamic retargeting: ") + why;
    return false;
  }
  if (cfg.ocp.tail_stride != 1) {  // the windows commit and read stages as frames dt_s apart
    error = "dynamic retargeting: the OCP must use a uniform grid (tail_stride 1)";
    return false;
  }
  if (cfg.stage_smoothing_passes < 0 || cfg.stage_smoothing_passes > 8) {
    error = "dynamic retargeting: stage_smoothing_passes must be within 0..8";
    return false;
  }
  if (cfg.commit_stages < 1 || cfg.max_sqp_iterations < 1 || !(cfg.step_tolerance > 0.0) ||
      !(cfg.tail_step_tolerance >= cfg.step_tolerance && std::isfinite(cfg.tail_step_tolerance))) {
    error = "dynamic retargeting: commit_stages and max_sqp_iterations must be >= 1, step_tolerance > 0, "
            "tail_step_tolerance finite and >= step_tolerance";
    return false;
  }
  if (plan.frame_count < 2) {
    error = "dynamic retargeting: the motion needs at least 2 frames";
    return false;
  }
  if (!plan.foot_contact[0][0] || !plan.foot_contact[0][1]) {
    error = "dynamic retargeting: the motion must start standing in double support";
    return false;
  }
  for (int i = 0; i < plan.frame_count; ++i) {
    if (!plan.q[i].allFinite()) {  // the velocities are differences of these frames
      error = "dynamic retargeting: frame " + std::to_string(i) + " is not finite";
      return false;
    }
    if (!plan.foot_contact[i][0] && !plan.foot_contact[i][1]) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "dynamic retargeting: flight at %.2f s (frame %d): the robot cannot leave the floor with both "
                    "feet (a flight repair was forbidden?)",
                    i / plan.rate_hz, i);
      error = buf;
      return false;
    }
  }

  const mpc::MpcConfig& ocp = cfg.ocp;
  auto ws = std::make_unique<mpc::MpcWorkspace>();
  mpc::mpc_init(robot, ocp, *ws);
  auto window = std::make_unique<planner::PlanWindow>();
  auto data = std::make_unique<dynamics::Data>();
  const int T = ws->horizon;
  const double dt = ocp.dt_s;
  const hal::TimeNs dt_ns = static_cast<hal::TimeNs>(std::llround(dt * 1e9));
  const double duration = planner::motion_plan_duration_s(plan);
  const int S = static_cast<int>(std::ceil(duration / dt - 1e-9));
  const double mg = robot.total_mass_kg * model::kGravity_m_s2;

  std::vector<StateVector> xs(S + 1);
  std::vector<InputVector> us(S + 1);
  std::vector<mpc::HeadVector> heads(S + 1);
  std::vector<planner::ContactFlags> flags(S + 1);
  StateVector x0;
  mpc::state_from_configuration(robot, *data, plan.q[0], planner::motion_plan_velocity(plan, 0), x0);
  // Where each stance corner landed in the committed trajectory: the stance rows hold it
  // there (not on the reference's foothold, which the swing cost only approaches; pulling a
  // landed foot onto it would slide it).
  using Anchors = std::array<Vec3, model::kNumContactPoints>;
  std::vector<Anchors> anchors(S + 1);
  int previous_commit = 0;  // stages the last window committed (the next build shifts by it)
  Anchors anchor;
  std::array<bool, model::kNumContactPoints> anchored{};
  dynamics::forward_kinematics(robot, *data, plan.q[0]);
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    anchor[c] = dynamics::frame_position(robot, *data, c);
    anchored[c] = true;  // the motion starts in double support
  }
  anchors[0] = anchor;

  const auto& lim = robot.limits;
  const drivers::AnkleMotors ankle_motors = drivers::ankle_motors_from_config(drivers::default_drivers_config(robot_model));
  const StandingAnkles standing_ankle_load = standing_ankles(robot, *data);
  const Eigen::Matrix<double, kNumMpcJoints, 1> soft_start = cfg.torque_soft_start * lim.torque_Nm.head<kNumMpcJoints>();
  Eigen::Matrix<double, kNumMpcJoints, 1> vel_limit = lim.velocity_rad_s.head<kNumMpcJoints>();
  std::vector<Eigen::Matrix<double, kNumMpcJoints, 1>> lag(T + 1);
  std::vector<StateVector> x_accepted(T + 1), dx_accepted(T + 1);
  std::vector<InputVector> u_accepted(T + 1), du_accepted(T + 1);
  StageTorque st_torque;
  long iterations_total = 0;
  DynamicStats& stats = out.stats;
  stats = DynamicStats{};

  for (int s0 = 0; s0 < S;) {
    planner::motion_plan_window_rt(robot, *data, plan, plan.start_ns + s0 * dt_ns, dt, T + 1, *window);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      if (!anchored[c]) continue;
      for (int k = 0; k <= T && window->knots[k].in_contact[c]; ++k) {
        window->knots[k].point_position_m.segment<3>(3 * c) = anchor[c];
      }
    }
    int it = 0;
    // Where ws->x holds the point the next build linearizes stage k at: k + unshifted before a
    // window's first build (the build shifts the warm start by the stages committed since,
    // mpc.cpp), k after it; −1 before a cold start (the first window, a restart), which begins
    // from the reference. Read at k alone, a window's first iteration held each touchdown
    // where the foot was 0.2 s before it, mid-swing, and its QP then dragged the leg there and
    // back: measured (1.2 s windows, `--verify 0`) on the built-in dance 31.0 → 16.2 SQP
    // iterations a window for the same solution (oracle figures within 3 %), cmu_05_07
    // 35.2 → 25.6, cmu_05_20 26.2 → 21.2, rejected steps 232 → 15 in the built-in dance.
    int unshifted = s0 > 0 ? previous_commit : -1;
    bool converged = false;
    double alpha = 1.0, previous_step = std::numeric_limits<double>::infinity();
    int progress = 0, restarts = 0;
    bool have_accepted = false;
    double accepted_violation = 0.0;
    while (it < cfg.max_sqp_iterations) {
      // The builds rewrite what they own; the terms below touch R's force block across
      // corners, which they do not: cleared here. (Nothing writes S: mpc_init zeroes it once
      // and declares it zero, OcpStage::s_zero, so the Riccati does not read it.)
      for (int k = 0; k < T; ++k) ws->qp.stages[k].R.topLeftCorner<kForces, kForces>().setZero();
      // A touchdown inside the window holds the corner where the current iterate lands it.
      // A cold start keeps the reference's footholds (or, after a restart, the last landings).
      for (int k = 1; k <= T && unshifted >= 0; ++k) {
        const planner::ContactFlags& now = window->knots[k].in_contact;
        const planner::ContactFlags& before = window->knots[k - 1].in_contact;
        bool fk_done = false;
        for (int c = 0; c < model::kNumContactPoints; ++c) {
          if (!now[c] || before[c]) continue;
          if (!fk_done) {
            // Past the old horizon the build repeats its last state.
            const int j = std::min(k + unshifted, T);
            dynamics::forward_kinematics(robot, *data, mpc::configuration_from_state(ws->x[j], ws->head_rad[j]));
            fk_done = true;
          }
          const Vec3 landed = dynamics::frame_position(robot, *data, c);
          for (int m = k; m <= T && window->knots[m].in_contact[c]; ++m) {
            window->knots[m].point_position_m.segment<2>(3 * c) = landed.head<2>();
          }
        }
      }
      mpc::MpcStatus status = mpc::mpc_build_qp_from_state_rt(robot, ocp, *ws, x0, *window);
      unshifted = 0;
      if (status != mpc::MpcStatus::kOk) {
        error = std::string("dynamic retargeting: window at ") + std::to_string(s0 * dt) + " s: " + mpc::to_string(status);
        return false;
      }
      // Globalization by the constraint violation (the dynamics defects and equality rows at
      // this iterate): a step that made it grow past kViolationGrowth × the accepted point's
      // (plus kViolationSlack) is taken back and retried at half the length along the same
      // direction, so a window that cannot converge stalls near a consistent trajectory
      // instead of walking off (perfume at 19.6 s: steps of 15, violation 1.5).
      if (have_accepted && alpha > kMinStep &&
          ws->constraint_violation > kViolationGrowth * accepted_violation + kViolationSlack) {
        alpha = std::max(kMinStep, 0.5 * alpha);
        progress = 0;
        ++stats.rejected_steps;
        for (int k = 0; k <= T; ++k) {
          ws->x[k] = x_accepted[k] + alpha * dx_accepted[k];
          ws->u[k] = u_accepted[k] + alpha * du_accepted[k];
        }
        ws->u[T] = ws->u[T - 1];
        if (++it >= cfg.max_sqp_iterations) break;
        continue;
      }
      have_accepted = true;
      accepted_violation = ws->constraint_violation;
      for (int k = 0; k <= T; ++k) {
        x_accepted[k] = ws->x[k];
        u_accepted[k] = ws->u[k];
      }
      // The dynamic part of the torques (M q̈ + C q̇) of the current iterate, held fixed.
      // The last stage's acceleration would involve x_T, which only u_{T−1} sets: a lag there
      // feeds back on itself (the iteration then walks off along x_T); it takes stage T−2's.
      // Only with the torque term on (it cost a third of each iteration for nothing).
      const bool torque_term = cfg.torque_penalty_weight > 0.0;
      for (int k = 0; torque_term && k + 1 < T; ++k) {
        const ConfigVector qk = mpc::configuration_from_state(ws->x[k], ws->head_rad[k]);
        const ConfigVector qn = mpc::configuration_from_state(ws->x[k + 1], ws->head_rad[k + 1]);
        const ConfigVector qp = k > 0 ? mpc::configuration_from_state(ws->x[k - 1], ws->head_rad[k - 1]) : qk;
        const VelocityVector v_out = mocap::config_rate(qk, qn, dt);
        const VelocityVector v_in = k > 0 ? mocap::config_rate(qp, qk, dt) : v_out;
        const VelocityVector v = 0.5 * (v_in + v_out);
        const VelocityVector a = k > 0 ? VelocityVector((v_out - v_in) / dt) : VelocityVector::Zero();
        dynamics::forward_kinematics(robot, *data, qk);
        dynamics::forward_velocities(robot, *data, v);
        dynamics::rnea(robot, *data, a, false);
        lag[k] = data->tau.segment<kNumMpcJoints>(6);
        dynamics::forward_velocities(robot, *data, VelocityVector::Zero());
        dynamics::rnea(robot, *data, VelocityVector::Zero(), false);
        lag[k] -= data->tau.segment<kNumMpcJoints>(6);
      }
      lag[T - 1] = T >= 2 ? lag[T - 2] : Eigen::Matrix<double, kNumMpcJoints, 1>::Zero();
      for (int k = 0; k < T; ++k) {
        auto& stage = ws->qp.stages[k];
        const planner::ContactFlags& contact = window->knots[k].in_contact;
        Eigen::Matrix<double, kNumMpcJoints, 1> tau = Eigen::Matrix<double, kNumMpcJoints, 1>::Zero();
        if (torque_term && k + cfg.commit_stages < T) {
          stage_torque(robot, *data, ws->x[k], ws->u[k], ws->head_rad[k], contact, false, st_torque);
          tau = st_torque.tau_Nm + lag[k];
        }
        const bool legs_near_limit =
            (tau.head<kLegs>().cwiseAbs().array() > soft_start.head<kLegs>().array()).any();
        if (torque_term && k + cfg.commit_stages < T && legs_near_limit) {
          stage_torque(robot, *data, ws->x[k], ws->u[k], ws->head_rad[k], contact, true, st_torque);
          for (int j = 0; j < kLegs; ++j) {
            const double excess = std::min(std::abs(tau[j]) - soft_start[j], kTorqueExcessCap_Nm);
            if (excess <= 0.0) continue;
            // ½ w e², e = |τ| − τ_soft: gradient w e sign(τ) ∇τ, Gauss-Newton Hessian w ∇τ∇τᵀ.
            const double w = dt * cfg.torque_penalty_weight;
            const double g = w * excess * (tau[j] > 0.0 ? 1.0 : -1.0);
            const auto gx = st_torque.d_dx.row(j).transpose();
            const auto gu = st_torque.d_du.row(j).transpose();
            // Hessian: the force block exactly, the state part on the diagonal and no cross
            // term (the whole rank-one product, scaled by w·|∂τ/∂q|² ~ 1e4 against the joint
            // weights ~6, left the Riccati's Schur complements to roundoff: not_convex).
            stage.Q.diagonal().noalias() += w * gx.cwiseAbs2();
            stage.q.noalias() += g * gx;
            stage.R.topLeftCorner<kForces, kForces>().noalias() += w * gu.head<kForces>() * gu.head<kForces>().transpose();
            stage.r.head<kForces>().noalias() += g * gu.head<kForces>();
          }
          ws->swing_block_written[k] = true;  // the next build clears Q's joint block
        }
        if (cfg.ankle_effort_weight > 0.0 && ankle_motors.active) {
          add_ankle_effort_cost(robot, *data, ankle_motors, cfg.ankle_effort_weight * dt, standing_ankle_load,
                                ws->x[k], ws->u[k], ws->head_rad[k], contact, stage);
        }
        if (cfg.ankle_motor_weight > 0.0 && ankle_motors.active) {
          add_ankle_motor_hinge(robot, *data, ankle_motors, cfg.ankle_motor_weight * dt, cfg.ankle_motor_share, ws->x[k],
                                ws->u[k], ws->head_rad[k], contact, stage);
        }
        for (int j = 0; j < kNumMpcJoints; ++j) {
          const int col = mpc::kUJointVelocity + j;
          const double w = ws->u[k][col];
          double d1a, d2a, d1b, d2b;
          mpc::relaxed_barrier(vel_limit[j] - w, cfg.velocity_barrier_mu, cfg.velocity_barrier_delta_rad_s, d1a, d2a);
          mpc::relaxed_barrier(vel_limit[j] + w, cfg.velocity_barrier_mu, cfg.velocity_barrier_delta_rad_s, d1b, d2b);
          stage.R(col, col) += dt * (d2a + d2b);
          stage.r[col] += dt * (d1b - d1a);
        }
      }
      status = mpc::mpc_solve_qp_rt(*ws);
      ++it;
      if (status != mpc::MpcStatus::kOk && restarts < kMaxRestarts) {
        // A QP the Riccati cannot factor (a Schur complement lost definiteness far from the
        // reference): the window starts over from the reference, a cold start.
        ++stats.qp_failures;
        ++restarts;
        mpc::mpc_reset(*ws);
        unshifted = -1;
        have_accepted = false;
        alpha = 1.0;
        previous_step = std::numeric_limits<double>::infinity();
        progress = 0;
        continue;
      }
      if (status != mpc::MpcStatus::kOk) {
        ++stats.qp_failures;
        error = "dynamic retargeting: the QP of the window at " + std::to_string(s0 * dt) + " s failed (" +
                qp::to_string(ws->qp_status) + ", iteration " + std::to_string(it) + ")";
        return false;
      }
      for (int k = 0; k <= T; ++k) {
        dx_accepted[k] = ws->solution.x[k];
        du_accepted[k] = k < T ? InputVector(ws->solution.u[k]) : InputVector::Zero();
      }
      // The step over the stages this window commits (states 0 … n, their inputs and u_n)
      // and over the whole window.
      double step = 0.0, step_committed = 0.0;
      const int n_committed = std::min(cfg.commit_stages, T);
      for (int k = 0; k <= T; ++k) {
        step = std::max(step, ws->solution.x[k].cwiseAbs().maxCoeff());
        if (k < T) {
          step = std::max(step, ws->solution.u[k].tail<kNumMpcJoints>().cwiseAbs().maxCoeff());
          step = std::max(step, ws->solution.u[k].head<kForces>().cwiseAbs().maxCoeff() / mg);
        }
        if (k == n_committed) step_committed = step;
      }
      if (!std::isfinite(step)) {
        error = "dynamic retargeting: non-finite iterate in the window at " + std::to_string(s0 * dt) + " s";
        return false;
      }
      // Step control: the torque terms (lagged dynamic part, derivatives by differences) make
      // the full-step iteration cycle between two points near the limits, and without the
      // torque terms some windows still cycle (no step control: cmu_05_20 46.5 iterations a
      // window, 4 at the cap); a step larger than the one before is taken at a fraction
      // (halved each time, doubled back after two that shrank). Demanding that each step
      // contract by 0.2·fraction (as before) stalled windows at the smallest fraction while
      // the steps shrank by 0.2 % an iteration (cmu_05_07 at 10.6 s: 170 iterations at 1/64,
      // the cap); measured with the landing fix (1.2 s windows, built-in / cmu_05_07 /
      // cmu_05_20): 16.2 / 25.6 / 21.2 → 15.1 / 23.4 / 21.2 iterations a window, none at the
      // cap.
      if (step > previous_step) {
        alpha = std::max(kMinStep, 0.5 * alpha);
        progress = 0;
      } else if (++progress >= 2) {
        alpha = std::min(1.0, 2.0 * alpha);
      }
      previous_step = step;
      if (alpha < 1.0) {
        for (int k = 0; k <= T; ++k) {
          ws->x[k] -= (1.0 - alpha) * ws->solution.x[k];
          if (k < T) ws->u[k] -= (1.0 - alpha) * ws->solution.u[k];
        }
        ws->u[T] = ws->u[T - 1];
      }
      if (step_committed < cfg.step_tolerance && step < cfg.tail_step_tolerance) {
        converged = true;
        break;
      }
    }
    ++stats.windows;
    iterations_total += it;
    stats.sqp_iterations_max = std::max(stats.sqp_iterations_max, it);
    if (!converged) ++stats.windows_not_converged;
    const int n_commit = std::min(cfg.commit_stages, S - s0);
    for (int j = 0; j < n_commit; ++j) {
      xs[s0 + j] = ws->x[j];
      us[s0 + j] = ws->u[j];
      heads[s0 + j] = ws->head_rad[j];
      flags[s0 + j] = window->knots[j].in_contact;
    }
    x0 = ws->x[n_commit];
    heads[s0 + n_commit] = ws->head_rad[n_commit];
    flags[s0 + n_commit] = window->knots[n_commit].in_contact;
    for (int j = 1; j <= n_commit; ++j) {
      const planner::ContactFlags& now = window->knots[j].in_contact;
      bool fk_done = false;
      for (int c = 0; c < model::kNumContactPoints; ++c) {
        if (!now[c]) {
          anchored[c] = false;
        } else if (!anchored[c]) {  // touchdown: held where it landed, on the floor's height
          if (!fk_done) {
            dynamics::forward_kinematics(robot, *data, mpc::configuration_from_state(ws->x[j], ws->head_rad[j]));
            fk_done = true;
          }
          const Vec3 landed = dynamics::frame_position(robot, *data, c);
          anchor[c] = landed;
          anchored[c] = true;
        }
      }
      anchors[s0 + j] = anchor;
    }
    s0 += n_commit;
    previous_commit = n_commit;
    if (cfg.on_progress) cfg.on_progress(static_cast<double>(s0) / S);
  }
  xs[S] = x0;
  us[S] = us[S - 1];
  out.stage_x = xs;
  out.stage_u = us;
  out.stage_head = heads;
  // The plan's own ankle motor torques, stage by stage (quasi-static, the stage's forces): what
  // the optimization asked of the motors, before the frames (the oracle) add the dynamics.
  for (int k = 0; k < S && ankle_motors.active; ++k) {
    Eigen::Matrix<double, kNumMpcJoints, 1> tau;
    quasi_static_torques(robot, *data, mpc::configuration_from_state(xs[k], heads[k]), us[k], flags[k], tau, nullptr);
    bool over = false;
    for (int leg = 0; leg < 2; ++leg) {
      const int j = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + model::kAnklePitchInLeg;
      Eigen::Vector2d motor;
      if (!drivers::ankle_motor_torques_rt(ankle_motors, leg,
                                           Eigen::Vector2d(xs[k][mpc::kXJoints + j], xs[k][mpc::kXJoints + j + 1]),
                                           Eigen::Vector2d(tau[j], tau[j + 1]), motor)) {
        continue;
      }
      for (int m = 0; m < 2; ++m) over = over || std::abs(motor[m]) > ankle_motors.limit_Nm[leg](m);
    }
    if (over) ++stats.stages_over_ankle_motors;
  }
  stats.sqp_iterations_mean = stats.windows > 0 ? static_cast<double>(iterations_total) / stats.windows : 0.0;

  smooth_stages(xs, cfg.stage_smoothing_passes);
  // Stages → frames: Catmull-Rom through the stage poses (smooth accelerations for the
  // inverse dynamics), forces linear between nodes (node k carries u_{k−1}, see below).
  const int n = plan.frame_count;
  out.q.resize(n);
  out.contacts.resize(n);
  out.forces_N.resize(n);
  for (int i = 0; i < n; ++i) {
    const double t = i / plan.rate_hz;
    const int k = std::clamp(static_cast<int>(std::floor(t / dt)), 0, S - 1);
    const double s = std::clamp(t / dt - k, 0.0, 1.0);
    const auto at = [&](int m) -> const StateVector& { return xs[std::clamp(m, 0, S)]; };
    // The four stages on one branch of their Euler angles.
    const std::array<StateVector, 4> p = {on_branch_of(at(k - 1), at(k)), at(k), on_branch_of(at(k + 1), at(k)),
                                          on_branch_of(at(k + 2), at(k))};
    const StateVector x = catmull_rom<StateVector>(p[0], p[1], p[2], p[3], s);
    const mpc::HeadVector head = heads[k] + s * (heads[k + 1] - heads[k]);
    out.q[i] = mpc::configuration_from_state(x, head);
    const std::array<bool, 2>& fc = plan.foot_contact[i];
    out.contacts[i] = make_label(fc[0], fc[1]);
    // Force at t: explicit Euler moves the position with ṙ_k and ṙ with u_k, so the
    // second difference of the stage positions at node k is dt²(u_{k−1}/m − g): node k
    // carries u_{k−1}, and the force is linear between nodes.
    const double tm = t / dt - 1.0;
    const int k0 = std::clamp(static_cast<int>(std::floor(tm)), 0, S - 1);
    const int k1 = std::min(k0 + 1, S - 1);
    const double w = std::clamp(tm - k0, 0.0, 1.0);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      const bool in = fc[c / 4];
      Vec3 f = Vec3::Zero();
      if (in) {
        const Vec3 f0 = us[k0].segment<3>(3 * c), f1 = us[k1].segment<3>(3 * c);
        f = flags[k0][c] && flags[k1][c] ? Vec3((1.0 - w) * f0 + w * f1) : (flags[k1][c] ? f1 : f0);
      }
      out.forces_N[i].segment<3>(3 * c) = f;
    }
    out.forces_N[i] = forces_on_robot_corners(robot_model, robot, out.forces_N[i]);
  }
  // Stance feet exactly on their footholds (the reference's, which the repair placed).
  // Pass 1 finds, frame by frame, how far the base must come down for the legs to reach
  // (a leg at full stretch cannot reach a foothold the TO crept past); pass 2 lowers it by a
  // smooth envelope of those drops. Lowered frame by frame, the base jumped by up to 1.7 cm
  // between frames and the stance knee by 0.2 rad (perfume at 25.86 s): an inverse-dynamics
  // torque 5.5× the hip-pitch limit that no motor could give.
  // Swing feet follow the TO's swing, shifted by a correction carried smoothly from the stance
  // before to the stance after (swing_corrections): switched in one frame, the legs jumped at
  // lift-off and touchdown.
  std::vector<std::array<Vec3, model::kNumContactPoints>> targets(n);
  std::vector<std::array<Vec3, model::kNumContactPoints>> fk(n);
  std::array<std::vector<Vec3>, model::kNumContactPoints> correction;
  for (auto& c : correction) c.assign(n, Vec3::Zero());
  std::array<std::vector<bool>, 2> stance_of;
  for (int f = 0; f < 2; ++f) {
    stance_of[f].resize(n);
    for (int i = 0; i < n; ++i) stance_of[f][i] = plan.foot_contact[i][f];
  }
  for (int i = 0; i < n; ++i) {
    dynamics::forward_kinematics(robot, *data, plan.q[i]);
    std::array<Vec3, model::kNumContactPoints> reference;
    for (int c = 0; c < model::kNumContactPoints; ++c) reference[c] = dynamics::frame_position(robot, *data, c);
    dynamics::forward_kinematics(robot, *data, out.q[i]);
    for (int c = 0; c < model::kNumContactPoints; ++c) {
      fk[i][c] = dynamics::frame_position(robot, *data, c);
      if (!plan.foot_contact[i][c / 4]) continue;
      // The stage whose anchors hold this frame's stance (a touchdown between stages: the next).
      const double ts = i / plan.rate_hz / dt;
      const int ka = std::clamp(static_cast<int>(std::floor(ts)), 0, S);
      const int kb = std::min(ka + 1, S);
      const int kc = flags[ka][c] ? ka : kb;
      const Vec3 held = flags[kc][c] ? anchors[kc][c] : reference[c];
      correction[c][i] = held - fk[i][c];
      stats.foothold_correction_max_m = std::max(stats.foothold_correction_max_m, correction[c][i].norm());
    }
  }
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    const std::vector<Vec3> carried = swing_corrections(stance_of[c / 4], correction[c]);
    for (int i = 0; i < n; ++i) targets[i][c] = fk[i][c] + carried[i];
  }
  std::vector<ConfigVector> start(n);
  std::vector<double> need(n, 0.0);
  for (int i = 0; i < n; ++i) {
    start[i] = out.q[i];
    double miss = leg_ik_lm(robot, *data, targets[i], out.q[i]);
    // The drop that reaches (or, out of reach even then, the one that comes nearest).
    for (double drop = 1e-3; !(miss <= kFootholdTolerance_m) && drop <= kMaxBaseDrop_m + 1e-12; drop += 1e-3) {
      ConfigVector q = start[i];
      q[2] -= drop;
      const double m = leg_ik_lm(robot, *data, targets[i], q);
      if (m < miss) {
        miss = m;
        need[i] = drop;
      }
    }
  }
  const std::vector<double> drop = smooth_envelope(need, static_cast<int>(std::lround(kBaseDropSmoothing_s * plan.rate_hz)));
  for (int i = 0; i < n; ++i) {
    if (drop[i] > 0.0) {
      out.q[i] = start[i];
      out.q[i][2] -= drop[i];
    }
    const double miss = leg_ik_lm(robot, *data, targets[i], out.q[i]);
    stats.base_drop_max_m = std::max(stats.base_drop_max_m, drop[i]);
    // Out of reach even then: the nearest pose is kept and the miss reported (the report's
    // foothold_miss_m_max; the simulator is the judge of whether the dance survives it).
    if (!(miss <= kFootholdTolerance_m)) ++stats.foothold_miss_frames;
    stats.foothold_miss_max_m = std::max(stats.foothold_miss_max_m, miss);
  }
  // The frames are final: the forces that produce them (contact_forces.h), the TO's as the
  // prior. The TO's own left the built-in dance's frames a base-wrench residual of 27 N on
  // average (860 N at a touchdown); these, 1.1 N.
  const std::vector<CornerForces> prior = std::move(out.forces_N);
  contact_forces_for_motion(robot_model, out.q, out.contacts, plan.rate_hz, ocp.friction_coefficient, prior,
                            out.forces_N, stats.forces);
  stats.solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return true;
}

std::vector<double> smooth_envelope(const std::vector<double>& v, int w) {
  const int n = static_cast<int>(v.size());
  std::vector<double> env(v), tmp(n, 0.0);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - w); j <= std::min(n - 1, i + w); ++j) env[i] = std::max(env[i], v[j]);
  }
  const int h = std::max(0, w / 2);
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < n; ++i) {
      double sum = 0.0;
      // Frames past the ends count as the end frame (the envelope holds its value there).
      for (int j = i - h; j <= i + h; ++j) sum += env[std::clamp(j, 0, n - 1)];
      tmp[i] = sum / (2 * h + 1);
    }
    env.swap(tmp);
  }
  return env;
}

void smooth_stages(std::vector<StateVector>& xs, int passes) {
  const int S = static_cast<int>(xs.size()) - 1;
  std::vector<StateVector> in;
  for (int pass = 0; pass < passes && S >= 2; ++pass) {
    in = xs;
    for (int k = 1; k < S; ++k) {
      xs[k] = 0.25 * on_branch_of(in[k - 1], in[k]) + 0.5 * in[k] + 0.25 * on_branch_of(in[k + 1], in[k]);
    }
  }
}

std::vector<Vec3> swing_corrections(const std::vector<bool>& stance, const std::vector<Vec3>& held) {
  const int n = static_cast<int>(stance.size());
  std::vector<Vec3> out(n, Vec3::Zero());
  for (int i = 0; i < n;) {
    if (stance[i]) {
      out[i] = held[i];
      ++i;
      continue;
    }
    int b = i;  // the swing is [i, b)
    while (b < n && !stance[b]) ++b;
    const Vec3 from = i > 0 ? held[i - 1] : Vec3::Zero();
    const Vec3 to = b < n ? held[b] : from;
    for (int j = i; j < b; ++j) {
      const double s = static_cast<double>(j - i + 1) / (b - i + 1);
      const double w = s * s * (3.0 - 2.0 * s);
      out[j] = (1.0 - w) * from + w * to;
    }
    i = b;
  }
  return out;
}

}  // namespace kuavo::mocap
