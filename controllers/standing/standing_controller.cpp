#include "controllers/standing/standing_controller.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace kuavo::control {
namespace {

using dynamics::Vec3;

// Hip pitch axis to sole, straight leg: the URDF thigh and shank lengths.
constexpr double kThigh_m = 0.284;
constexpr double kShank_m = 0.346;
constexpr double kBaseToHipPitch_m = 0.066 + 0.1287;  // FACTS.md §2.2
constexpr double kAnkleToSole_m = 0.0595;
constexpr double kElbowBend_rad = -0.116;  // reference.info standing arm pose

}  // namespace

dynamics::JointVector standing_pose(const model::Model& model, double base_height_m, double ankle_behind_hip_m) {
  dynamics::JointVector q = dynamics::JointVector::Zero();
  const double drop = base_height_m - kBaseToHipPitch_m - kAnkleToSole_m;
  // Thigh forward by a, shank back by b: the ankle is L1 sin a − L2 sin b ahead of
  // the hip pitch axis and L1 cos a + L2 cos b below it. Bisection on a: the drop
  // shrinks as a grows.
  auto shank_angle = [&](double a) {
    return std::asin(std::clamp((kThigh_m * std::sin(a) + ankle_behind_hip_m) / kShank_m, -1.0, 1.0));
  };
  double lo = 0.0, hi = 1.5;
  for (int it = 0; it < 60; ++it) {
    const double a = 0.5 * (lo + hi);
    const double d = kThigh_m * std::cos(a) + kShank_m * std::cos(shank_angle(a));
    (d > drop ? lo : hi) = a;
  }
  const double a = 0.5 * (lo + hi);
  const double b = shank_angle(a);
  for (int leg : {model::kLeftLegFirst, model::kRightLegFirst}) {
    q[leg + 2] = -a;     // hip pitch: negative swings the thigh forward
    q[leg + 3] = a + b;  // knee
    q[leg + 4] = -b;     // ankle pitch: foot flat
  }
  q[model::kLeftArmFirst + 3] = kElbowBend_rad;
  q[model::kRightArmFirst + 3] = kElbowBend_rad;
  for (int j = 0; j < model::kNumJoints; ++j) {
    q[j] = std::clamp(q[j], model.limits.position_min_rad[j], model.limits.position_max_rad[j]);
  }
  return q;
}

dynamics::JointVector centred_standing_pose(const model::Model& model, dynamics::Data& data, double base_height_m) {
  double behind_m = 0.0;
  dynamics::JointVector pose = standing_pose(model, base_height_m, behind_m);
  for (int it = 0; it < 8; ++it) {
    dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
    q[6] = 1.0;
    q.tail<model::kNumJoints>() = pose;
    dynamics::forward_kinematics(model, data, q);
    dynamics::crba(model, data);
    double feet_x = 0.0;
    for (int c = 0; c < model::kNumContactPoints; ++c) feet_x += dynamics::frame_position(model, data, c).x();
    feet_x /= model::kNumContactPoints;
    // Moving the feet back by e moves the support centre back by e (the torso stays).
    behind_m += feet_x - data.com_m.x();
    pose = standing_pose(model, base_height_m, behind_m);
  }
  return pose;
}

void place_on_ground(const model::Model& model, dynamics::Data& data, dynamics::ConfigVector& q) {
  dynamics::forward_kinematics(model, data, q);
  double lowest = 1e9;
  for (int c = 0; c < model::kNumContactPoints; ++c) lowest = std::min(lowest, dynamics::frame_position(model, data, c).z());
  q[2] -= lowest;
}

void standing_init(const model::Model& model, const StandingConfig& config, StandingState& state) {
  state.config = config;
  state.pose_rad = centred_standing_pose(model, state.data, config.base_height_m);
  state.contact_force_N.setZero();
  state.filter_started = false;
  state.com_velocity_m_s.setZero();
  // The CoM target: where the centred pose puts it (over the middle of the feet).
  state.com_ref_m.setZero();
}

void standing_step_rt(const model::Model& model, StandingState& s, const hal::SensorFrame& sensors,
                      hal::CommandFrame& command) {
  constexpr int kN = model::kNumContactPoints;
  const StandingConfig& cfg = s.config;
  // Kinematics from the IMU orientation and the encoders; base position is irrelevant.
  dynamics::ConfigVector q = dynamics::ConfigVector::Zero();
  const auto& o = sensors.imu.orientation_xyzw;
  q.segment<4>(3) << o[0], o[1], o[2], o[3];
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  for (int k = 0; k < 3; ++k) v[3 + k] = sensors.imu.angular_rate_rad_s[k];
  for (int j = 0; j < model::kNumJoints; ++j) {
    q[7 + j] = sensors.joints[j].position_rad;
    v[6 + j] = sensors.joints[j].velocity_rad_s;
  }
  dynamics::forward_kinematics(model, s.data, q);
  dynamics::crba(model, s.data);
  dynamics::forward_velocities(model, s.data, dynamics::VelocityVector::Zero());
  dynamics::rnea(model, s.data, dynamics::VelocityVector::Zero(), true);  // gravity only

  // Feet centre, CoM relative to it, and its velocity (base linear velocity cancels).
  Eigen::Matrix<double, 2, kN> corners;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  Eigen::Matrix<double, 3, model::kNv> j_feet = Eigen::Matrix<double, 3, model::kNv>::Zero();
  for (int c = 0; c < kN; ++c) {
    corners.col(c) = dynamics::frame_position(model, s.data, c).head<2>();
    centre += corners.col(c) / kN;
    dynamics::frame_jacobian(model, s.data, c, s.jacobian);
    s.contact_jacobian.middleRows<3>(3 * c) = s.jacobian.topRows<3>();
    j_feet += s.jacobian.topRows<3>() / kN;
  }
  const Eigen::Vector2d com = s.data.com_m.head<2>() - centre;
  const Eigen::Vector2d com_velocity =
      (s.data.momentum_matrix_ref.topRows<2>() / s.data.total_mass_kg - j_feet.topRows<2>()) * v;
  const double alpha = s.filter_started ? 1.0 - std::exp(-2.0 * 3.14159265358979323846 * cfg.velocity_filter_hz * cfg.dt_s) : 1.0;
  s.com_velocity_m_s += alpha * (com_velocity - s.com_velocity_m_s);
  s.filter_started = true;

  // Capture-point law for the centre of pressure, kept inside the feet's box.
  const double height = std::max(0.3, s.data.com_m.z() - (s.data.position_m[6].z() + s.data.position_m[12].z()) * 0.5 + 0.0595);
  const double omega = std::sqrt(model::kGravity_m_s2 / height);
  const Eigen::Vector2d capture = com + s.com_velocity_m_s / omega;
  Eigen::Vector2d cop = capture + cfg.capture_gain * (capture - s.com_ref_m);
  Eigen::Vector2d lo = corners.rowwise().minCoeff() - centre, hi = corners.rowwise().maxCoeff() - centre;
  lo.array() += cfg.cop_margin_m;
  hi.array() -= cfg.cop_margin_m;
  cop = cop.cwiseMax(lo).cwiseMin(hi);
  s.cop_m = cop;

  // Vertical forces closest to an even split with total weight W and centre of pressure cop.
  const double weight_N = s.data.total_mass_kg * model::kGravity_m_s2;
  Eigen::Matrix<double, 3, kN> a;
  a.row(0).setOnes();
  a.row(1) = corners.row(0).array() - centre.x();
  a.row(2) = corners.row(1).array() - centre.y();
  const Eigen::Matrix<double, kN, 1> even = Eigen::Matrix<double, kN, 1>::Constant(weight_N / kN);
  const Eigen::Vector3d target(weight_N, weight_N * cop.x(), weight_N * cop.y());
  const Eigen::Matrix3d aat = a * a.transpose();
  Eigen::Matrix<double, kN, 1> fz = even + a.transpose() * aat.llt().solve(target - a * even);
  fz = fz.cwiseMax(0.0);
  s.contact_force_N.setZero();
  for (int c = 0; c < kN; ++c) s.contact_force_N[3 * c + 2] = fz[c];
  const dynamics::JointVector tau_ff =
      s.data.tau.tail<model::kNumJoints>() - s.contact_jacobian.rightCols<model::kNumJoints>().transpose() * s.contact_force_N;

  for (int j = 0; j < model::kNumJoints; ++j) {
    hal::JointCommand& c = command.joints[j];
    c.mode = hal::JointMode::kPdTorque;
    c.torque_ff_Nm = tau_ff[j];
    c.position_ref_rad = s.pose_rad[j];
    c.velocity_ref_rad_s = 0.0;
    if (j < model::kLeftArmFirst) {
      const int k = j % model::kLegJoints;
      c.kp_Nm_per_rad = cfg.leg_kp[k];
      c.kd_Nm_s_per_rad = cfg.leg_kd[k];
    } else if (j < model::kHeadFirst) {
      c.kp_Nm_per_rad = cfg.arm_kp;
      c.kd_Nm_s_per_rad = cfg.arm_kd;
    } else {
      c.kp_Nm_per_rad = cfg.head_kp;
      c.kd_Nm_s_per_rad = cfg.head_kd;
    }
  }
  command.stamp_ns = sensors.imu.stamp_ns;
}

}  // namespace kuavo::control
