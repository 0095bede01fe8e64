// Random OCP QPs and their dense transcription, for the qp tests. The transcription is the
// independent oracle: it is written directly from the problem statement in ocp_qp.h and shares
// no code with the Riccati solver.
#pragma once

#include <Eigen/Core>
#include <random>

#include "controllers/qp/ocp_qp.h"
#include "tests/qp/dense_qp_fixtures.h"

namespace kuavo::qp::test {

// Dense form in z = [u₀, x₁, u₁, x₂, …, u_{T−1}, x_T] (x₀ is data):
//   min ½zᵀHz + gᵀz  s.t.  Aeq z = beq,  G z ≤ h,
// with the multiplier order [π₁, ν₀, π₂, ν₁, …] for Aeq and [λ₀, λ₁, …, λ_T] for G.
struct DenseTranscription {
  Eigen::MatrixXd H, Aeq, G;
  Eigen::VectorXd g, beq, h;
};

template <int NX, int NU, int N, int NC, int NG>
DenseTranscription transcribe(const OcpQp<NX, NU, N, NC, NG>& qp) {
  const int T = qp.horizon, nz = NX + NU;
  const int nv = T * nz, ne = T * (NX + NC), ni = (T + 1) * NG;
  DenseTranscription d;
  d.H = Eigen::MatrixXd::Zero(nv, nv);
  d.g = Eigen::VectorXd::Zero(nv);
  d.Aeq = Eigen::MatrixXd::Zero(ne, nv);
  d.beq = Eigen::VectorXd::Zero(ne);
  d.G = Eigen::MatrixXd::Zero(ni, nv);
  d.h = Eigen::VectorXd::Zero(ni);
  auto iu = [&](int k) { return k * nz; };           // u_k, k < T
  auto ix = [&](int k) { return (k - 1) * nz + NU; };  // x_k, k ≥ 1
  const Eigen::Matrix<double, NX, 1> x0 = qp.x_initial;
  for (int k = 0; k <= T; ++k) {
    const auto& s = qp.stages[k];
    // Cost.
    if (k < T) {
      d.H.block(iu(k), iu(k), NU, NU) += s.R;
      d.g.segment(iu(k), NU) += s.r;
      if (k == 0) {
        d.g.segment(iu(k), NU).noalias() += s.S * x0;
      } else {
        d.H.block(ix(k), ix(k), NX, NX) += s.Q;
        d.H.block(iu(k), ix(k), NU, NX) += s.S;
        d.H.block(ix(k), iu(k), NX, NU) += s.S.transpose();
        d.g.segment(ix(k), NX) += s.q;
      }
    } else if (k > 0) {
      d.H.block(ix(k), ix(k), NX, NX) += s.Q;
      d.g.segment(ix(k), NX) += s.q;
    }
    // Dynamics and stage equalities.
    if (k < T) {
      const int row = k * (NX + NC);
      d.Aeq.block(row, iu(k), NX, NU) = s.B;
      d.Aeq.block(row, ix(k + 1), NX, NX) = -Eigen::MatrixXd::Identity(NX, NX);
      d.beq.segment(row, NX) = -s.b;
      if (k == 0) {
        d.beq.segment(row, NX) -= s.A * x0;
      } else {
        d.Aeq.block(row, ix(k), NX, NX) = s.A;
      }
      for (int i = 0; i < s.num_eq; ++i) {  // unused rows stay 0 = 0
        d.Aeq.block(row + NX + i, iu(k), 1, NU) = s.D.row(i);
        d.beq(row + NX + i) = s.e(i);
        if (k == 0) {
          d.beq(row + NX + i) -= s.C.row(i).dot(x0);
        } else {
          d.Aeq.block(row + NX + i, ix(k), 1, NX) = s.C.row(i);
        }
      }
    }
    // Inequalities (unused rows: 0 ≤ 1).
    if constexpr (NG > 0) for (int i = 0; i < NG; ++i) {
      const int row = k * NG + i;
      if (i >= s.num_ineq) {
        d.h(row) = 1.0;
        continue;
      }
      d.h(row) = s.h(i);
      if (k < T) d.G.block(row, iu(k), 1, NU) = s.Gu.row(i);
      if (k == 0) {
        d.h(row) -= s.Gx.row(i).dot(x0);
      } else {
        d.G.block(row, ix(k), 1, NX) = s.Gx.row(i);
      }
    }
  }
  return d;
}

template <int NX, int NU, int N, int NC, int NG, typename Sol>
void pack(const OcpQp<NX, NU, N, NC, NG>& qp, const Sol& sol, Eigen::VectorXd& z, Eigen::VectorXd& y,
          Eigen::VectorXd& lam) {
  const int T = qp.horizon, nz = NX + NU;
  z.resize(T * nz);
  y.setZero(T * (NX + NC));
  lam.setZero((T + 1) * NG);
  for (int k = 0; k < T; ++k) {
    z.segment(k * nz, NU) = sol.u[k];
    z.segment(k * nz + NU, NX) = sol.x[k + 1];
    y.segment(k * (NX + NC), NX) = sol.costate[k + 1];
    y.segment(k * (NX + NC) + NX, NC) = sol.nu[k];
  }
  for (int k = 0; k <= T; ++k) lam.segment(k * NG, NG) = sol.lambda[k];
}

struct OcpKkt {
  double equality = 0.0, inequality = 0.0, stationarity = 0.0, dual_sign = 0.0, complementarity = 0.0;
};

// KKT residuals of the dense transcription at the OCP solution and multipliers.
template <int NX, int NU, int N, int NC, int NG, typename Sol>
OcpKkt ocp_kkt(const OcpQp<NX, NU, N, NC, NG>& qp, const Sol& sol) {
  const DenseTranscription d = transcribe(qp);
  Eigen::VectorXd z, y, lam;
  pack(qp, sol, z, y, lam);
  OcpKkt k;
  if (z.size() == 0) return k;
  const Eigen::VectorXd grad = d.H * z + d.g;
  const double scale = 1.0 + grad.cwiseAbs().maxCoeff();
  k.stationarity = (grad + d.Aeq.transpose() * y + d.G.transpose() * lam).cwiseAbs().maxCoeff() / scale;
  k.equality = (d.Aeq * z - d.beq).cwiseAbs().maxCoeff();
  if (lam.size() == 0) return k;
  const Eigen::VectorXd slack = d.h - d.G * z;
  k.inequality = std::max(0.0, -slack.minCoeff());
  k.dual_sign = std::max(0.0, -lam.minCoeff());
  k.complementarity = (lam.array() * slack.array().abs()).maxCoeff();
  return k;
}

// Random strictly feasible OCP: a random trajectory defines the equality right-hand sides and
// sits strictly inside the inequalities; a large linear term pulls the optimum against them.
template <int NX, int NU, int N, int NC, int NG>
void make_random_ocp(OcpQp<NX, NU, N, NC, NG>& qp, std::mt19937_64& rng, int horizon, double push = 5.0) {
  qp.horizon = horizon;
  for (int i = 0; i < NX; ++i) qp.x_initial(i) = gaussian(rng);
  Eigen::VectorXd x = qp.x_initial;
  for (int k = 0; k <= horizon; ++k) {
    auto& s = qp.stages[k];
    Eigen::MatrixXd M(NX + NU + 5, NX + NU);
    fill_gaussian(M, rng);
    const Eigen::MatrixXd W = M.transpose() * M / double(NX + NU) + 0.05 * Eigen::MatrixXd::Identity(NX + NU, NX + NU);
    s.Q = W.topLeftCorner(NX, NX);
    s.S = W.bottomLeftCorner(NU, NX);
    s.R = W.bottomRightCorner(NU, NU);
    for (int i = 0; i < NX; ++i) s.q(i) = push * gaussian(rng);
    for (int i = 0; i < NU; ++i) s.r(i) = push * gaussian(rng);
    fill_gaussian(s.A, rng);
    s.A = Eigen::MatrixXd::Identity(NX, NX) + 0.1 * Eigen::MatrixXd(s.A);
    fill_gaussian(s.B, rng);
    s.B *= 0.2;
    for (int i = 0; i < NX; ++i) s.b(i) = 0.1 * gaussian(rng);
    Eigen::VectorXd u(NU);
    for (int i = 0; i < NU; ++i) u(i) = gaussian(rng);
    const bool terminal = k == horizon;
    s.num_eq = terminal ? 0 : (k % (NC + 1));
    fill_gaussian(s.C, rng);
    fill_gaussian(s.D, rng);
    if constexpr (NC > 0) s.e = s.C * x + s.D * u;
    s.num_ineq = NG;
    fill_gaussian(s.Gx, rng);
    fill_gaussian(s.Gu, rng);
    if constexpr (NG > 0) {
      s.h = s.Gx * x + (terminal ? Eigen::VectorXd::Zero(NG) : Eigen::VectorXd(s.Gu * u));
      for (int i = 0; i < NG; ++i) s.h(i) += uniform(rng, 0.1, 1.0);
    }
    if (!terminal) x = s.A * x + s.B * u + s.b;
  }
}

}  // namespace kuavo::qp::test
