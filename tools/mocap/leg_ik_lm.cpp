#include "tools/mocap/leg_ik_lm.h"

#include <Eigen/Cholesky>
#include <algorithm>

namespace kuavo::mocap {
namespace {

using dynamics::ConfigVector;
using dynamics::Vec3;
using Err = Eigen::Matrix<double, 9, 1>;
using Jac = Eigen::Matrix<double, 9, 6>;

constexpr int kCorners[2][3] = {{0, 1, 2}, {4, 5, 6}};  // three corners fix a foot
constexpr int kMaxIterations = 60;
constexpr double kLambdaStart = 1e-6, kLambdaMin = 1e-9, kLambdaMax = 1e3;

double foot_error(const model::Model& robot, dynamics::Data& data, const std::array<Vec3, model::kNumContactPoints>& targets,
                  const ConfigVector& q, int foot, Err& err) {
  // The base and this leg's bodies only: the corners and their Jacobian need nothing else.
  const int first_body = 1 + (foot == 0 ? model::kLeftLegFirst : model::kRightLegFirst);
  dynamics::forward_kinematics_chain(robot, data, q, first_body, first_body + model::kLegJoints - 1);
  for (int r = 0; r < 3; ++r) {
    const int c = kCorners[foot][r];
    err.segment<3>(3 * r) = targets[c] - dynamics::frame_position(robot, data, c);
  }
  return err.norm();
}

// The foot's corner Jacobian in its leg's joints at the kinematics data holds (foot_error's q).
void foot_jacobian(const model::Model& robot, const dynamics::Data& data, int foot, Jac& jac) {
  const int first = foot == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
  dynamics::FrameJacobian j;
  for (int r = 0; r < 3; ++r) {
    dynamics::frame_jacobian(robot, data, kCorners[foot][r], j);
    jac.middleRows<3>(3 * r) = j.block<3, 6>(0, 6 + first);
  }
}

}  // namespace

double leg_ik_lm(const model::Model& robot, dynamics::Data& data, const std::array<Vec3, model::kNumContactPoints>& targets,
                 ConfigVector& q) {
  const auto& lim = robot.limits;
  for (int foot = 0; foot < 2; ++foot) {
    const int joint0 = foot == 0 ? model::kLeftLegFirst : model::kRightLegFirst;
    const int col = 7 + joint0;
    const Eigen::Matrix<double, 6, 1> lo = lim.position_min_rad.segment<6>(joint0);
    const Eigen::Matrix<double, 6, 1> hi = lim.position_max_rad.segment<6>(joint0);
    q.segment<6>(col) = q.segment<6>(col).cwiseMax(lo).cwiseMin(hi);
    double lambda = kLambdaStart;
    Err err, trial_err;
    Jac jac;
    double e = foot_error(robot, data, targets, q, foot, err);
    foot_jacobian(robot, data, foot, jac);
    for (int it = 0; it < kMaxIterations && e > 1e-9; ++it) {
      const Eigen::Matrix<double, 6, 6> normal = jac.transpose() * jac + lambda * Eigen::Matrix<double, 6, 6>::Identity();
      const Eigen::Matrix<double, 6, 1> keep = q.segment<6>(col);
      q.segment<6>(col) = (keep + normal.ldlt().solve(jac.transpose() * err)).cwiseMax(lo).cwiseMin(hi);
      const double trial = foot_error(robot, data, targets, q, foot, trial_err);
      if (trial < e) {
        // Accepted: data holds the trial's kinematics; the error and Jacobian come from it.
        lambda = std::max(kLambdaMin, 0.3 * lambda);
        e = trial;
        err = trial_err;
        foot_jacobian(robot, data, foot, jac);
      } else {
        q.segment<6>(col) = keep;
        lambda *= 10.0;
        if (lambda > kLambdaMax) break;
      }
    }
  }
  dynamics::forward_kinematics(robot, data, q);
  double worst = 0.0;
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    worst = std::max(worst, (targets[c] - dynamics::frame_position(robot, data, c)).cwiseAbs().maxCoeff());
  }
  return worst;
}

}  // namespace kuavo::mocap
