// plan_knot_from_state against the CRBA/centroidal pass (an independent CoM and momentum)
// and the frame API.
#include "controllers/planner/plan_knot.h"

#include <gtest/gtest.h>

#include <random>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::planner {
namespace {

TEST(PlanKnot, ComAndCornersMatchTheDynamicsPasses) {
  model::Model robot;
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, robot), model::ModelError::kOk);
  static dynamics::Data data, oracle;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (int trial = 0; trial < 20; ++trial) {
    dynamics::ConfigVector q = dynamics::neutral_configuration(robot);
    q.head<3>() += dynamics::Vec3(u(rng), u(rng), u(rng));
    q.segment<4>(3) = Eigen::Quaterniond(1.0, u(rng), u(rng), u(rng)).normalized().coeffs();
    dynamics::VelocityVector v;
    for (int i = 0; i < model::kNv; ++i) v[i] = u(rng);
    for (int j = 0; j < model::kNumJoints; ++j) q[7 + j] = 0.5 * u(rng);
    ContactFlags flags{};
    flags[trial % kNumPoints] = true;
    PlanKnot knot;
    plan_knot_from_state(robot, data, q, v, flags, 123, knot);

    dynamics::compute_all_terms(robot, oracle, q, v);
    const dynamics::Vec6 h = oracle.centroidal_matrix * v;
    EXPECT_LT((knot.com_position_m - oracle.com_m).norm(), 1e-12);
    EXPECT_LT((knot.com_velocity_m_s - h.head<3>() / oracle.total_mass_kg).norm(), 1e-12);
    for (int c = 0; c < kNumPoints; ++c) {
      EXPECT_LT((knot.point_position_m.segment<3>(3 * c) - dynamics::frame_position(robot, oracle, c)).norm(), 1e-12);
      dynamics::FrameJacobian j;
      dynamics::frame_jacobian(robot, oracle, c, j);
      EXPECT_LT((knot.point_velocity_m_s.segment<3>(3 * c) - (j * v).head<3>()).norm(), 1e-12);
    }
    EXPECT_EQ(knot.stamp_ns, 123);
    EXPECT_EQ(knot.in_contact, flags);
  }
}

}  // namespace
}  // namespace kuavo::planner
