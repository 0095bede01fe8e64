// Random dense QPs of WBC/IK shape and an independent KKT check, for the qp tests.
// The check uses only the problem data and the returned (x, multipliers): it shares no code
// with the solver.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "controllers/qp/dense_qp.h"

namespace kuavo::qp::test {

inline double gaussian(std::mt19937_64& rng) { return std::normal_distribution<double>(0.0, 1.0)(rng); }
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

template <typename M>
void fill_gaussian(M& m, std::mt19937_64& rng) {
  for (int j = 0; j < m.cols(); ++j)
    for (int i = 0; i < m.rows(); ++i) m(i, j) = gaussian(rng);
}

// A feasible random QP: H = MᵀM/NV + reg·I, constraints built around a known feasible point
// with some rows tight, and a linear term that pushes the unconstrained minimizer far outside
// so that many inequalities end up active.
template <int NV, int NE, int NI>
void make_random_dense_qp(DenseQp<NV, NE, NI>& qp, std::mt19937_64& rng, double push = 10.0,
                          double reg = 1e-2) {
  Eigen::MatrixXd M(NV + 10, NV);
  fill_gaussian(M, rng);
  qp.H = M.transpose() * M / double(NV) + reg * Eigen::MatrixXd::Identity(NV, NV);
  for (int i = 0; i < NV; ++i) qp.g(i) = push * gaussian(rng);
  Eigen::VectorXd x_feasible(NV);
  for (int i = 0; i < NV; ++i) x_feasible(i) = gaussian(rng);
  fill_gaussian(qp.A, rng);
  if constexpr (NE > 0) qp.b = qp.A * x_feasible;
  fill_gaussian(qp.C, rng);
  if constexpr (NI > 0) for (int i = 0; i < NI; ++i) {
    const double cx = qp.C.row(i).dot(x_feasible);
    const double kind = uniform(rng, 0.0, 1.0);
    qp.c_lower(i) = kind < 0.2 ? -kInfinity : cx - uniform(rng, 0.0, 2.0);
    qp.c_upper(i) = kind > 0.8 ? kInfinity : cx + uniform(rng, 0.0, 2.0);
  }
  for (int j = 0; j < NV; ++j) {
    qp.x_lower(j) = x_feasible(j) - uniform(rng, 0.1, 3.0);
    qp.x_upper(j) = x_feasible(j) + uniform(rng, 0.1, 3.0);
  }
}

struct KktResiduals {
  double equality = 0.0;        // max |A x − b|
  double inequality = 0.0;      // max violation of l ≤ C x ≤ u and the bounds
  double stationarity = 0.0;    // max |H x + g + Aᵀy + Cᵀz + z_b|, relative to the gradient scale
  double dual_sign = 0.0;       // max wrong-signed multiplier (z > 0 needs a finite upper side ...)
  double complementarity = 0.0; // max |z| · distance to the side z points at
};

template <int NV, int NE, int NI>
KktResiduals dense_kkt(const DenseQp<NV, NE, NI>& qp, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                       const Eigen::VectorXd& z, const Eigen::VectorXd& zb) {
  KktResiduals k;
  const Eigen::MatrixXd H = qp.H.template selfadjointView<Eigen::Lower>();
  if constexpr (NE > 0) k.equality = (qp.A * x - qp.b).cwiseAbs().maxCoeff();
  Eigen::VectorXd grad = H * x + qp.g;
  const double scale = 1.0 + grad.cwiseAbs().maxCoeff();
  if constexpr (NE > 0) grad += qp.A.transpose() * y;
  if constexpr (NI > 0) grad += qp.C.transpose() * z;
  grad += zb;
  k.stationarity = grad.cwiseAbs().maxCoeff() / scale;
  auto side = [&k](double v, double lo, double hi, double mult) {
    k.inequality = std::max({k.inequality, lo - v, v - hi});
    if (mult > 0.0) {
      k.dual_sign = std::max(k.dual_sign, std::isfinite(hi) ? 0.0 : mult);
      if (std::isfinite(hi)) k.complementarity = std::max(k.complementarity, mult * std::abs(hi - v));
    } else if (mult < 0.0) {
      k.dual_sign = std::max(k.dual_sign, std::isfinite(lo) ? 0.0 : -mult);
      if (std::isfinite(lo)) k.complementarity = std::max(k.complementarity, -mult * std::abs(v - lo));
    }
  };
  if constexpr (NI > 0) for (int i = 0; i < NI; ++i) side(qp.C.row(i).dot(x), qp.c_lower(i), qp.c_upper(i), z(i));
  for (int j = 0; j < NV; ++j) side(x(j), qp.x_lower(j), qp.x_upper(j), zb(j));
  return k;
}

template <int NV, int NE, int NI>
KktResiduals dense_kkt(const DenseQp<NV, NE, NI>& qp, const DenseQpSolution<NV, NE, NI>& s) {
  return dense_kkt(qp, Eigen::VectorXd(s.x), Eigen::VectorXd(s.y_eq), Eigen::VectorXd(s.z_ineq),
                   Eigen::VectorXd(s.z_bound));
}

}  // namespace kuavo::qp::test
