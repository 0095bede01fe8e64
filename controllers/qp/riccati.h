// Riccati recursion for the OCP of ocp_qp.h with stage-wise state-input equalities, split into
// a matrix pass (riccati_factor, O(T·(NX+NU)³)) and a vector pass (riccati_solve, O(T·(NX+NU)²))
// so the interior-point method can solve twice per factorization.
//
// Per stage, with Pₖ₊₁ the cost-to-go Hessian, the stage block
//   [Quu Qux; Qxu Qxx] = [R S; Sᵀ Q] + [B A]ᵀ Pₖ₊₁ [B A]      (+ Gᵀ W G from the barrier)
// is factored in place: Quu = Lu Luᵀ, X = Qxu Lu⁻ᵀ, so that Qxx − X Xᵀ is the unconstrained
// cost-to-go. An equality D u = e − C x is eliminated in the range space of Quu:
// Y = Lu⁻¹ Dᵀ, M = YᵀY = Lm Lmᵀ, G = C − YᵀXᵀ, and the cost-to-go gains (Lm⁻¹G)ᵀ(Lm⁻¹G).
// This keeps every matrix at its fixed size (no per-stage nullspace basis of varying width),
// and costs only O(NU²·NC) more per constrained stage.
//
// Speed: P[B A] is one product, [B A]ᵀ(P[B A]) one product for only the lower triangle of
// the whole block, the Cholesky and the triangular solve run in place on the block, Qxx − XXᵀ
// is a symmetric rank update — no temporaries, every product noalias.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <algorithm>
#include <cmath>
#include <limits>

#include "controllers/qp/ocp_qp.h"

namespace kuavo::qp {

template <int NX, int NU, int NC, int NG>
struct RiccatiStage {
  static constexpr int NZ = NU + NX;
  // Lower triangle: [Lu ·; X Qxx−XXᵀ]. Only Lu and X are used after the factorization.
  Eigen::Matrix<double, NZ, NZ> block = Eigen::Matrix<double, NZ, NZ>::Zero();
  Eigen::Matrix<double, NX, NX> P = Eigen::Matrix<double, NX, NX>::Zero();  // full, symmetric
  Eigen::Matrix<double, NX, 1> p = Eigen::Matrix<double, NX, 1>::Zero();
  Eigen::Matrix<double, NU, 1> k0 = Eigen::Matrix<double, NU, 1>::Zero();   // Lu⁻¹ qu
  // Equality elimination (rows ≥ num_eq padded: Y, Gmᵀ columns zero, Lm identity).
  Eigen::Matrix<double, NU, NC> Y = Eigen::Matrix<double, NU, NC>::Zero();
  Eigen::LLT<Eigen::Matrix<double, NC, NC>, Eigen::Lower> m_llt;
  Eigen::Matrix<double, NX, NC> GmT = Eigen::Matrix<double, NX, NC>::Zero();  // (Lm⁻¹G)ᵀ
  Eigen::Matrix<double, NC, 1> gm = Eigen::Matrix<double, NC, 1>::Zero();     // Lm⁻¹γ
  // Barrier terms set by the caller: Hessian weight W = diag(w) and linear term Gᵀρ.
  Eigen::Matrix<double, NG, 1> w = Eigen::Matrix<double, NG, 1>::Zero();
  Eigen::Matrix<double, NG, 1> rho = Eigen::Matrix<double, NG, 1>::Zero();
};

// The vector data of an LQ problem with the matrices of an OcpQp: riccati_solve reads these
// instead of the problem's own b, q, r, e, x_initial, so the interior point can solve for a
// Newton step (whose right-hand sides are residuals) with the same factorization.
template <int NX, int NU, int N, int NC>
struct RiccatiVectors {
  std::array<Eigen::Matrix<double, NX, 1>, N + 1> b{};
  std::array<Eigen::Matrix<double, NX, 1>, N + 1> q{};
  std::array<Eigen::Matrix<double, NU, 1>, N + 1> r{};
  std::array<Eigen::Matrix<double, NC, 1>, N + 1> e{};
  Eigen::Matrix<double, NX, 1> x_initial = Eigen::Matrix<double, NX, 1>::Zero();
};

template <int NX, int NU, int N, int NC, int NG>
void copy_vectors(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiVectors<NX, NU, N, NC>& v) {
  for (int k = 0; k <= qp.horizon; ++k) {
    const auto& s = qp.stages[k];
    v.b[k] = s.b;
    v.q[k] = s.q;
    v.r[k] = s.r;
    v.e[k] = s.e;
  }
  v.x_initial = qp.x_initial;
}

template <int NX, int NU, int N, int NC, int NG>
struct RiccatiWorkspace {
  static constexpr int NZ = NU + NX;
  std::array<RiccatiStage<NX, NU, NC, NG>, N + 1> stage{};
  Eigen::Matrix<double, NX, NZ> BA = Eigen::Matrix<double, NX, NZ>::Zero();   // [B A]
  Eigen::Matrix<double, NX, NZ> PBA = Eigen::Matrix<double, NX, NZ>::Zero();  // Pₖ₊₁[B A]
  Eigen::Matrix<double, NG, NU> GuW = Eigen::Matrix<double, NG, NU>::Zero();  // √W Gu
  Eigen::Matrix<double, NG, NX> GxW = Eigen::Matrix<double, NG, NX>::Zero();  // √W Gx
  Eigen::Matrix<double, NC, NC> M = Eigen::Matrix<double, NC, NC>::Zero();
  Eigen::Matrix<double, NX, 1> v = Eigen::Matrix<double, NX, 1>::Zero();
  Eigen::Matrix<double, NU, 1> qu = Eigen::Matrix<double, NU, 1>::Zero();
  Eigen::Matrix<double, NU, 1> t = Eigen::Matrix<double, NU, 1>::Zero();
  Eigen::Matrix<double, NC, 1> gamma = Eigen::Matrix<double, NC, 1>::Zero();
};

namespace riccati_detail {

// Stage equalities whose Cholesky pivots of M = D Quu⁻¹ Dᵀ spread by more than this ratio
// (condition number of M beyond 1e14, about 1/ε) are treated as dependent.
inline constexpr double kRankPivotRatio = 1e-7;

template <int NX, int NU, int NC, int NG>
void add_barrier_hessian(const OcpStage<NX, NU, NC, NG>& s, RiccatiStage<NX, NU, NC, NG>& w,
                         Eigen::Matrix<double, NG, NU>& GuW, Eigen::Matrix<double, NG, NX>& GxW,
                         bool terminal) {
  if constexpr (NG > 0) {
    const int m = s.num_ineq;
    if (m == 0) return;
    for (int i = 0; i < m; ++i) {
      const double sw = std::sqrt(w.w(i));
      GxW.row(i) = sw * s.Gx.row(i);
      if (!terminal) GuW.row(i) = sw * s.Gu.row(i);
    }
    auto Qxx = w.block.template bottomRightCorner<NX, NX>();
    Qxx.template selfadjointView<Eigen::Lower>().rankUpdate(GxW.topRows(m).transpose());
    if (terminal) return;
    w.block.template topLeftCorner<NU, NU>().template selfadjointView<Eigen::Lower>().rankUpdate(
        GuW.topRows(m).transpose());
    w.block.template bottomLeftCorner<NX, NU>().noalias() += GxW.topRows(m).transpose() * GuW.topRows(m);
  }
}

}  // namespace riccati_detail

// Matrix pass over stages T … 0. Reads the barrier weights ws.stage[k].w. Returns kSolved,
// kNotConvex (a Quu, or the terminal P, not positive definite) or kRankDeficient (a Dₖ).
template <int NX, int NU, int N, int NC, int NG>
QpStatus riccati_factor(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws) {
  using riccati_detail::add_barrier_hessian;
  const int T = qp.horizon;
  {
    auto& wT = ws.stage[T];
    wT.block.template bottomRightCorner<NX, NX>() = qp.stages[T].Q;
    add_barrier_hessian(qp.stages[T], wT, ws.GuW, ws.GxW, true);
    wT.P = wT.block.template bottomRightCorner<NX, NX>().template selfadjointView<Eigen::Lower>();
  }
  for (int k = T - 1; k >= 0; --k) {
    const auto& s = qp.stages[k];
    auto& w = ws.stage[k];
    const auto& P_next = ws.stage[k + 1].P;
    auto Quu = w.block.template topLeftCorner<NU, NU>();
    auto X = w.block.template bottomLeftCorner<NX, NU>();  // Qxu, then Qxu Lu⁻ᵀ
    auto Qxx = w.block.template bottomRightCorner<NX, NX>();

    // One product for P[B A] and one lower-triangular product for the whole block
    // [B A]ᵀ(P[B A]): each operand is packed once, not once per sub-block.
    ws.BA.template leftCols<NU>() = s.B;
    ws.BA.template rightCols<NX>() = s.A;
    ws.PBA.noalias() = P_next * ws.BA;
    Quu = s.R;
    X = s.S.transpose();
    Qxx = s.Q;
    w.block.template triangularView<Eigen::Lower>() += ws.BA.transpose() * ws.PBA;
    add_barrier_hessian(s, w, ws.GuW, ws.GxW, false);

    Eigen::LLT<Eigen::Ref<Eigen::Matrix<double, NU, NU>>, Eigen::Lower> llt(Quu);
    if (llt.info() != Eigen::Success) return QpStatus::kNotConvex;
    Quu.template triangularView<Eigen::Lower>().transpose().template solveInPlace<Eigen::OnTheRight>(X);
    Qxx.template selfadjointView<Eigen::Lower>().rankUpdate(X, -1.0);

    if constexpr (NC > 0) {
      const int ne = s.num_eq;
      if (ne > 0) {
        w.Y.setZero();
        w.Y.leftCols(ne) = s.D.topRows(ne).transpose();
        Quu.template triangularView<Eigen::Lower>().solveInPlace(w.Y);
        ws.M.setIdentity();
        ws.M.topLeftCorner(ne, ne).noalias() = w.Y.leftCols(ne).transpose() * w.Y.leftCols(ne);
        w.m_llt.compute(ws.M);
        // Relative pivot test: D rows (nearly) dependent in the Quu⁻¹ metric.
        const auto& Lm = w.m_llt.matrixLLT();
        double min_pivot = std::numeric_limits<double>::infinity(), max_pivot = 0.0;
        for (int i = 0; i < ne; ++i) {
          min_pivot = std::min(min_pivot, std::abs(Lm(i, i)));
          max_pivot = std::max(max_pivot, std::abs(Lm(i, i)));
        }
        if (w.m_llt.info() != Eigen::Success || !(min_pivot > riccati_detail::kRankPivotRatio * max_pivot)) {
          return QpStatus::kRankDeficient;
        }
        w.GmT.setZero();
        w.GmT.leftCols(ne) = s.C.topRows(ne).transpose();
        w.GmT.noalias() -= X * w.Y;
        w.m_llt.matrixU().template solveInPlace<Eigen::OnTheRight>(w.GmT);
        Qxx.template selfadjointView<Eigen::Lower>().rankUpdate(w.GmT);
      } else {
        w.Y.setZero();
        w.GmT.setZero();
      }
    }
    w.P = Qxx.template selfadjointView<Eigen::Lower>();
  }
  return QpStatus::kSolved;
}

// Vector pass and forward rollout: writes x, u, costate, nu of sol for the factorization in ws,
// the vectors vec and the barrier linear terms Gᵀρ (ρ in ws.stage[k].rho).
template <int NX, int NU, int N, int NC, int NG>
void riccati_solve(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                   const RiccatiVectors<NX, NU, N, NC>& vec, OcpSolution<NX, NU, N, NC, NG>& sol) {
  const int T = qp.horizon;
  {
    const auto& s = qp.stages[T];
    auto& w = ws.stage[T];
    w.p = vec.q[T];
    if constexpr (NG > 0) {
      if (s.num_ineq > 0) w.p.noalias() += s.Gx.topRows(s.num_ineq).transpose() * w.rho.head(s.num_ineq);
    }
  }
  for (int k = T - 1; k >= 0; --k) {
    const auto& s = qp.stages[k];
    auto& w = ws.stage[k];
    const auto& next = ws.stage[k + 1];
    const auto Lu = w.block.template topLeftCorner<NU, NU>().template triangularView<Eigen::Lower>();
    const auto X = w.block.template bottomLeftCorner<NX, NU>();
    ws.v = next.p;
    ws.v.noalias() += next.P * vec.b[k];
    ws.qu = vec.r[k];
    ws.qu.noalias() += s.B.transpose() * ws.v;
    w.p = vec.q[k];
    w.p.noalias() += s.A.transpose() * ws.v;
    if constexpr (NG > 0) {
      const int m = s.num_ineq;
      if (m > 0) {
        ws.qu.noalias() += s.Gu.topRows(m).transpose() * w.rho.head(m);
        w.p.noalias() += s.Gx.topRows(m).transpose() * w.rho.head(m);
      }
    }
    w.k0 = ws.qu;
    Lu.solveInPlace(w.k0);
    w.p.noalias() -= X * w.k0;
    if constexpr (NC > 0) {
      if (s.num_eq > 0) {
        ws.gamma.setZero();
        ws.gamma.head(s.num_eq) = -vec.e[k].head(s.num_eq);
        ws.gamma.noalias() -= w.Y.transpose() * w.k0;
        w.gm = ws.gamma;
        w.m_llt.matrixL().solveInPlace(w.gm);
        w.p.noalias() += w.GmT * w.gm;
      }
    }
  }
  sol.x[0] = vec.x_initial;
  for (int k = 0; k < T; ++k) {
    const auto& s = qp.stages[k];
    const auto& w = ws.stage[k];
    const auto Lu = w.block.template topLeftCorner<NU, NU>().template triangularView<Eigen::Lower>();
    const auto X = w.block.template bottomLeftCorner<NX, NU>();
    ws.t = w.k0;
    ws.t.noalias() += X.transpose() * sol.x[k];
    if constexpr (NC > 0) {
      sol.nu[k].setZero();
      if (s.num_eq > 0) {
        sol.nu[k] = w.gm;
        sol.nu[k].noalias() += w.GmT.transpose() * sol.x[k];
        w.m_llt.matrixU().solveInPlace(sol.nu[k]);
        ws.t.noalias() += w.Y * sol.nu[k];
      }
    }
    sol.u[k] = -ws.t;
    Lu.transpose().solveInPlace(sol.u[k]);
    sol.x[k + 1] = vec.b[k];
    sol.x[k + 1].noalias() += s.A * sol.x[k];
    sol.x[k + 1].noalias() += s.B * sol.u[k];
  }
  for (int k = 0; k <= T; ++k) {
    sol.costate[k] = ws.stage[k].p;
    sol.costate[k].noalias() += ws.stage[k].P * sol.x[k];
  }
  if constexpr (NC > 0) sol.nu[T].setZero();
  sol.u[T].setZero();
}

}  // namespace kuavo::qp
