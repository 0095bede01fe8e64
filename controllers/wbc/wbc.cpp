#include "controllers/wbc/wbc.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace kuavo::wbc {
namespace {

using dynamics::Mat3;
constexpr int kNv = model::kNv;
constexpr int kNj = model::kNumJoints;
constexpr int kForce0 = kNumAccelerations;  // index of the first force variable
constexpr int kMotorRow0 = kNumFrictionRows;
constexpr int kSerialRow0 = kNumFrictionRows + kNumAnkleMotorRows;
constexpr int kTorqueRow0 = kSerialRow0 + kNumSerialDriveRows;
constexpr int kPointsPerFoot = kNumPoints / 2;  // points [0, 4) left foot, [4, 8) right
// Torque bounds are planned this far inside the limit. A solution on a bound meets it only to
// roundoff, and the firmware recomputes the motor torques from the same numbers in another
// order: 1e-13 N·m over the ankle motors' 27 N·m in the built-in dance, which the drivers
// count as clamps and the output stage as torques clipped at the peak (= the WBC limit for
// ankles and hip pitch). The limit itself is then left to real saturation.
constexpr double kTorqueBoundRoundoff_Nm = 1e-6;
static_assert(model::kRightLegFirst == model::kLeftLegFirst + model::kLegJoints);

bool finite_reference(const WbcReference& r) {
  return r.base_euler_zyx_rad.allFinite() && r.base_angular_velocity_rad_s.allFinite() &&
         r.base_angular_acceleration_rad_s2.allFinite() && r.com_position_m.allFinite() &&
         r.com_velocity_m_s.allFinite() && r.momentum_rate.allFinite() && r.joint_position_rad.allFinite() &&
         r.joint_velocity_rad_s.allFinite() && r.joint_acceleration_rad_s2.allFinite() &&
         r.point_position_m.allFinite() && r.point_velocity_m_s.allFinite() &&
         r.point_acceleration_m_s2.allFinite() && r.contact_force_N.allFinite();
}

// Heading-only rotation of the base: Leju runs the CoM and base-angular PD in this frame, so
// its per-axis gains mean forward/lateral whatever the heading.
Mat3 yaw_rotation(const Mat3& r) {
  return Eigen::AngleAxisd(std::atan2(r(1, 0), r(0, 0)), Vec3::UnitZ()).toRotationMatrix();
}

Vec3 as_vec3(const std::array<double, 3>& a) { return Vec3(a[0], a[1], a[2]); }

bool is_arm(int j) { return j >= model::kLeftArmFirst && j < model::kHeadFirst; }
bool is_head(int j) { return j >= model::kHeadFirst; }

// Kinematic and dynamic terms of the tick, one kinematics pass.
void compute_terms(const model::Model& model, WbcWorkspace& ws, const dynamics::ConfigVector& q,
                   const dynamics::VelocityVector& v) {
  dynamics::compute_all_terms(model, ws.data, q, v);
  dynamics::bias_accelerations(model, ws.data);  // after rnea, which reuses data.acceleration
  for (int c = 0; c < kNumPoints; ++c) {
    dynamics::frame_jacobian(model, ws.data, c, ws.frame_jacobian);
    ws.contact_jacobian.middleRows<3>(3 * c) = ws.frame_jacobian.topRows<3>();
    ws.contact_bias.segment<3>(3 * c) = dynamics::frame_bias_acceleration(model, ws.data, c).head<3>();
    ws.point_position_m.segment<3>(3 * c) = dynamics::frame_position(model, ws.data, c);
    ws.point_velocity_m_s.segment<3>(3 * c) = dynamics::frame_velocity(model, ws.data, c).head<3>();
  }
}

void build_cost(const WbcConfig& cfg, WbcWorkspace& ws, const dynamics::ConfigVector& q,
                const dynamics::VelocityVector& v, const WbcReference& ref) {
  Qp& qp = ws.qp;
  const dynamics::Data& d = ws.data;
  const double mass = d.total_mass_kg;
  const Mat3& r_base = d.rotation[0];
  const Mat3 r_yaw = yaw_rotation(r_base);

  // Contact points: a_des = a_ref + kp (p_ref − p) + kd (v_ref − ṗ), as rows √w·(J q̈ + J̇v − a_des).
  for (int c = 0; c < kNumPoints; ++c) {
    const bool stance = ref.in_contact[c];
    const Vec3 kp = stance ? Vec3::Constant(cfg.stance_kp) : Vec3(cfg.swing_kp_xy, cfg.swing_kp_xy, cfg.swing_kp_z);
    const Vec3 kd = stance ? Vec3::Constant(cfg.stance_kd) : Vec3(cfg.swing_kd_xy, cfg.swing_kd_xy, cfg.swing_kd_z);
    const Vec3 a_des = ref.point_acceleration_m_s2.segment<3>(3 * c) +
                       kp.cwiseProduct(ref.point_position_m.segment<3>(3 * c) - ws.point_position_m.segment<3>(3 * c)) +
                       kd.cwiseProduct(ref.point_velocity_m_s.segment<3>(3 * c) - ws.point_velocity_m_s.segment<3>(3 * c));
    const double sw = std::sqrt(stance ? cfg.weight_stance_point : cfg.weight_swing_point);
    ws.task_rows.middleRows<3>(3 * c) = sw * ws.contact_jacobian.middleRows<3>(3 * c);
    ws.task_targets.segment<3>(3 * c) = sw * (a_des - ws.contact_bias.segment<3>(3 * c));
  }

  // CoM: r̈ = (A_lin q̈ + Ȧ_lin v)/m tracks ḣ_ref/m + PD (yaw frame).
  {
    const Vec3 com_velocity = d.momentum_matrix_ref.topRows<3>() * v / mass;
    const Vec3 e = r_yaw.transpose() * (ref.com_position_m - d.com_m);
    const Vec3 ed = r_yaw.transpose() * (ref.com_velocity_m_s - com_velocity);
    const Vec3 a_des = ref.momentum_rate.head<3>() / mass +
                       r_yaw * (as_vec3(cfg.com_kp).cwiseProduct(e) + as_vec3(cfg.com_kd).cwiseProduct(ed));
    const double sw = std::sqrt(cfg.weight_com);
    ws.task_rows.bottomRows<3>() = (sw / mass) * d.momentum_matrix_ref.topRows<3>();
    ws.task_targets.tail<3>() = sw * (a_des - d.centroidal_bias.head<3>() / mass);
  }

  // H = task_rowsᵀ task_rows, by blocks: a foot's 12 point rows reach only the base and that
  // leg's 6 joints (the leg is the feet's only path to the base), so each foot is one 12×12
  // product instead of 12 rows against all 34 columns; the 3 CoM rows are dense. 1/5 of the
  // dense product's flops. Only the acceleration block and the force diagonal are written:
  // the acceleration–force blocks stay zero and the force block diagonal from wbc_init. The
  // WBC tests check H against the dense product and that structure.
  auto h_acc = qp.H.topLeftCorner<kNv, kNv>();
  const auto com_rows = ws.task_rows.bottomRows<3>();
  h_acc.noalias() = com_rows.transpose().lazyProduct(com_rows);  // fixed sizes: no GEMM packing
  for (int foot = 0; foot < 2; ++foot) {
    constexpr int kRows = 3 * kPointsPerFoot;
    const int r0 = kRows * foot, leg = 6 + model::kLeftLegFirst + model::kLegJoints * foot;
    Eigen::Matrix<double, kRows, 12> rows;
    rows.leftCols<6>() = ws.task_rows.block<kRows, 6>(r0, 0);
    rows.rightCols<6>() = ws.task_rows.block<kRows, 6>(r0, leg);
    Eigen::Matrix<double, 12, 12> gram;
    gram.noalias() = rows.transpose().lazyProduct(rows);
    h_acc.block<6, 6>(0, 0) += gram.topLeftCorner<6, 6>();
    h_acc.block<6, 6>(leg, 0) += gram.bottomLeftCorner<6, 6>();
    h_acc.block<6, 6>(0, leg) += gram.topRightCorner<6, 6>();
    h_acc.block<6, 6>(leg, leg) += gram.bottomRightCorner<6, 6>();
  }
  qp.g.setZero();
  qp.g.head<kNv>().noalias() = -ws.task_rows.transpose() * ws.task_targets;

  // Base angular acceleration. ω_world = R ω_base and ω×ω = 0, so ω̇_world = R q̈[3:6]
  // exactly: the rows R are orthonormal, RᵀR = I.
  {
    const Mat3 r_ref = rotation_from_euler_zyx(ref.base_euler_zyx_rad);
    const Eigen::AngleAxisd error(r_ref * r_base.transpose());
    const Vec3 e = r_yaw.transpose() * (error.angle() * error.axis());
    const Vec3 omega_world = r_base * v.segment<3>(3);
    const Vec3 ed = r_yaw.transpose() * (ref.base_angular_velocity_rad_s - omega_world);
    const Vec3 a_des = ref.base_angular_acceleration_rad_s2 +
                       r_yaw * (as_vec3(cfg.base_angular_kp).cwiseProduct(e) + as_vec3(cfg.base_angular_kd).cwiseProduct(ed));
    qp.H.block<3, 3>(3, 3).diagonal().array() += cfg.weight_base_angular;
    qp.g.segment<3>(3) -= cfg.weight_base_angular * (r_base.transpose() * a_des);
  }

  // Arm and head joints: q̈ = q̈_ref + kp (q_ref − q) + kd (v_ref − v).
  for (int j = model::kLeftArmFirst; j < kNj; ++j) {
    const bool head = is_head(j);
    const double w = head ? cfg.weight_head : cfg.weight_arm;
    const double kp = head ? cfg.head_kp : cfg.arm_kp, kd = head ? cfg.head_kd : cfg.arm_kd;
    const double a_des = ref.joint_acceleration_rad_s2[j] + kp * (ref.joint_position_rad[j] - q[7 + j]) +
                         kd * (ref.joint_velocity_rad_s[j] - v[6 + j]);
    qp.H(6 + j, 6 + j) += w;
    qp.g(6 + j) -= w * a_des;
  }

  qp.H.topLeftCorner<kNv, kNv>().diagonal().array() += cfg.weight_acceleration_regularization;
  qp.H.bottomRightCorner<kNumForces, kNumForces>().diagonal().setConstant(cfg.weight_contact_force);
  qp.g.tail<kNumForces>() -= cfg.weight_contact_force * ref.contact_force_N;
}

void build_constraints(const model::Model& model, const WbcConfig& cfg, WbcWorkspace& ws,
                       const dynamics::ConfigVector& q, const dynamics::VelocityVector& v, const WbcReference& ref) {
  Qp& qp = ws.qp;
  const dynamics::Data& d = ws.data;
  const auto& mass_matrix = d.mass_matrix;
  const auto& bias = d.tau;  // b(q, v): Coriolis, centrifugal and gravity

  // Floating base: M_b q̈ − J_bᵀ f = −b_b.
  qp.A.leftCols<kNv>() = mass_matrix.topRows<6>();
  qp.A.rightCols<kNumForces>() = -ws.contact_jacobian.leftCols<6>().transpose();
  qp.b = -bias.head<6>();

  // Torque rows: τ = M_j q̈ + b_j − J_jᵀ f within ±limit.
  qp.C.block<kNj, kNv>(kTorqueRow0, 0) = mass_matrix.bottomRows<kNj>();
  qp.C.block<kNj, kNumForces>(kTorqueRow0, kForce0) = -ws.contact_jacobian.rightCols<kNj>().transpose();
  const dynamics::JointVector torque_limit =
      (model.limits.torque_Nm.cwiseMin(ws.torque_cap_Nm).array() - kTorqueBoundRoundoff_Nm).matrix();
  qp.c_lower.segment<kNj>(kTorqueRow0) = -torque_limit - bias.tail<kNj>();
  qp.c_upper.segment<kNj>(kTorqueRow0) = torque_limit - bias.tail<kNj>();

  // Contacts: the pyramid rows (fixed in wbc_init) are switched on for stance points only.
  // A swing point's force is cut out of every row (zero columns in A and C) and from the
  // cost target, so it decouples and the unconstrained minimizer already puts it at 0: the
  // [0, 0] bounds below then never enter the working set (12 solver iterations saved per
  // foot in swing).
  for (int c = 0; c < kNumPoints; ++c) {
    if (!ref.in_contact[c]) {
      qp.A.middleCols<3>(kForce0 + 3 * c).setZero();
      qp.C.block<kNj, 3>(kTorqueRow0, kForce0 + 3 * c).setZero();
      qp.g.segment<3>(kForce0 + 3 * c).setZero();
    }
  }
  for (int c = 0; c < kNumPoints; ++c) {
    const int r = kFrictionRowsPerPoint * c, x = kForce0 + 3 * c;
    if (ref.in_contact[c]) {
      for (int k = 0; k < kFrictionRowsPerPoint; k += 2) {
        qp.c_lower(r + k) = -qp::kInfinity;  // f_t − μ f_z ≤ 0
        qp.c_upper(r + k) = 0.0;
        qp.c_lower(r + k + 1) = 0.0;  // f_t + μ f_z ≥ 0
        qp.c_upper(r + k + 1) = qp::kInfinity;
      }
      qp.x_lower.segment<2>(x).setConstant(-qp::kInfinity);
      qp.x_upper.segment<2>(x).setConstant(qp::kInfinity);
      qp.x_lower(x + 2) = 0.0;
      qp.x_upper(x + 2) = cfg.max_normal_force_N;
    } else {
      qp.c_lower.segment<kFrictionRowsPerPoint>(r).setConstant(-qp::kInfinity);
      qp.c_upper.segment<kFrictionRowsPerPoint>(r).setConstant(qp::kInfinity);
      qp.x_lower.segment<3>(x).setZero();
      qp.x_upper.segment<3>(x).setZero();
    }
  }

  // Ankle motors: the two ankle torque rows of each leg (swing forces already cut out) mapped
  // through the linkage; bounds on the motor torque, less the mapped bias. A drive whose
  // loop damps (gain > 0, CSP) applies gain·J·(v_ref − v) on top of the command's torque
  // at the sample it closes on (v_ref = reference + q̈·dt, as the command is written below;
  // v the measured joint velocity): its q̈ part joins the row, the rest the bounds.
  const AnkleMotorLimits& motors = ws.ankle_motor_limits;
  for (int leg = 0; leg < 2; ++leg) {
    const int jp = (leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst) + model::kAnklePitchInLeg;
    const Eigen::Matrix2d velocity_map = motors.joint_to_motor[leg].transpose().inverse();
    const Eigen::Vector2d v_ref(ref.joint_velocity_rad_s[jp], ref.joint_velocity_rad_s[jp + 1]);
    const Eigen::Vector2d v_joint(v[6 + jp], v[6 + jp + 1]);
    for (int k = 0; k < 2; ++k) {
      const int r = kMotorRow0 + 2 * leg + k;
      if (!motors.active) {
        qp.C.row(r).setZero();
        qp.c_lower(r) = -qp::kInfinity;
        qp.c_upper(r) = qp::kInfinity;
        continue;
      }
      const double gp = motors.joint_to_motor[leg](k, 0), gr = motors.joint_to_motor[leg](k, 1);
      qp.C.row(r) = gp * qp.C.row(kTorqueRow0 + jp) + gr * qp.C.row(kTorqueRow0 + jp + 1);
      const double kv = motors.velocity_gain_Nm_s_per_rad[leg](k);
      qp.C(r, 6 + jp) += kv * cfg.dt_s * velocity_map(k, 0);
      qp.C(r, 6 + jp + 1) += kv * cfg.dt_s * velocity_map(k, 1);
      const double offset = gp * bias(6 + jp) + gr * bias(6 + jp + 1) + kv * velocity_map.row(k).dot(v_ref - v_joint);
      const double limit = cfg.ankle_motor_torque_share * motors.limit_Nm[leg](k) - kTorqueBoundRoundoff_Nm;
      qp.c_lower(r) = -limit - offset;
      qp.c_upper(r) = limit - offset;
    }
  }

  // Serial leg drives: the drive's torque at its sample, τ + kv·(v_ref − v) (v_ref = reference
  // + q̈·dt), within the drive's clamp, as the ankle motors' (the torque row plus kv·dt on the
  // joint's q̈).
  const SerialLegDriveLimits& serial = ws.serial_drive_limits;
  for (int leg = 0; leg < 2; ++leg) {
    const int first = leg == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    for (int k = 0; k < hal::kSerialLegJoints; ++k) {
      const int r = kSerialRow0 + hal::kSerialLegJoints * leg + k, j = first + k;
      if (!serial.active) {
        qp.C.row(r).setZero();
        qp.c_lower(r) = -qp::kInfinity;
        qp.c_upper(r) = qp::kInfinity;
        continue;
      }
      const double kv = serial.velocity_gain_Nm_s_per_rad[leg][k];
      qp.C.row(r) = qp.C.row(kTorqueRow0 + j);
      qp.C(r, 6 + j) += kv * cfg.dt_s;
      const double offset = bias(6 + j) + kv * (ref.joint_velocity_rad_s[j] - v[6 + j]);
      const double limit = serial.limit_Nm[leg][k] - kTorqueBoundRoundoff_Nm;
      qp.c_lower(r) = -limit - offset;
      qp.c_upper(r) = limit - offset;
    }
  }

  // Joint accelerations: never cross a position limit within the lookahead h at constant a,
  // q + v h + ½ a h² ∈ [q_min, q_max]; and |a| ≤ max. A joint already beyond its limit gets
  // a window that pulls it back (the two sides swapped), never an empty one.
  const double h = cfg.joint_limit_lookahead_s, a_max = cfg.max_joint_acceleration_rad_s2;
  for (int j = 0; j < kNj; ++j) {
    const double drift = q[7 + j] + v[6 + j] * h;
    double hi = std::min(a_max, 2.0 * (model.limits.position_max_rad[j] - drift) / (h * h));
    double lo = std::max(-a_max, 2.0 * (model.limits.position_min_rad[j] - drift) / (h * h));
    if (lo > hi) std::swap(lo, hi);
    qp.x_lower(6 + j) = lo;
    qp.x_upper(6 + j) = hi;
  }
}

void set_gains(const WbcConfig& cfg, bool fallback, int j, hal::JointCommand& c) {
  if (j < model::kLeftArmFirst) {
    const int k = j % model::kLegJoints;
    c.kp_Nm_per_rad = fallback ? cfg.fallback_leg_kp[k] : cfg.leg_kp[k];
    c.kd_Nm_s_per_rad = fallback ? cfg.fallback_leg_kd[k] : cfg.leg_kd[k];
  } else if (is_arm(j)) {
    c.kp_Nm_per_rad = fallback ? cfg.fallback_arm_kp : cfg.arm_pd_kp;
    c.kd_Nm_s_per_rad = fallback ? cfg.fallback_arm_kd : cfg.arm_pd_kd;
  } else {
    c.kp_Nm_per_rad = cfg.head_pd_kp;
    c.kd_Nm_s_per_rad = cfg.head_pd_kd;
  }
}

// Gravity-compensated stiff PD on a held pose: the weight split evenly over the points the
// reference has in contact (all 8 if the reference is unusable). Needs compute_terms.
void fallback_command(const model::Model& model, const WbcConfig& cfg, WbcWorkspace& ws, const dynamics::ConfigVector& q,
                      const WbcReference& ref, bool reference_usable, hal::CommandFrame& command) {
  if (!ws.hold_position_latched) {
    for (int j = 0; j < kNj; ++j) {
      ws.hold_position_rad[j] = ws.have_last_good ? ws.last_good_command.joints[j].position_ref_rad : q[7 + j];
    }
    ws.hold_position_latched = true;
  }
  int in_contact = 0;
  for (int c = 0; c < kNumPoints; ++c) in_contact += (!reference_usable || ref.in_contact[c]) ? 1 : 0;
  ForceVector& f = ws.diagnostics.contact_force_N;
  f.setZero();
  if (in_contact > 0) {
    const double share_N = ws.data.total_mass_kg * model::kGravity_m_s2 / in_contact;
    for (int c = 0; c < kNumPoints; ++c) {
      if (!reference_usable || ref.in_contact[c]) f[3 * c + 2] = share_N;
    }
  }
  ws.diagnostics.torque_Nm = ws.data.tau.tail<kNj>() - ws.contact_jacobian.rightCols<kNj>().transpose() * f;
  ws.diagnostics.acceleration.setZero();
  for (int j = 0; j < kNj; ++j) {
    hal::JointCommand& c = command.joints[j];
    c.mode = hal::JointMode::kPdTorque;
    const double limit = std::min(model.limits.torque_Nm[j], ws.torque_cap_Nm[j]);
    c.torque_ff_Nm = std::clamp(ws.diagnostics.torque_Nm[j], -limit, limit);
    c.position_ref_rad = ws.hold_position_rad[j];
    c.velocity_ref_rad_s = 0.0;
    set_gains(cfg, true, j, c);
  }
}

}  // namespace

void wbc_init(const model::Model& model, const WbcConfig& config, WbcWorkspace& ws) {
  (void)model;
  Qp& qp = ws.qp;
  qp.H.setIdentity();
  qp.g.setZero();
  qp.A.setZero();
  qp.b.setZero();
  qp.C.setZero();
  qp.c_lower.setConstant(-qp::kInfinity);
  qp.c_upper.setConstant(qp::kInfinity);
  qp.x_lower.setConstant(-qp::kInfinity);
  qp.x_upper.setConstant(qp::kInfinity);
  const double mu = config.friction_coefficient;
  for (int c = 0; c < kNumPoints; ++c) {
    const int r = kFrictionRowsPerPoint * c, x = kForce0 + 3 * c;
    for (int t = 0; t < 2; ++t) {  // tangential x, then y
      qp.C(r + 2 * t, x + t) = 1.0;
      qp.C(r + 2 * t, x + 2) = -mu;
      qp.C(r + 2 * t + 1, x + t) = 1.0;
      qp.C(r + 2 * t + 1, x + 2) = mu;
    }
  }
  ws.qp_settings = qp::DenseQpSettings{};
  ws.qp_settings.max_iterations = config.qp_max_iterations;
  ws.solution.working_set_size = 0;
  ws.solution.status = qp::QpStatus::kBadInput;
  ws.have_last_good = false;
  ws.hold_position_latched = false;
  ws.diagnostics = WbcDiagnostics{};
}

WbcStatus wbc_step_rt(const model::Model& model, const WbcConfig& cfg, WbcWorkspace& ws,
                      const dynamics::ConfigVector& q, const dynamics::VelocityVector& v,
                      const WbcReference& ref, hal::TimeNs now_ns, hal::CommandFrame& command) {
  WbcDiagnostics& diag = ws.diagnostics;
  command.stamp_ns = now_ns;
  if (!q.allFinite() || !v.allFinite()) {
    for (auto& c : command.joints) c = hal::JointCommand{hal::JointMode::kDamping, 0.0, 0.0, 0.0, 0.0, cfg.damping_kd};
    diag.status = WbcStatus::kDamping;
    diag.failure = WbcFailure::kStateInvalid;
    ++diag.failed_ticks;
    return diag.status;
  }
  compute_terms(model, ws, q, v);

  WbcFailure failure = WbcFailure::kNone;
  const bool reference_usable = finite_reference(ref);
  if (!reference_usable) {
    failure = WbcFailure::kReferenceInvalid;
  } else if (now_ns - ref.stamp_ns > cfg.max_reference_age_ns) {
    failure = WbcFailure::kReferenceStale;
  } else {
    build_cost(cfg, ws, q, v, ref);
    build_constraints(model, cfg, ws, q, v, ref);
    // The previous working set is a guess only (GI stays correct with any), so it is used
    // whenever the last solve succeeded.
    ws.qp_settings.warm_start = ws.solution.status == qp::QpStatus::kSolved;
    ws.qp_settings.max_iterations = cfg.qp_max_iterations;
    diag.qp_status = qp::solve_dense_qp(ws.qp, ws.qp_settings, ws.qp_workspace, ws.solution);
    diag.qp_iterations = ws.solution.iterations;
    if (diag.qp_status != qp::QpStatus::kSolved) {
      failure = WbcFailure::kQpFailed;
    } else {
      const auto& x = ws.solution.x;
      diag.acceleration = x.head<kNv>();
      diag.contact_force_N = x.tail<kNumForces>();
      // The solver leaves bound-pinned swing forces at roundoff (1e-14 N): make them exact.
      for (int c = 0; c < kNumPoints; ++c) {
        if (!ref.in_contact[c]) diag.contact_force_N.segment<3>(3 * c).setZero();
      }
      diag.torque_Nm.noalias() = ws.data.mass_matrix.bottomRows<kNj>() * diag.acceleration;
      diag.torque_Nm += ws.data.tau.tail<kNj>();
      diag.torque_Nm.noalias() -= ws.contact_jacobian.rightCols<kNj>().transpose() * diag.contact_force_N;
      if (!x.allFinite() || !diag.torque_Nm.allFinite()) failure = WbcFailure::kSolutionInvalid;
    }
  }

  if (failure == WbcFailure::kNone) {
    const double dt = cfg.dt_s;
    for (int j = 0; j < kNj; ++j) {
      hal::JointCommand& c = command.joints[j];
      const double a = diag.acceleration[6 + j];
      c.mode = hal::JointMode::kPdTorque;
      c.torque_ff_Nm = diag.torque_Nm[j];
      // Leju's output: the planned joint state advanced by the WBC acceleration over one tick.
      c.position_ref_rad = ref.joint_position_rad[j] + 0.5 * a * dt * dt;
      c.velocity_ref_rad_s = ref.joint_velocity_rad_s[j] + a * dt;
      set_gains(cfg, false, j, c);
    }
    ws.last_good_command = command;
    ws.have_last_good = true;
    ws.hold_position_latched = false;
    diag.failed_ticks = 0;
    diag.failure = WbcFailure::kNone;
    diag.status = WbcStatus::kOk;
    return diag.status;
  }

  ++diag.failed_ticks;
  diag.failure = failure;
  if (ws.have_last_good && diag.failed_ticks <= cfg.hold_ticks) {
    const hal::TimeNs stamp = command.stamp_ns;
    command = ws.last_good_command;
    command.stamp_ns = stamp;
    diag.status = WbcStatus::kHoldingLastCommand;
  } else {
    fallback_command(model, cfg, ws, q, ref, reference_usable, command);
    diag.status = WbcStatus::kFallbackPd;
  }
  return diag.status;
}

void wbc_reference_hold_state(const model::Model& model, WbcWorkspace& ws, const dynamics::ConfigVector& q,
                              hal::TimeNs stamp_ns, WbcReference& out) {
  dynamics::compute_all_terms(model, ws.data, q, dynamics::VelocityVector::Zero());
  out = WbcReference{};
  out.stamp_ns = stamp_ns;
  out.base_euler_zyx_rad = euler_zyx_from_rotation(ws.data.rotation[0]);
  out.com_position_m = ws.data.com_m;
  out.joint_position_rad = q.tail<kNj>();
  for (int c = 0; c < kNumPoints; ++c) {
    out.point_position_m.segment<3>(3 * c) = dynamics::frame_position(model, ws.data, c);
    out.in_contact[c] = true;
    dynamics::frame_jacobian(model, ws.data, c, ws.frame_jacobian);
    ws.contact_jacobian.middleRows<3>(3 * c) = ws.frame_jacobian.topRows<3>();
  }
  // Planned forces: the least-norm set that balances gravity (base rows J_bᵀ f = b_b). Zero
  // planned forces would make the force task fight the CoM task for the whole weight.
  const Eigen::Matrix<double, 6, kNumForces> base_rows = ws.contact_jacobian.leftCols<6>().transpose();
  const Eigen::Matrix<double, 6, 6> gram = base_rows * base_rows.transpose();
  out.contact_force_N = base_rows.transpose() * gram.ldlt().solve(ws.data.tau.head<6>());
}

}  // namespace kuavo::wbc
