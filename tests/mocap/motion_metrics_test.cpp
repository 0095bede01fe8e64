// The CoM path of a motion (tools/mocap/motion_metrics.h). Oracles: closed forms of rigid
// motions -- a robot translated as a whole moves its CoM by the translation; one turned
// about a vertical axis through a point moves it on a circle about that point's vertical --
// and the CoM of the rigid-body library's CRBA for the standing frame.
#include "tools/mocap/motion_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/mocap/motion_fixture.h"

namespace kuavo::mocap::test {
namespace {

// A square walked by the whole robot: 4 sides of 0.3 m in 10 frames each.
TEST(MotionMetrics, ARigidTranslationMovesTheComAlongTheSamePath) {
  const ConfigVector q0 = standing().q;
  std::vector<ConfigVector> q;
  const Vec3 corner[] = {{0, 0, 0}, {0.3, 0, 0}, {0.3, 0.3, 0}, {0, 0.3, 0}, {0, 0, 0}};
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < 10; ++k) {
      ConfigVector qi = q0;
      qi.head<3>() += corner[side] + (corner[side + 1] - corner[side]) * (k / 10.0);
      q.push_back(qi);
    }
  }
  q.push_back(q0);
  const std::vector<Vec3> com = com_trajectory(robot(), q);
  ASSERT_EQ(com.size(), q.size());
  dynamics::compute_all_terms(robot(), scratch(), q0, dynamics::VelocityVector::Zero());
  EXPECT_LT((com[0] - scratch().com_m).norm(), 1e-12);
  for (std::size_t i = 0; i < q.size(); ++i) EXPECT_LT((com[i] - com[0] - (q[i].head<3>() - q0.head<3>())).norm(), 1e-12);
  const int last = static_cast<int>(com.size()) - 1;
  EXPECT_NEAR(path_length(com, 0, last), 1.2, 1e-12);
  // Additive over a split, clamped at the ends, empty when reversed.
  EXPECT_NEAR(path_length(com, 0, 15) + path_length(com, 15, last), 1.2, 1e-12);
  EXPECT_NEAR(path_length(com, -5, last + 7), 1.2, 1e-12);
  EXPECT_NEAR(path_length(com, 0, 10), 0.3, 1e-12);
  EXPECT_EQ(path_length(com, 12, 3), 0.0);
}

// Turning in place about the vertical through the base origin: the CoM keeps its height and
// its distance r from that vertical, so its path over a turn of θ is the arc r·θ (the
// polyline of n chords: 2 n r sin(θ / 2n)).
TEST(MotionMetrics, TurningInPlaceMovesTheComOnAnArc) {
  const ConfigVector q0 = standing().q;
  std::vector<ConfigVector> q;
  const int n = 36;
  const double theta = M_PI / 2.0;
  const Mat3 r0 = Eigen::Quaterniond(q0[6], q0[3], q0[4], q0[5]).toRotationMatrix();
  for (int i = 0; i <= n; ++i) {
    ConfigVector qi = q0;
    set_base_rotation(qi, rot_z(theta * i / n) * r0);
    q.push_back(qi);
  }
  const std::vector<Vec3> com = com_trajectory(robot(), q);
  const double r = (com[0] - q0.head<3>()).head<2>().norm();
  ASSERT_GT(r, 1e-3) << "the standing CoM must be off the base's vertical for the test to mean anything";
  for (const Vec3& c : com) EXPECT_NEAR((c - q0.head<3>()).head<2>().norm(), r, 1e-12);
  EXPECT_NEAR(path_length(com, 0, n), 2.0 * n * r * std::sin(theta / (2.0 * n)), 1e-12);
}

}  // namespace
}  // namespace kuavo::mocap::test
