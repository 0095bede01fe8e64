#include "sim/newton_system.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kuavo::sim {

SUNLinearSolver NewtonSystem::make_linear_solver(SUNContext ctx) {
  SUNLinearSolver s = SUNLinSolNewEmpty(ctx);
  if (s == nullptr) return nullptr;
  s->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  s->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  s->ops->setup = setup;
  s->ops->solve = solve;
  s->ops->free = free;
  s->content = this;  // owned by the plant, not by the solver
  return s;
}

int NewtonSystem::free(SUNLinearSolver s) {
  if (s == nullptr) return 0;
  s->content = nullptr;
  SUNLinSolFreeEmpty(s);
  return 0;
}

int NewtonSystem::update(void* cvode, CVRhsFn f, void* user, sunrealtype t, N_Vector y, N_Vector fy, bool jok,
                         bool* jcur, sunrealtype gamma, N_Vector tmp1, N_Vector tmp2) {
  gamma_ = gamma;
  *jcur = false;
  if (jok) return 0;
  *jcur = true;
  ++jacobian_evaluations_;
  // Increments as cvLsDenseDQJac chooses them: √ε·|y_j|, at least a share of 1/ewt_j.
  N_Vector ewt = tmp1;
  CVodeGetErrWeights(cvode, ewt);
  sunrealtype h = 0.0;
  CVodeGetCurrentStep(cvode, &h);
  const double srur = std::sqrt(std::numeric_limits<double>::epsilon());
  const double fnorm = N_VWrmsNorm(fy, ewt);
  const double min_inc =
      fnorm != 0.0 ? 1000.0 * std::abs(h) * std::numeric_limits<double>::epsilon() * kN * fnorm : 1.0;
  const double* w = N_VGetArrayPointer(ewt);
  double* yd = N_VGetArrayPointer(y);
  const double* f0 = N_VGetArrayPointer(fy);
  const double* f1 = N_VGetArrayPointer(tmp2);
  for (int j = 0; j < kNq + kNu; ++j) {
    const double saved = yd[j];
    const double inc = std::max(srur * std::abs(saved), min_inc / w[j]);
    yd[j] = saved + inc;
    const int rc = f(t, y, tmp2, user);
    yd[j] = saved;
    if (rc != 0) return rc;
    const double inv = 1.0 / inc;
    // Column j of J, split into its blocks (the q̇ rows of a q column are Jqq: dropped).
    if (j < kNq) {
      for (int i = 0; i < kNu; ++i) juq_(i, j) = (f1[kNq + i] - f0[kNq + i]) * inv;
      for (int i = 0; i < kNz; ++i) jzq_(i, j) = (f1[kNq + kNu + i] - f0[kNq + kNu + i]) * inv;
    } else {
      const int k = j - kNq;
      for (int i = 0; i < kNq; ++i) jqu_(i, k) = (f1[i] - f0[i]) * inv;
      for (int i = 0; i < kNu; ++i) juu_(i, k) = (f1[kNq + i] - f0[kNq + i]) * inv;
      for (int i = 0; i < kNz; ++i) jzu_(i, k) = (f1[kNq + kNu + i] - f0[kNq + kNu + i]) * inv;
    }
  }
  juq_jqu_.noalias() = juq_ * jqu_;  // γ-free: every setup until the next J reuses it
  return 0;
}

int NewtonSystem::setup(SUNLinearSolver s, SUNMatrix) {
  auto* self = static_cast<NewtonSystem*>(s->content);
  const double g = self->gamma_;
  self->schur_ = -(g * g) * self->juq_jqu_ - g * self->juu_;
  self->schur_.diagonal().array() += 1.0;
  self->lu_.compute(self->schur_);
  // A zero pivot: tell CVODE the factorisation failed (recoverable: it retries with a smaller step).
  return self->lu_.matrixLU().diagonal().cwiseAbs().minCoeff() > 0.0 ? 0 : SUNLS_LUFACT_FAIL;
}

int NewtonSystem::solve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) {
  auto* self = static_cast<NewtonSystem*>(s->content);
  const double g = self->gamma_;
  const double* bd = N_VGetArrayPointer(b);
  double* xd = N_VGetArrayPointer(x);  // may alias b
  const Eigen::Map<const Eigen::Matrix<double, kNq, 1>> bq(bd);
  const Eigen::Map<const Eigen::Matrix<double, kNu, 1>> bu(bd + kNq);
  const Eigen::Matrix<double, kNz, 1> bz = Eigen::Map<const Eigen::Matrix<double, kNz, 1>>(bd + kNq + kNu);
  const Eigen::Matrix<double, kNu, 1> xu = self->lu_.solve(bu + g * (self->juq_ * bq));
  const Eigen::Matrix<double, kNq, 1> xq = bq + g * (self->jqu_ * xu);
  Eigen::Map<Eigen::Matrix<double, kN, 1>> out(xd);
  out.head<kNq>() = xq;
  out.segment<kNu>(kNq) = xu;
  out.tail<kNz>() = bz + g * (self->jzq_ * xq + self->jzu_ * xu);
  return 0;
}

}  // namespace kuavo::sim
