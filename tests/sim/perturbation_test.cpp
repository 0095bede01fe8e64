// Model mismatch of the plant (sim/perturbation.h): each perturbation does what it says,
// checked against an expectation that does not come from the code under test: the
// plant's weight and centre of pressure at rest against the sums over the perturbed
// tables, a block sliding down a tilted ground against g(sin θ − μ cos θ), a joint
// swinging on a spring against 2π√((I + J_a)/(k_t·k)), a joint held (creeping) against
// Coulomb friction and accelerating past it against the closed forms, and biased IMU
// readings against scale·truth + bias.
#include <gtest/gtest.h>

#include <cmath>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/standing/standing_controller.h"
#include "sim/perturbation.h"
#include "sim/plant.h"
#include "sim/sensor_model.h"

namespace kuavo::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

model::Model robot() {
  model::Model m;
  model::build_model(model::Variant::kS45, 55.0, m);
  return m;
}

// Every joint held at q_ref by a stiff PD (a statue), except those the caller changes.
// The legs' gains are well above the standing robot's gravity stiffness m·g·h ≈ 500
// N·m/rad, so the statue does not sway on its ankles.
hal::CommandFrame hold(const dynamics::ConfigVector& q) {
  hal::CommandFrame c;
  for (int j = 0; j < model::kNumJoints; ++j) {
    hal::JointCommand& jc = c.joints[j];
    const bool leg = j < 2 * model::kLegJoints;
    jc.mode = hal::JointMode::kPdTorque;
    jc.position_ref_rad = q[7 + j];
    jc.kp_Nm_per_rad = leg ? 2.0e4 : 500.0;
    jc.kd_Nm_s_per_rad = leg ? 200.0 : 5.0;
  }
  return c;
}

TEST(Perturbation, NoneIsInactiveAndLeavesTheRobotAlone) {
  const model::Model m = robot();
  sim::PerturbationSet none;
  ASSERT_TRUE(sim::perturbation_set_by_name("none", none));
  const sim::PlantPerturbation p = sim::draw_perturbation(m, none, 42);
  EXPECT_FALSE(p.active);
  model::Model out;
  sim::perturbed_model(m, p, out);
  for (int b = 0; b < model::kNumBodies; ++b) {
    EXPECT_EQ(out.bodies[b].mass_kg, m.bodies[b].mass_kg);
    EXPECT_EQ(out.bodies[b].com_m, m.bodies[b].com_m);
  }
  const sim::GroundParams g = sim::perturbed_ground(sim::kCarpet, p);
  EXPECT_EQ(g.terrain, nullptr);
  EXPECT_EQ(g.friction_coefficient, sim::kCarpet.friction_coefficient);
}

TEST(Perturbation, ShowSetDrawsWithinItsRangesAndIsSeeded) {
  const model::Model m = robot();
  sim::PerturbationSet show;
  ASSERT_TRUE(sim::perturbation_set_by_name("show", show));
  ASSERT_EQ(sim::validate_perturbation_set(show), nullptr);
  const sim::PlantPerturbation a = sim::draw_perturbation(m, show, 7);
  const sim::PlantPerturbation b = sim::draw_perturbation(m, show, 7);
  const sim::PlantPerturbation c = sim::draw_perturbation(m, show, 8);
  ASSERT_TRUE(a.active);
  EXPECT_EQ(a.foot_friction, b.foot_friction);
  EXPECT_EQ(a.mass_scale, b.mass_scale);
  EXPECT_NE(a.foot_friction, c.foot_friction);
  EXPECT_GE(a.foot_friction, 0.4);
  EXPECT_LE(a.foot_friction, 1.0);
  for (int b2 = 0; b2 < model::kNumBodies; ++b2) {
    EXPECT_LE(std::abs(a.mass_scale[b2] - 1.0), 0.06);
    EXPECT_LE(a.com_offset_m[b2].cwiseAbs().maxCoeff(), 0.01);
  }
  EXPECT_LE(std::abs(std::atan(a.terrain.slope_x)), 2.0 * kPi / 180.0 + 1e-12);
  for (int j = 0; j < model::kNumJoints; ++j) {
    EXPECT_LE(a.actuation.coulomb_Nm[j], 0.02 * m.limits.peak_torque_Nm[j] + 1e-12);
    EXPECT_GE(a.actuation.armature_kgm2[j], 0.5 * sim::nominal_armature_kgm2()[j]);
  }
  sim::PerturbationSet bad = show;
  bad.foot_friction = {0.5, 0.4};
  EXPECT_NE(sim::validate_perturbation_set(bad), nullptr);
}

// The statue on the floor: at rest the ground carries the plant's weight, Σ m_i·g over the
// perturbed tables, and the centre of pressure sits under their centre of mass.
TEST(Perturbation, PlantWeightAndCentreOfMassFollowThePerturbedTables) {
  const model::Model nominal = robot();
  sim::PerturbationSet set;
  set.name = "mass";
  set.link_mass_rel = {-0.06, 0.06};
  set.link_com_m = {-0.03, 0.03};  // wider than "show", so the CoM shift dwarfs the tolerance
  set.link_inertia_rel = {-0.1, 0.1};
  const sim::PlantPerturbation p = sim::draw_perturbation(nominal, set, 11);
  model::Model plant_model;
  sim::perturbed_model(nominal, p, plant_model);

  double mass_expected = 0.0;
  for (int b = 0; b < model::kNumBodies; ++b) mass_expected += nominal.bodies[b].mass_kg * p.mass_scale[b];
  constexpr double kMassTolerance_rel = 2e-3;  // residual motion of the settling statue
  ASSERT_GT(std::abs(mass_expected - nominal.total_mass_kg), 5.0 * kMassTolerance_rel * nominal.total_mass_kg)
      << "this seed's draw does not change the mass enough to tell";

  sim::PlantConfig cfg;
  sim::Plant plant(plant_model, cfg);
  auto data = std::make_unique<dynamics::Data>();
  dynamics::ConfigVector q = dynamics::neutral_configuration(nominal);
  control::place_on_ground(nominal, *data, q);
  plant.reset(q, dynamics::VelocityVector::Zero());
  plant.set_command(hold(q));
  for (int k = 0; k < 1500; ++k) ASSERT_EQ(plant.advance(2e-3), sim::PlantError::kOk) << plant.last_error();

  const sim::PlantTruth& t = plant.truth();
  double fz = 0.0;
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    fz += t.contact_force_N[c].z();
    moment += t.contact_force_N[c].z() * t.contact_point_m[c].head<2>();
  }
  EXPECT_NEAR(fz / model::kGravity_m_s2, mass_expected, kMassTolerance_rel * mass_expected);
  EXPECT_NEAR(plant_model.total_mass_kg, mass_expected, 1e-9);

  // Closed form at the plant's pose: Σ m_i (p_i + R_i c_i) / Σ m_i over the perturbed
  // tables, the body frames from forward kinematics.
  auto com_of = [&](const model::Model& m, const std::array<double, model::kNumBodies>& scale,
                    const std::array<Eigen::Vector3d, model::kNumBodies>& offset) {
    dynamics::forward_kinematics(m, *data, t.q);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double mass = 0.0;
    for (int b = 0; b < model::kNumBodies; ++b) {
      const double mb = nominal.bodies[b].mass_kg * scale[b];
      sum += mb * (data->position_m[b] + data->rotation[b] * (nominal.bodies[b].com_m + offset[b]));
      mass += mb;
    }
    return Eigen::Vector3d(sum / mass);
  };
  const Eigen::Vector3d com_expected = com_of(nominal, p.mass_scale, p.com_offset_m);
  std::array<double, model::kNumBodies> ones;
  ones.fill(1.0);
  std::array<Eigen::Vector3d, model::kNumBodies> zeros;
  for (auto& z : zeros) z.setZero();
  const Eigen::Vector3d com_nominal = com_of(nominal, ones, zeros);
  constexpr double kCopTolerance_m = 1e-3;
  ASSERT_GT((com_expected - com_nominal).head<2>().norm(), 3.0 * kCopTolerance_m) << "draw too small to tell";
  const Eigen::Vector2d cop = moment / fz;
  EXPECT_LE((cop - com_expected.head<2>()).norm(), kCopTolerance_m);
  EXPECT_LE((t.com_m - com_expected).norm(), 1e-9);
}

// A block of mass m on one contact point of the tilted terrain: it slides down at
// g(sin θ − μ cos θ) when tan θ > μ and stays put otherwise. Semi-implicit Euler at
// 20 µs, well inside the ground spring's period (2π/√(k/m) = 21 ms).
struct Block {
  double down_slope_speed_m_s = 0.0;
  double travel_m = 0.0;
};
Block slide(double tilt_rad, double mu, double seconds, sim::Terrain& terrain) {
  terrain.slope_x = std::tan(tilt_rad);
  sim::GroundParams g = sim::kFloor;
  g.friction_coefficient = mu;
  g.terrain = &terrain;
  const double mass_kg = 7.0, dt = 2e-5;
  const Eigen::Vector3d gravity(0, 0, -model::kGravity_m_s2);
  Eigen::Vector3d p(0.0, 0.0, -mass_kg * model::kGravity_m_s2 / g.normal_stiffness), v = Eigen::Vector3d::Zero();
  sim::ContactPointState s;
  sim::update_contact_point(g, p, v, s);
  const Eigen::Vector3d p0 = p;
  const Eigen::Vector3d down = Eigen::Vector3d(-1.0, 0.0, -terrain.slope_x).normalized();
  for (int k = 0; k < static_cast<int>(seconds / dt); ++k) {
    const Eigen::Vector3d f = sim::contact_force(g, p, v, s) + mass_kg * gravity;
    v += dt * f / mass_kg;
    p += dt * v;
    sim::update_contact_point(g, p, v, s);
  }
  return {v.dot(down), (p - p0).dot(down)};
}

TEST(Perturbation, BlockSlidesDownTheTiltedGroundAtTheCoulombRate) {
  sim::Terrain terrain;
  const double tilt = 30.0 * kPi / 180.0;
  const double mu = 0.4;
  const Block a = slide(tilt, mu, 0.3, terrain);
  const Block b = slide(tilt, mu, 0.6, terrain);
  const double accel = (b.down_slope_speed_m_s - a.down_slope_speed_m_s) / 0.3;
  const double expected = model::kGravity_m_s2 * (std::sin(tilt) - mu * std::cos(tilt));
  EXPECT_NEAR(accel, expected, 0.01 * expected);
  // μ above tan θ: it holds, moving only by the stiction spring's stretch.
  const Block held = slide(tilt, 0.8, 0.6, terrain);
  EXPECT_LT(std::abs(held.travel_m), 1e-3);
  EXPECT_LT(std::abs(held.down_slope_speed_m_s), 1e-3);
}

// The drawn foot friction reaches the plant's ground: a block launched on it stops after
// v0² / (2 μ g).
TEST(Perturbation, DrawnFootFrictionSetsTheStoppingDistance) {
  const model::Model m = robot();
  sim::PerturbationSet set;
  set.name = "mu";
  set.foot_friction = {0.4, 1.0};
  const sim::PlantPerturbation p = sim::draw_perturbation(m, set, 5);
  const sim::GroundParams g = sim::perturbed_ground(sim::kFloor, p);
  ASSERT_EQ(g.friction_coefficient, p.foot_friction);
  ASSERT_GT(std::abs(p.foot_friction - sim::kFloor.friction_coefficient), 0.05);
  const double mass_kg = 7.0, dt = 2e-5, v0 = 1.0;
  Eigen::Vector3d x(0.0, 0.0, -mass_kg * model::kGravity_m_s2 / g.normal_stiffness), v(v0, 0.0, 0.0);
  sim::ContactPointState s;
  sim::update_contact_point(g, x, v, s);
  const double x0 = x.x();
  for (int k = 0; k < 100000 && v.x() > 1e-4; ++k) {
    v += dt * (sim::contact_force(g, x, v, s) / mass_kg + Eigen::Vector3d(0, 0, -model::kGravity_m_s2));
    x += dt * v;
    sim::update_contact_point(g, x, v, s);
  }
  const double expected = v0 * v0 / (2.0 * p.foot_friction * model::kGravity_m_s2);
  EXPECT_NEAR(x.x() - x0, expected, 0.01 * expected);
}

// Moment of inertia of joint j's subtree about its axis at configuration q (parallel axis
// theorem over the model's tables; frames from forward kinematics).
double subtree_inertia_about_axis(const model::Model& m, dynamics::Data& d, const dynamics::ConfigVector& q, int joint) {
  dynamics::forward_kinematics(m, d, q);
  const int root = joint + 1;
  const Eigen::Vector3d axis = d.rotation[root] * m.bodies[root].axis;
  const Eigen::Vector3d origin = d.position_m[root];
  double inertia = 0.0;
  for (int b = 1; b < model::kNumBodies; ++b) {
    int a = b;
    while (a > 0 && a != root) a = m.bodies[a].parent;
    if (a != root) continue;
    const model::Body& body = m.bodies[b];
    const Eigen::Matrix3d ic = d.rotation[b] * body.inertia_com_kgm2 * d.rotation[b].transpose();
    const Eigen::Vector3d r = d.position_m[b] + d.rotation[b] * body.com_m - origin;
    const Eigen::Vector3d r_perp = r - r.dot(axis) * axis;
    inertia += axis.dot(ic * axis) + body.mass_kg * r_perp.squaredNorm();
  }
  return inertia;
}

constexpr int kWristPitch = model::kLeftArmFirst + 6;  // zarm_l7_joint: a light distal joint

// Floating in zero gravity with every other joint held: the wrist on a spring k swings
// with the period 2π√((I + J_a) / (k_t·k)), J_a the rotor inertia, k_t the torque-constant
// error, I the hand's inertia about the axis from the tables. The floating base lowers
// the effective I by ~2e-4 kg·m² (the hand's momentum about the robot's CoM), which a
// large J_a makes a 0.05 % effect on the period. Without the armature the period would
// be ~10x shorter.
TEST(Perturbation, JointSwingPeriodIncludesArmatureAndTorqueConstant) {
  const model::Model m = robot();
  sim::JointActuation act;
  act.torque_scale.fill(1.0);
  act.armature_kgm2[kWristPitch] = 0.2;
  act.torque_scale[kWristPitch] = 1.1;
  sim::PlantConfig cfg;
  cfg.gravity = false;
  cfg.contact = false;
  cfg.relative_tolerance = 1e-8;
  cfg.absolute_tolerance = 1e-9;
  cfg.actuation = &act;
  sim::Plant plant(m, cfg);
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  auto d = std::make_unique<dynamics::Data>();
  const double inertia = subtree_inertia_about_axis(m, *d, q, kWristPitch);
  hal::CommandFrame c = hold(q);
  const double k = 5.0, amplitude = 0.1;
  c.joints[kWristPitch].kp_Nm_per_rad = k;
  c.joints[kWristPitch].kd_Nm_s_per_rad = 0.0;
  q[7 + kWristPitch] = amplitude;
  plant.reset(q, dynamics::VelocityVector::Zero());
  plant.set_command(c);
  const double expected = 2.0 * kPi * std::sqrt((inertia + act.armature_kgm2[kWristPitch]) / (1.1 * k));
  // Downward zero crossings, interpolated linearly between 1 ms samples.
  std::vector<double> crossings;
  double prev = amplitude, t_prev = 0.0;
  while (plant.time_s() < 3.5 * expected) {
    ASSERT_EQ(plant.advance(1e-3), sim::PlantError::kOk) << plant.last_error();
    const double now = plant.truth().q[7 + kWristPitch];
    if (prev > 0.0 && now <= 0.0) crossings.push_back(t_prev + (plant.time_s() - t_prev) * prev / (prev - now));
    prev = now;
    t_prev = plant.time_s();
  }
  ASSERT_GE(crossings.size(), 3u);
  const double period = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  EXPECT_NEAR(period, expected, 2e-3 * expected);
  const double without_armature = 2.0 * kPi * std::sqrt(inertia / (1.1 * k));
  EXPECT_GT(period, 3.0 * without_armature);
}

// A torque below the Coulomb level holds the joint (it creeps at the smoothing speed
// v_s·atanh(τ/τ_c)); above it the joint accelerates against Coulomb and viscous friction:
// v(t) = (τ − τ_c)/b · (1 − exp(−b t / (I + J_a))).
TEST(Perturbation, JointHeldByCoulombFrictionAndDrivenPastIt) {
  const model::Model m = robot();
  sim::JointActuation act;
  act.torque_scale.fill(1.0);
  act.armature_kgm2[kWristPitch] = 0.2;
  act.coulomb_Nm[kWristPitch] = 0.5;
  act.viscous_Nm_s_rad[kWristPitch] = 0.05;
  sim::PlantConfig cfg;
  cfg.gravity = false;
  cfg.contact = false;
  cfg.relative_tolerance = 1e-8;
  cfg.absolute_tolerance = 1e-9;
  cfg.actuation = &act;
  const dynamics::ConfigVector q0 = dynamics::neutral_configuration(m);
  auto d = std::make_unique<dynamics::Data>();
  const double inertia = subtree_inertia_about_axis(m, *d, q0, kWristPitch) + act.armature_kgm2[kWristPitch];
  auto run = [&](double torque_Nm, double seconds, double& dq, double& v) {
    sim::Plant plant(m, cfg);
    plant.reset(q0, dynamics::VelocityVector::Zero());
    hal::CommandFrame c = hold(q0);
    c.joints[kWristPitch].kp_Nm_per_rad = 0.0;
    c.joints[kWristPitch].kd_Nm_s_per_rad = 0.0;
    c.joints[kWristPitch].torque_ff_Nm = torque_Nm;
    plant.set_command(c);
    while (plant.time_s() < seconds - 1e-9) ASSERT_EQ(plant.advance(1e-3), sim::PlantError::kOk) << plant.last_error();
    dq = plant.truth().q[7 + kWristPitch] - q0[7 + kWristPitch];
    v = plant.truth().v[6 + kWristPitch];
  };
  double dq = 0.0, v = 0.0;
  // Held: τ = τ_c/2 creeps at v_s·atanh(0.5) (+ the viscous share, 0.03 % here).
  run(0.25, 1.0, dq, v);
  const double creep = sim::kCoulombSmoothing_rad_s * std::atanh(0.5);
  EXPECT_NEAR(v, creep, 0.02 * creep);
  EXPECT_LT(dq, 1.05 * creep * 1.0);
  // Driven past it: τ = 0.8 Nm.
  run(0.8, 0.5, dq, v);
  const double b = act.viscous_Nm_s_rad[kWristPitch];
  const double excess = 0.8 - act.coulomb_Nm[kWristPitch];
  const double v_expected = excess / b * (1.0 - std::exp(-b * 0.5 / inertia));
  EXPECT_NEAR(v, v_expected, 0.01 * v_expected);
}

// IMU and encoder errors: reading = scale·truth + bias, position = truth + offset, on a
// sensor model with its own noise switched off.
TEST(Perturbation, SensorErrorsBiasAndScaleTheReadings) {
  sim::SensorNoise quiet{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  sim::SensorModel sensors(3, quiet);
  sim::PlantTruth truth;
  truth.q = dynamics::ConfigVector::Zero();
  truth.q[6] = 1.0;
  truth.q[7 + 3] = 0.4;
  truth.v[3] = 0.2;
  truth.v[5] = -0.1;
  truth.base_specific_force_m_s2 = Eigen::Vector3d(0.1, 0.0, model::kGravity_m_s2);
  hal::SensorFrame clean, biased;
  sensors.sample(truth, 0, clean);
  sim::SensorErrors e;
  e.gyro_bias_rad_s = Eigen::Vector3d(0.001, -0.002, 0.0015);
  e.accel_bias_m_s2 = Eigen::Vector3d(0.03, -0.04, 0.02);
  e.gyro_scale = Eigen::Vector3d(1.004, 0.996, 1.001);
  e.accel_scale = Eigen::Vector3d(0.995, 1.003, 1.005);
  e.encoder_offset_rad[3] = 0.005;
  sensors.set_errors(&e);
  sensors.sample(truth, 0, biased);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(clean.imu.angular_rate_rad_s[k], truth.v[3 + k], 1e-15);
    EXPECT_NEAR(biased.imu.angular_rate_rad_s[k], e.gyro_scale[k] * truth.v[3 + k] + e.gyro_bias_rad_s[k], 1e-15);
    EXPECT_NEAR(biased.imu.acceleration_m_s2[k],
                e.accel_scale[k] * truth.base_specific_force_m_s2[k] + e.accel_bias_m_s2[k], 1e-14);
  }
  EXPECT_NEAR(biased.joints[3].position_rad, 0.405, 1e-15);
  EXPECT_NEAR(biased.joints[4].position_rad, 0.0, 1e-15);
}

}  // namespace
}  // namespace kuavo::test
