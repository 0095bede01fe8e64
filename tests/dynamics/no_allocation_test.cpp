// Every rigid-body algorithm runs with the allocation trap armed and allocates nothing.
#include <gtest/gtest.h>

#include "tests/dynamics/random_state.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::test {
namespace {

model::Model g_robot;
dynamics::Data g_data;  // static storage, as the controllers keep it

TEST(RigidBodyNoAllocation, AllAlgorithmsOverManyStates) {
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, g_robot), model::ModelError::kOk);
  std::mt19937_64 rng(3);
  static dynamics::ConfigVector qs[64];
  static dynamics::VelocityVector vs[64];
  for (int i = 0; i < 64; ++i) {
    qs[i] = random_configuration(g_robot, rng);
    vs[i] = random_velocity(rng);
  }
  static dynamics::FrameJacobian jacobian;
  static dynamics::ComJacobian com_jacobian;
  double checksum = 0.0;
  AllocTrap trap;
  for (int n = 0; n < 1000; ++n) {
    const dynamics::ConfigVector& q = qs[n % 64];
    const dynamics::VelocityVector& v = vs[n % 64];
    dynamics::compute_all_terms(g_robot, g_data, q, v);
    dynamics::rnea(g_robot, g_data, v, true);
    dynamics::centroidal_dynamics(g_robot, g_data);
    dynamics::com_jacobian(g_data, com_jacobian);
    for (int f = 0; f < model::kNumFrames; ++f) {
      dynamics::frame_jacobian(g_robot, g_data, f, jacobian);
      checksum += dynamics::frame_bias_acceleration(g_robot, g_data, f)[0] +
                  dynamics::frame_velocity(g_robot, g_data, f)[1] + jacobian(0, 0);
    }
    checksum += dynamics::integrate(q, v, 0.002)[0] + g_data.mass_matrix(7, 7) + com_jacobian(0, 0);
  }
  EXPECT_EQ(trap.count(), 0u) << "first allocation: " << trap.first_size_bytes() << " bytes";
  EXPECT_TRUE(std::isfinite(checksum));
}

}  // namespace
}  // namespace kuavo::test
