// forward_kinematics_chain (one limb's poses only, for the offline leg IK) against the whole
// forward_kinematics, which the Simbody oracle checks: the chain's bodies bit for bit, its
// frames' positions and Jacobians bit for bit, and nothing outside the chain written.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/dynamics/random_state.h"

namespace kuavo::test {
namespace {

using dynamics::ConfigVector;

struct Chain {
  int first_joint, joints;
};
constexpr Chain kChains[] = {{model::kLeftLegFirst, model::kLegJoints},
                             {model::kRightLegFirst, model::kLegJoints},
                             {model::kLeftArmFirst, model::kArmJoints},
                             {model::kRightArmFirst, model::kArmJoints},
                             {model::kHeadFirst, 2}};

bool same_bits(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

template <typename M>
bool all_same_bits(const M& a, const M& b) {
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    if (!same_bits(a.data()[i], b.data()[i])) return false;
  }
  return true;
}

template <typename M>
bool all_nan(const M& a) {
  return a.array().isNaN().all();
}

TEST(KinematicsChain, LimbPosesMatchWholeKinematicsBitForBitAndTouchNothingElse) {
  model::Model robot;
  ASSERT_EQ(model::build_model(model::Variant::kS45, 55.0, robot), model::ModelError::kOk);
  std::mt19937_64 rng(23);
  auto whole = std::make_unique<dynamics::Data>();
  auto chain = std::make_unique<dynamics::Data>();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  int frames_checked = 0;
  for (int n = 0; n < 40; ++n) {
    const ConfigVector q = random_configuration(robot, rng);
    dynamics::forward_kinematics(robot, *whole, q);
    for (const Chain& c : kChains) {
      for (int b = 0; b < model::kNumBodies; ++b) {
        chain->position_m[b].setConstant(nan);
        chain->rotation[b].setConstant(nan);
        chain->motion_subspace[b].setConstant(nan);
      }
      const int first = 1 + c.first_joint, last = c.first_joint + c.joints;
      dynamics::forward_kinematics_chain(robot, *chain, q, first, last);
      for (int b = 0; b < model::kNumBodies; ++b) {
        const bool in = b == 0 || (b >= first && b <= last);
        if (in) {
          EXPECT_TRUE(all_same_bits(chain->position_m[b], whole->position_m[b])) << "body " << b;
          EXPECT_TRUE(all_same_bits(chain->rotation[b], whole->rotation[b])) << "body " << b;
          if (b > 0) {
            EXPECT_TRUE(all_same_bits(chain->motion_subspace[b], whole->motion_subspace[b])) << "body " << b;
          }
        } else {
          EXPECT_TRUE(all_nan(chain->position_m[b]) && all_nan(chain->rotation[b]) &&
                      all_nan(chain->motion_subspace[b]))
              << "body " << b << " outside the chain was written";
        }
      }
      // The chain's frames (sole corners, hands, camera on the head): positions and Jacobians.
      for (int f = 0; f < model::kNumFrames; ++f) {
        const int b = robot.frames[f].body;
        if (b < first || b > last) continue;
        ++frames_checked;
        EXPECT_TRUE(all_same_bits(dynamics::frame_position(robot, *chain, f), dynamics::frame_position(robot, *whole, f)));
        dynamics::FrameJacobian jc, jw;
        dynamics::frame_jacobian(robot, *chain, f, jc);
        dynamics::frame_jacobian(robot, *whole, f, jw);
        EXPECT_TRUE(all_same_bits(jc, jw)) << "frame " << f;
      }
    }
  }
  // Each sample reaches the 8 sole corners and both hands at least.
  EXPECT_GE(frames_checked, 40 * 10);
}

}  // namespace
}  // namespace kuavo::test
