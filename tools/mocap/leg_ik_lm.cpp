#include "tools/mocap/leg_ik_lm.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

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

Eigen::Matrix<double, 6, 6> leg_jacobian_gram(const Eigen::Matrix<double, 9, 6>& jac) {
  // Column j of the result at once, over i (the transpose makes jac's rows contiguous: the
  // inner loops vectorize, each lane its own entry's chain).
  const Eigen::Matrix<double, 6, 9> jt = jac.transpose();
  Eigen::Matrix<double, 6, 6> g;
  for (int j = 0; j < 6; ++j) {
    double* out = &g(0, j);
    if (j < 4) {  // the GEMM's 4-column panel: rows 0-7 in two alternating chains, then row 8
      double even[6] = {}, odd[6] = {};
      for (int r = 0; r < 8; r += 2) {
        const double a = jt(j, r), b = jt(j, r + 1);
        for (int i = 0; i < 6; ++i) {
          even[i] = std::fma(jt(i, r), a, even[i]);
          odd[i] = std::fma(jt(i, r + 1), b, odd[i]);
        }
      }
      const double c = jt(j, 8);
      for (int i = 0; i < 6; ++i) out[i] = std::fma(jt(i, 8), c, even[i] + odd[i]);
    } else {  // its single columns: one chain
      double sum[6] = {};
      for (int r = 0; r < 9; ++r) {
        const double a = jt(j, r);
        for (int i = 0; i < 6; ++i) sum[i] = std::fma(jt(i, r), a, sum[i]);
      }
      for (int i = 0; i < 6; ++i) out[i] = sum[i];
    }
  }
  return g;
}

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
      const Eigen::Matrix<double, 6, 6> normal = leg_jacobian_gram(jac) + lambda * Eigen::Matrix<double, 6, 6>::Identity();
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
  // Both legs posed at the returned q (each loop's last trial may have been rejected): the
  // corners need nothing else.
  for (const int first : {model::kLeftLegFirst, model::kRightLegFirst}) {
    dynamics::forward_kinematics_chain(robot, data, q, 1 + first, first + model::kLegJoints);
  }
  double worst = 0.0;
  for (int c = 0; c < model::kNumContactPoints; ++c) {
    worst = std::max(worst, (targets[c] - dynamics::frame_position(robot, data, c)).cwiseAbs().maxCoeff());
  }
  return worst;
}

}  // namespace kuavo::mocap
