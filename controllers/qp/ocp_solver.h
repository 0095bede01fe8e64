// OCP QP solver: Mehrotra predictor-corrector interior point over the Riccati recursion.
//
// Why an interior point (and not OCS2's relaxed-barrier single pass): it returns the exact
// QP solution, so the MPC's answer does not depend on a barrier parameter and can be checked
// against a dense solver; its cost is fixed per iteration (one riccati_factor, two
// riccati_solve, O(T·(NX+NU)²) bookkeeping) and the iteration count is capped, so the
// worst case is max_iterations × that, known in advance. An active-set method on the OCP has
// no such bound (each change of the active set is another factorization, and the count is not
// predictable). For a strict one-pass RTI the caller sets max_iterations = 1 with warm_start:
// that is one Newton step on the barrier problem, which is what a relaxed-barrier RTI does.
//
// Each iteration solves the Newton system as an equality-constrained LQ problem in the step
// (Δx, Δu): same dynamics/equality matrices, right-hand sides = current residuals, cost Hessian
// augmented by Gᵀ(λ/s)G (the standard condensing of slacks and multipliers). Solving for the
// step rather than the new point keeps the right-hand sides small as λ/s grows large near the
// solution (solving for the new point cancels terms of size (λ/s)·h and loses all accuracy).
//
// On the cap: status kMaxIterations, and sol holds the last iterate; sol.residual and
// sol.complementarity say how far it is from optimal (the inequalities hold up to residual).
// kInfeasible is reported when a multiplier exceeds settings.infeasible_multiplier (no
// interior exists); kNumericalError when a later factorization fails from roundoff (extreme
// λ/s), with sol left at the last iterate. Allocation-free.
#pragma once

#include <algorithm>
#include <cmath>

#include "controllers/qp/ocp_qp.h"
#include "controllers/qp/riccati.h"

namespace kuavo::qp {

template <int NX, int NU, int N, int NC, int NG>
struct OcpWorkspace {
  using IneqVector = Eigen::Matrix<double, NG, 1>;
  RiccatiWorkspace<NX, NU, N, NC, NG> riccati;
  RiccatiVectors<NX, NU, N, NC> vec;    // Newton right-hand sides
  OcpSolution<NX, NU, N, NC, NG> step;  // Newton step (x, u) and new multipliers (costate, nu)
  std::array<IneqVector, N + 1> slack{};
  std::array<IneqVector, N + 1> rp{};  // G z + s − h
  std::array<IneqVector, N + 1> target{};
  std::array<IneqVector, N + 1> ds_aff{};
  std::array<IneqVector, N + 1> dl_aff{};
  std::array<IneqVector, N + 1> ds{};
  std::array<IneqVector, N + 1> dl{};
  Eigen::Matrix<double, NX, 1> rx = Eigen::Matrix<double, NX, 1>::Zero();
  Eigen::Matrix<double, NU, 1> ru = Eigen::Matrix<double, NU, 1>::Zero();
  Eigen::Matrix<double, NC, 1> re = Eigen::Matrix<double, NC, 1>::Zero();
  IneqVector g = IneqVector::Zero();
};

namespace ocp_detail {

// Fraction of the distance to the boundary s, λ ≥ 0 an interior step may cover.
inline constexpr double kFractionToBoundary = 0.995;
// Warm start keeps slacks and multipliers at least this far inside (a point on the boundary
// stalls an interior-point method).
inline constexpr double kWarmStartFloor = 1e-3;
// Safety cap on the barrier Hessian weight λᵢ/sᵢ. Near 1e16–1e17 (relative to O(1) costs) the
// cost-to-go loses its small eigenvalues to roundoff and the Cholesky of Quu fails (seen in
// the ill-conditioned tests). The tolerances normally stop the method near 1e10–1e12; past the
// cap the step is an inexact Newton step, which may stall (then: kMaxIterations, not a crash).
inline constexpr double kMaxBarrierWeight = 1e15;

// Fills ws.vec with the Newton right-hand sides at sol (cost gradient, dynamics and equality
// residuals), ws.rp with G z + s − h, and returns the max-norm KKT residual (equalities,
// inequalities with slacks, stationarity).
template <int NX, int NU, int N, int NC, int NG>
double linearize(const OcpQp<NX, NU, N, NC, NG>& qp, OcpWorkspace<NX, NU, N, NC, NG>& ws,
                 const OcpSolution<NX, NU, N, NC, NG>& sol) {
  const int T = qp.horizon;
  auto& v = ws.vec;
  v.x_initial = qp.x_initial - sol.x[0];
  double res = v.x_initial.cwiseAbs().maxCoeff();
  // The products on the vector-pass kernels (riccati_kernels.h): Eigen's general gemv costs
  // its setup at these sizes, and this runs once per interior-point iteration and per MPC call.
  using kernels::gemv_n;
  using kernels::gemv_t;
  using kernels::Update;
  for (int k = 0; k <= T; ++k) {
    const auto& s = qp.stages[k];
    const bool terminal = k == T;
    const double* x = sol.x[k].data();
    const double* u = sol.u[k].data();
    v.q[k] = s.q;
    gemv_n<Update::kAdd>(NX, NX, s.Q.data(), NX, x, v.q[k].data());
    if (!terminal) {
      gemv_t<Update::kAdd>(NU, NX, s.S.data(), NU, u, v.q[k].data());  // + Sᵀu
      v.r[k] = s.r;
      gemv_n<Update::kAdd>(NU, NU, s.R.data(), NU, u, v.r[k].data());
      gemv_n<Update::kAdd>(NU, NX, s.S.data(), NU, x, v.r[k].data());
      v.b[k] = s.b - sol.x[k + 1];
      gemv_n<Update::kAdd>(NX, NX, s.A.data(), NX, x, v.b[k].data());
      gemv_n<Update::kAdd>(NX, NU, s.B.data(), NX, u, v.b[k].data());
      res = std::max(res, v.b[k].cwiseAbs().maxCoeff());
      ws.ru = v.r[k];
      gemv_t<Update::kAdd>(NX, NU, s.B.data(), NX, sol.costate[k + 1].data(), ws.ru.data());
      ws.rx = v.q[k] - sol.costate[k];
      gemv_t<Update::kAdd>(NX, NX, s.A.data(), NX, sol.costate[k + 1].data(), ws.rx.data());
    } else {
      ws.rx = v.q[k] - sol.costate[k];
    }
    if constexpr (NC > 0) {
      const int ne = s.num_eq;
      v.e[k].setZero();
      if (!terminal && ne > 0) {
        auto re = ws.re.head(ne);  // only the used rows (the MPC's capacity is 30, ~12 used)
        re = -s.e.head(ne);
        gemv_n<Update::kAdd>(ne, NX, s.C.data(), NC, x, re.data());
        gemv_n<Update::kAdd>(ne, NU, s.D.data(), NC, u, re.data());
        v.e[k].head(ne) = -re;
        res = std::max(res, re.cwiseAbs().maxCoeff());
        gemv_t<Update::kAdd>(ne, NX, s.C.data(), NC, sol.nu[k].data(), ws.rx.data());
        gemv_t<Update::kAdd>(ne, NU, s.D.data(), NC, sol.nu[k].data(), ws.ru.data());
      }
    }
    if constexpr (NG > 0) {
      const int m = s.num_ineq;
      if (m > 0) {
        ws.rx.noalias() += s.Gx.topRows(m).transpose() * sol.lambda[k].head(m);
        ws.g.noalias() = s.Gx * sol.x[k];
        if (!terminal) {
          ws.ru.noalias() += s.Gu.topRows(m).transpose() * sol.lambda[k].head(m);
          ws.g.noalias() += s.Gu * sol.u[k];
        }
        ws.rp[k].head(m) = ws.g.head(m) + ws.slack[k].head(m) - s.h.head(m);
        res = std::max(res, ws.rp[k].head(m).cwiseAbs().maxCoeff());
      }
    }
    if (k > 0) res = std::max(res, ws.rx.cwiseAbs().maxCoeff());  // x₀ is data: π₀ is free
    if (!terminal) res = std::max(res, ws.ru.cwiseAbs().maxCoeff());
  }
  return res;
}

// ws.ds = −rp − G Δz for the step in ws.step, rows of stage k.
template <int NX, int NU, int N, int NC, int NG>
void slack_step(const OcpQp<NX, NU, N, NC, NG>& qp, OcpWorkspace<NX, NU, N, NC, NG>& ws, int k,
                Eigen::Matrix<double, NG, 1>& ds) {
  const auto& s = qp.stages[k];
  const int m = s.num_ineq;
  ws.g.noalias() = s.Gx * ws.step.x[k];
  if (k < qp.horizon) ws.g.noalias() += s.Gu * ws.step.u[k];
  ds.head(m) = -ws.rp[k].head(m) - ws.g.head(m);
}

// Largest α ≤ 1/τ with v + α dv ≥ 0 for both pairs.
template <int NG, int N>
double max_step(const std::array<Eigen::Matrix<double, NG, 1>, N + 1>& s,
                const std::array<Eigen::Matrix<double, NG, 1>, N + 1>& ds,
                const std::array<Eigen::Matrix<double, NG, 1>, N + 1>& l,
                const std::array<Eigen::Matrix<double, NG, 1>, N + 1>& dl, const int* rows, int T) {
  double alpha = 1.0 / kFractionToBoundary;
  for (int k = 0; k <= T; ++k) {
    for (int i = 0; i < rows[k]; ++i) {
      if (ds[k](i) < 0.0) alpha = std::min(alpha, -s[k](i) / ds[k](i));
      if (dl[k](i) < 0.0) alpha = std::min(alpha, -l[k](i) / dl[k](i));
    }
  }
  return alpha;
}

}  // namespace ocp_detail

template <int NX, int NU, int N, int NC, int NG>
QpStatus solve_ocp_qp(const OcpQp<NX, NU, N, NC, NG>& qp, const OcpSettings& settings,
                      OcpWorkspace<NX, NU, N, NC, NG>& ws, OcpSolution<NX, NU, N, NC, NG>& sol) {
  using namespace ocp_detail;
  const int T = qp.horizon;
  sol.iterations = 0;
  sol.residual = 0.0;
  sol.complementarity = 0.0;
  auto finish = [&sol](QpStatus status) {
    sol.status = status;
    return status;
  };
  if (T < 0 || T > N || !qp.x_initial.allFinite() || qp.stages[T].num_eq != 0) return finish(QpStatus::kBadInput);
  std::array<int, N + 1> rows{};
  int m_total = 0;
  double scale = std::max(1.0, qp.x_initial.cwiseAbs().maxCoeff());
  for (int k = 0; k <= T; ++k) {
    const auto& s = qp.stages[k];
    if (s.num_eq < 0 || s.num_eq > NC || s.num_ineq < 0 || s.num_ineq > NG) return finish(QpStatus::kBadInput);
    rows[k] = s.num_ineq;
    m_total += s.num_ineq;
    scale = std::max({scale, s.q.cwiseAbs().maxCoeff(), s.r.cwiseAbs().maxCoeff(), s.b.cwiseAbs().maxCoeff()});
    if (s.num_eq > 0) scale = std::max(scale, s.e.head(s.num_eq).cwiseAbs().maxCoeff());
    if (s.num_ineq > 0) scale = std::max(scale, s.h.head(s.num_ineq).cwiseAbs().maxCoeff());
  }
  const double residual_tolerance = settings.residual_tolerance * scale;
  const double complementarity_tolerance = settings.complementarity_tolerance * scale;

  if (m_total == 0) {
    // Pure equality-constrained LQ: one factorization and one solve is the exact answer.
    for (int k = 0; k <= T; ++k) {
      ws.riccati.stage[k].w.setZero();
      ws.riccati.stage[k].rho.setZero();
      sol.lambda[k].setZero();
      ws.slack[k].setZero();
    }
    copy_vectors(qp, ws.vec);
    // The residual's stationarity rows need the costates.
    const QpStatus f = riccati_factor_solve(qp, ws.riccati, ws.vec, sol, settings.lq_residual || settings.lq_costate);
    if (f != QpStatus::kSolved) return finish(f);
    // kSolved promises a finite x and u (data with NaN or ∞ get past the factorization's pivot
    // tests); callers need not check again.
    bool finite = true;
    for (int k = 0; k <= T && finite; ++k) finite = sol.x[k].allFinite() && sol.u[k].allFinite();
    if (!finite) return finish(QpStatus::kBadInput);
    if (!settings.lq_residual) {
      sol.residual = -1.0;  // not computed
      return finish(QpStatus::kSolved);
    }
    sol.residual = linearize(qp, ws, sol);
    if (!std::isfinite(sol.residual)) return finish(QpStatus::kBadInput);
    return finish(QpStatus::kSolved);
  }

  for (int k = 0; k <= T; ++k) {
    if (!settings.warm_start) {
      sol.x[k].setZero();
      sol.u[k].setZero();
      sol.costate[k].setZero();
      sol.nu[k].setZero();
      ws.slack[k].setOnes();
      sol.lambda[k].setOnes();
    } else {
      ws.slack[k] = ws.slack[k].cwiseMax(kWarmStartFloor);
      sol.lambda[k] = sol.lambda[k].cwiseMax(kWarmStartFloor);
    }
  }
  sol.x[0] = qp.x_initial;

  for (;;) {
    double mu = 0.0, lambda_max = 0.0;
    for (int k = 0; k <= T; ++k) {
      mu += ws.slack[k].head(rows[k]).dot(sol.lambda[k].head(rows[k]));
      if (rows[k] > 0) lambda_max = std::max(lambda_max, sol.lambda[k].head(rows[k]).maxCoeff());
    }
    mu /= m_total;
    sol.residual = linearize(qp, ws, sol);
    sol.complementarity = mu;
    if (!std::isfinite(sol.residual) || !std::isfinite(mu)) return finish(QpStatus::kBadInput);
    if (sol.residual <= residual_tolerance && mu <= complementarity_tolerance) {
      return finish(QpStatus::kSolved);
    }
    if (lambda_max > settings.infeasible_multiplier) return finish(QpStatus::kInfeasible);
    if (sol.iterations >= settings.max_iterations) return finish(QpStatus::kMaxIterations);
    ++sol.iterations;

    for (int k = 0; k <= T; ++k) {
      auto& w = ws.riccati.stage[k];
      const int m = rows[k];
      w.w.head(m) = sol.lambda[k].head(m).cwiseQuotient(ws.slack[k].head(m)).cwiseMin(kMaxBarrierWeight);
      w.rho.head(m) = w.w.head(m).cwiseProduct(ws.rp[k].head(m));
    }
    const QpStatus f = riccati_factor(qp, ws.riccati);
    // The first factorization sees the data with unit-order weights: a failure there is the
    // problem's. Later, weights λ/s spread over many decades and roundoff can break it.
    if (f != QpStatus::kSolved) return finish(sol.iterations == 1 ? f : QpStatus::kNumericalError);

    // Predictor (affine scaling, σ = 0): ρ = w∘rp.
    riccati_solve(qp, ws.riccati, ws.vec, ws.step);
    for (int k = 0; k <= T; ++k) {
      const int m = rows[k];
      if (m == 0) continue;
      slack_step(qp, ws, k, ws.ds_aff[k]);
      ws.dl_aff[k].head(m) =
          -sol.lambda[k].head(m) - ws.riccati.stage[k].w.head(m).cwiseProduct(ws.ds_aff[k].head(m));
    }
    const double a_aff = std::min(1.0, max_step<NG, N>(ws.slack, ws.ds_aff, sol.lambda, ws.dl_aff, rows.data(), T));
    double mu_aff = 0.0;
    for (int k = 0; k <= T; ++k) {
      const int m = rows[k];
      mu_aff += (ws.slack[k].head(m) + a_aff * ws.ds_aff[k].head(m))
                    .dot(sol.lambda[k].head(m) + a_aff * ws.dl_aff[k].head(m));
    }
    mu_aff /= m_total;
    const double ratio = std::clamp(mu_aff / mu, 0.0, 1.0);
    const double sigma_mu = ratio * ratio * ratio * mu;

    // Corrector: target sᵢλᵢ = σμ − Δs_aff,i·Δλ_aff,i;  ρ = target/s + w∘rp.
    for (int k = 0; k <= T; ++k) {
      auto& w = ws.riccati.stage[k];
      const int m = rows[k];
      if (m == 0) continue;
      ws.target[k].head(m) =
          (sigma_mu - ws.ds_aff[k].head(m).array() * ws.dl_aff[k].head(m).array()).matrix();
      w.rho.head(m) = ws.target[k].head(m).cwiseQuotient(ws.slack[k].head(m)) +
                      w.w.head(m).cwiseProduct(ws.rp[k].head(m));
    }
    riccati_solve(qp, ws.riccati, ws.vec, ws.step);
    for (int k = 0; k <= T; ++k) {
      const int m = rows[k];
      if (m == 0) continue;
      slack_step(qp, ws, k, ws.ds[k]);
      // Δλ = target/s − λ − w∘Δs
      ws.dl[k].head(m) = ws.target[k].head(m).cwiseQuotient(ws.slack[k].head(m)) - sol.lambda[k].head(m) -
                         ws.riccati.stage[k].w.head(m).cwiseProduct(ws.ds[k].head(m));
    }
    const double alpha =
        std::min(1.0, kFractionToBoundary * max_step<NG, N>(ws.slack, ws.ds, sol.lambda, ws.dl, rows.data(), T));
    for (int k = 0; k <= T; ++k) {
      sol.x[k] += alpha * ws.step.x[k];
      sol.u[k] += alpha * ws.step.u[k];
      sol.costate[k] += alpha * (ws.step.costate[k] - sol.costate[k]);
      if constexpr (NC > 0) sol.nu[k] += alpha * (ws.step.nu[k] - sol.nu[k]);
      const int m = rows[k];
      ws.slack[k].head(m) += alpha * ws.ds[k].head(m);
      sol.lambda[k].head(m) += alpha * ws.dl[k].head(m);
    }
  }
}

}  // namespace kuavo::qp
