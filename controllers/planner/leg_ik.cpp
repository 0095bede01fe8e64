#include "controllers/planner/leg_ik.h"

#include <algorithm>

#include "controllers/dynamics/rigid_body.h"

namespace kuavo::planner {
namespace {

constexpr int kIkIterations = 20;
// Three corners fix a foot's pose: toe-left, toe-right, heel-left of each foot.
constexpr int kFootCorners[2][3] = {{0, 1, 2}, {4, 5, 6}};

}  // namespace

double solve_leg_ik(const model::Model& model, dynamics::Data& data, const std::array<Vec3, kNumPoints>& targets,
                    dynamics::ConfigVector& q) {
  double worst = 0.0;
  dynamics::FrameJacobian j;
  for (int it = 0; it < kIkIterations; ++it) {
    dynamics::forward_kinematics(model, data, q);
    worst = 0.0;
    for (int foot = 0; foot < 2; ++foot) {
      Eigen::Matrix<double, 9, 6> jac;
      Eigen::Matrix<double, 9, 1> err;
      const int first_joint = foot == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
      for (int r = 0; r < 3; ++r) {
        const int c = kFootCorners[foot][r];
        dynamics::frame_jacobian(model, data, c, j);
        jac.middleRows<3>(3 * r) = j.block<3, 6>(0, 6 + first_joint);
        err.segment<3>(3 * r) = targets[c] - dynamics::frame_position(model, data, c);
      }
      worst = std::max(worst, err.cwiseAbs().maxCoeff());
      const Eigen::Matrix<double, 6, 6> normal = jac.transpose() * jac + 1e-9 * Eigen::Matrix<double, 6, 6>::Identity();
      q.segment<6>(7 + first_joint) += normal.ldlt().solve(jac.transpose() * err);
    }
    if (worst < 1e-9) break;
  }
  dynamics::forward_kinematics(model, data, q);
  worst = 0.0;
  for (int c = 0; c < kNumPoints; ++c) worst = std::max(worst, (targets[c] - dynamics::frame_position(model, data, c)).cwiseAbs().maxCoeff());
  return worst;
}

}  // namespace kuavo::planner
