// Reference interpolation between two MPC knots.
#include <gtest/gtest.h>

#include "controllers/wbc/wbc_reference.h"

namespace kuavo::test {
namespace {

TEST(WbcReference, LinearBlendYawShortWayFlagsFromFirstKnot) {
  static wbc::WbcReference a, b, out;
  a.stamp_ns = 0;
  b.stamp_ns = 20'000'000;
  a.com_position_m = Eigen::Vector3d(0, 0, 0.8);
  b.com_position_m = Eigen::Vector3d(0.1, 0, 0.8);
  a.base_euler_zyx_rad[0] = 3.1;
  b.base_euler_zyx_rad[0] = -3.1;  // 0.083 rad away across ±π
  a.joint_position_rad.setConstant(1.0);
  b.joint_position_rad.setConstant(2.0);
  a.in_contact.fill(true);
  b.in_contact.fill(false);
  wbc::wbc_interpolate_reference(a, b, 0.25, out);
  EXPECT_EQ(out.stamp_ns, 5'000'000);
  EXPECT_NEAR(out.com_position_m.x(), 0.025, 1e-15);
  EXPECT_NEAR(out.joint_position_rad[7], 1.25, 1e-15);
  EXPECT_NEAR(out.base_euler_zyx_rad[0], 3.1 + 0.25 * (2 * 3.14159265358979323846 - 6.2), 1e-12);
  EXPECT_TRUE(out.in_contact[0]);
  wbc::wbc_interpolate_reference(a, b, 7.0, out);  // clamped
  EXPECT_NEAR(out.com_position_m.x(), 0.1, 1e-15);
}

TEST(WbcReference, EulerRoundTrip) {
  const Eigen::Vector3d ypr(0.7, -0.3, 0.2);
  EXPECT_LT((wbc::euler_zyx_from_rotation(wbc::rotation_from_euler_zyx(ypr)) - ypr).norm(), 1e-12);
}

}  // namespace
}  // namespace kuavo::test
