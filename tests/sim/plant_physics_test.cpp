// Physics sanity of the plant against Newton–Euler on the whole body, and the
// two integrators (SUNDIALS CVODE, Simbody RKM) against each other.
#include <gtest/gtest.h>

#include "controllers/dynamics/rigid_body.h"
#include "sim/plant.h"

namespace kuavo::test {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;

model::Model robot() {
  model::Model m;
  model::build_model(model::Variant::kS45, 55.0, m);
  return m;
}

hal::CommandFrame limp() { return hal::CommandFrame{}; }

// Dropped from 5 cm with the joints limp: over the fall, touchdown and first
// settling, the change of linear momentum equals gravity's impulse plus the contact
// impulse, and the change of angular momentum about the world origin equals the
// moments of both (Newton–Euler on the whole body). The contact impulse is
// integrated by CVODE as quadrature states, to the same tolerance as the motion.
TEST(PlantPhysics, MomentumChangeMatchesGravityAndContactImpulses) {
  const model::Model m = robot();
  sim::PlantConfig cfg;
  cfg.relative_tolerance = 1e-7;
  cfg.absolute_tolerance = 1e-8;
  sim::Plant plant(m, cfg);
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  q[2] += 0.05;
  q[3] = 0.05;  // a little roll so the feet land unevenly
  q.segment<4>(3).normalize();
  plant.reset(q, dynamics::VelocityVector::Zero());
  plant.set_command(limp());
  auto momentum_about_origin = [&](const sim::PlantTruth& t) {
    Vec6 h;
    h.head<3>() = t.momentum.head<3>();
    h.tail<3>() = t.momentum.tail<3>() + t.com_m.cross(t.momentum.head<3>());
    return h;
  };
  const Vec6 h0 = momentum_about_origin(plant.truth());
  const Eigen::Vector3d weight(0, 0, -m.total_mass_kg * model::kGravity_m_s2);
  Eigen::Vector3d gravity_moment = Eigen::Vector3d::Zero();
  Eigen::Vector3d c_prev = plant.truth().com_m;
  double peak_force = 0.0;
  const double dt = 1e-3;
  const int steps = 300;  // 0.3 s
  for (int k = 0; k < steps; ++k) {
    ASSERT_EQ(plant.advance(dt), sim::PlantError::kOk) << plant.last_error();
    // ∫ c × m g dt: c moves smoothly, the trapezoid is accurate to O(dt²·c̈).
    gravity_moment += 0.5 * dt * (c_prev + plant.truth().com_m).cross(weight);
    c_prev = plant.truth().com_m;
    for (const auto& f : plant.truth().contact_force_N) peak_force = std::max(peak_force, f.z());
  }
  ASSERT_GT(peak_force, 10.0) << "the robot never landed";
  const Vec6 dh = momentum_about_origin(plant.truth()) - h0;
  const Vec6 impulse = plant.contact_impulse();
  const Eigen::Vector3d linear_expected = impulse.head<3>() + weight * steps * dt;
  const Eigen::Vector3d angular_expected = impulse.tail<3>() + gravity_moment;
  EXPECT_LE((dh.head<3>() - linear_expected).norm(), 1e-5 * linear_expected.norm());
  EXPECT_LE((dh.tail<3>() - angular_expected).norm(), 1e-3);
  // The contact carried real load: its impulse is a sizeable part of gravity's.
  EXPECT_GT(impulse[2], 0.3 * m.total_mass_kg * model::kGravity_m_s2 * steps * dt);
}

TEST(PlantPhysics, FreeFallIsBallistic) {
  const model::Model m = robot();
  sim::PlantConfig cfg;
  cfg.contact = false;
  cfg.relative_tolerance = 1e-9;
  cfg.absolute_tolerance = 1e-10;
  sim::Plant plant(m, cfg);
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  dynamics::VelocityVector v = dynamics::VelocityVector::Zero();
  v[0] = 0.3;   // forward, base axes = world at identity
  v[5] = 0.4;   // yaw spin
  v[6 + 3] = 1.0;  // left knee swinging
  plant.reset(q, v);
  plant.set_command(limp());
  const Vec6 h0 = plant.truth().momentum;
  const Eigen::Vector3d c0 = plant.truth().com_m;
  for (int k = 0; k < 100; ++k) ASSERT_EQ(plant.advance(2e-3), sim::PlantError::kOk) << plant.last_error();
  const double t = 0.2;
  const Vec6 h1 = plant.truth().momentum;
  EXPECT_NEAR(h1[2] - h0[2], -m.total_mass_kg * model::kGravity_m_s2 * t, 1e-6);
  EXPECT_NEAR(h1[0] - h0[0], 0.0, 1e-6);
  EXPECT_LE((h1.tail<3>() - h0.tail<3>()).norm(), 1e-6);  // no external moment about the CoM
  const Eigen::Vector3d c_expected = c0 + h0.head<3>() / m.total_mass_kg * t - Eigen::Vector3d(0, 0, 0.5 * model::kGravity_m_s2 * t * t);
  EXPECT_LE((plant.truth().com_m - c_expected).norm(), 1e-6);
}

TEST(PlantIntegrators, CvodeAgreesWithSimbodyRungeKuttaMerson) {
  const model::Model m = robot();
  sim::PlantConfig a_cfg, b_cfg;
  a_cfg.relative_tolerance = b_cfg.relative_tolerance = 1e-8;
  a_cfg.absolute_tolerance = 1e-9;
  b_cfg.integrator = sim::Integrator::kSimbodyRungeKuttaMerson;
  sim::Plant a(m, a_cfg), b(m, b_cfg);
  dynamics::ConfigVector q = dynamics::neutral_configuration(m);
  q[2] += 0.01;
  hal::CommandFrame hold;
  for (int j = 0; j < model::kNumJoints; ++j) {
    hold.joints[j] = {hal::JointMode::kPdTorque, 0.0, 0.0, 0.0, 200.0, 5.0};
  }
  a.reset(q, dynamics::VelocityVector::Zero());
  b.reset(q, dynamics::VelocityVector::Zero());
  a.set_command(hold);
  b.set_command(hold);
  for (int k = 0; k < 50; ++k) {  // 0.1 s, through touchdown
    ASSERT_EQ(a.advance(2e-3), sim::PlantError::kOk) << a.last_error();
    ASSERT_EQ(b.advance(2e-3), sim::PlantError::kOk) << b.last_error();
  }
  EXPECT_LE((a.truth().q - b.truth().q).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LE((a.truth().v - b.truth().v).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_GT(a.truth().contact_force_N[0].z(), 0.0);
}

}  // namespace
}  // namespace kuavo::test
