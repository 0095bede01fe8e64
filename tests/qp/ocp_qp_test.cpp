// OCP QP (Riccati + interior point): agreement with the dense solver on the transcribed
// problem, KKT certificates at MPC size, degenerate cases and zero allocation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>

#include "controllers/qp/dense_qp_solver.h"
#include "controllers/qp/ocp_solver.h"
#include "tests/qp/ocp_qp_fixtures.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::qp::test {
namespace {

template <int NX, int NU, int N, int NC, int NG>
struct OcpFixture {
  OcpQp<NX, NU, N, NC, NG> qp;
  OcpWorkspace<NX, NU, N, NC, NG> ws;
  OcpSolution<NX, NU, N, NC, NG> sol;
};

// Solves the transcription of f.qp (horizon T) with the dense solver and compares trajectories.
template <int NX, int NU, int N, int NC, int NG, int T>
void expect_matches_dense(const OcpFixture<NX, NU, N, NC, NG>& f, double tol) {
  constexpr int kNv = T * (NX + NU), kNe = T * (NX + NC), kNi = (T + 1) * NG;
  auto dense = std::make_unique<DenseQp<kNv, kNe, kNi>>();
  auto ws = std::make_unique<DenseQpWorkspace<kNv, kNe, kNi>>();
  auto sol = std::make_unique<DenseQpSolution<kNv, kNe, kNi>>();
  const DenseTranscription d = transcribe(f.qp);
  dense->H = d.H;
  dense->g = d.g;
  dense->A = d.Aeq;
  dense->b = d.beq;
  dense->C = d.G;
  dense->c_upper = d.h;
  ASSERT_EQ(solve_dense_qp(*dense, DenseQpSettings{}, *ws, *sol), QpStatus::kSolved);
  Eigen::VectorXd z, y, lam;
  pack(f.qp, f.sol, z, y, lam);
  EXPECT_LE((z - Eigen::VectorXd(sol->x)).cwiseAbs().maxCoeff(), tol * (1.0 + z.cwiseAbs().maxCoeff()));
  if (lam.size() > 0) {
    EXPECT_LE((lam - Eigen::VectorXd(sol->z_ineq)).cwiseAbs().maxCoeff(), 1e3 * tol * (1.0 + lam.cwiseAbs().maxCoeff()));
  }
}

// Residuals to tol; complementarity is an interior-point's approximate quantity: the solver
// stops at mean sᵢλᵢ ≤ 1e-10·(data scale), so one row may carry up to (rows)·that.
template <int NX, int NU, int N, int NC, int NG>
void expect_kkt(const OcpQp<NX, NU, N, NC, NG>& qp, const OcpKkt& k, double tol) {
  double scale = 1.0;
  for (int j = 0; j <= qp.horizon; ++j) {
    const auto& s = qp.stages[j];
    scale = std::max({scale, s.q.cwiseAbs().maxCoeff(), s.r.cwiseAbs().maxCoeff(), s.b.cwiseAbs().maxCoeff()});
    if constexpr (NG > 0) scale = std::max(scale, s.h.cwiseAbs().maxCoeff());
  }
  EXPECT_LE(k.equality, tol);
  EXPECT_LE(k.inequality, tol);
  EXPECT_LE(k.stationarity, tol);
  EXPECT_LE(k.dual_sign, 0.0);
  EXPECT_LE(k.complementarity, 1e-10 * scale * (qp.horizon + 1) * NG + 1e-12);
}

TEST(OcpQp, EqualityOnlyMatchesDenseExactly) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 0>>();
  std::mt19937_64 rng(21);
  for (int n = 0; n < 30; ++n) {
    make_random_ocp(f->qp, rng, 5);
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    EXPECT_EQ(f->sol.iterations, 0);
    expect_kkt(f->qp, ocp_kkt(f->qp, f->sol), 1e-10);
    expect_matches_dense<4, 3, 5, 2, 0, 5>(*f, 1e-10);
  }
}

// lq_residual = false (the MPC's setting): the same solution bit for bit, the residual
// reported as not computed, and a non-finite result still refused. With lq_costate = false
// too (also the MPC's): x, u and ν still bit for bit, the costates not written.
TEST(OcpQp, EqualityOnlyWithoutResidualIsTheSameSolution) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 0>>();
  auto g = std::make_unique<OcpFixture<4, 3, 5, 2, 0>>();
  auto h = std::make_unique<OcpFixture<4, 3, 5, 2, 0>>();
  std::mt19937_64 rng(23);
  OcpSettings fast;
  fast.lq_residual = false;
  OcpSettings fastest = fast;
  fastest.lq_costate = false;
  for (int n = 0; n < 10; ++n) {
    make_random_ocp(f->qp, rng, 5);
    g->qp = f->qp;
    h->qp = f->qp;
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    ASSERT_EQ(solve_ocp_qp(g->qp, fast, g->ws, g->sol), QpStatus::kSolved);
    for (auto& c : h->sol.costate) c.setConstant(7.0);
    ASSERT_EQ(solve_ocp_qp(h->qp, fastest, h->ws, h->sol), QpStatus::kSolved);
    EXPECT_GE(f->sol.residual, 0.0);
    EXPECT_EQ(g->sol.residual, -1.0);
    EXPECT_EQ(h->sol.residual, -1.0);
    for (int k = 0; k <= 5; ++k) {
      EXPECT_EQ(f->sol.x[k], g->sol.x[k]);
      EXPECT_EQ(f->sol.u[k], g->sol.u[k]);
      EXPECT_EQ(f->sol.x[k], h->sol.x[k]);
      EXPECT_EQ(f->sol.u[k], h->sol.u[k]);
      EXPECT_EQ(f->sol.nu[k], h->sol.nu[k]);
      EXPECT_EQ(h->sol.costate[k], Eigen::Vector4d::Constant(7.0));
    }
    expect_kkt(g->qp, ocp_kkt(g->qp, g->sol), 1e-10);
  }
  g->qp.stages[2].b(1) = std::numeric_limits<double>::quiet_NaN();  // reaches x₃ … x₅ only
  EXPECT_EQ(solve_ocp_qp(g->qp, fast, g->ws, g->sol), QpStatus::kBadInput);
}

TEST(OcpQp, WithInequalitiesMatchesDense) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 3>>();
  std::mt19937_64 rng(22);
  int active = 0;
  for (int n = 0; n < 30; ++n) {
    make_random_ocp(f->qp, rng, 5);
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    expect_kkt(f->qp, ocp_kkt(f->qp, f->sol), 1e-8);
    expect_matches_dense<4, 3, 5, 2, 3, 5>(*f, 1e-7);
    for (int k = 0; k <= 5; ++k) active += (f->sol.lambda[k].array() > 1e-6).count();
  }
  EXPECT_GT(active, 30 * 3);  // the inequalities matter
}

TEST(OcpQp, ShorterHorizonThanCapacityMatchesDense) {
  auto f = std::make_unique<OcpFixture<4, 3, 8, 2, 3>>();
  std::mt19937_64 rng(23);
  for (int n = 0; n < 10; ++n) {
    make_random_ocp(f->qp, rng, 3);
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    expect_matches_dense<4, 3, 8, 2, 3, 3>(*f, 1e-7);
  }
}

// A workspace that solved a longer horizon keeps that horizon's factors in the later stages
// (the MPC changes its horizon between calls): the new terminal stage must ignore them, so the
// answer is the one a fresh workspace gives, bit for bit.
template <int NG>
void check_shorter_horizon_after_longer(std::mt19937_64& rng) {
  auto reused = std::make_unique<OcpFixture<4, 3, 8, 2, NG>>();
  auto fresh = std::make_unique<OcpFixture<4, 3, 8, 2, NG>>();
  make_random_ocp(reused->qp, rng, 8);
  ASSERT_EQ(solve_ocp_qp(reused->qp, OcpSettings{}, reused->ws, reused->sol), QpStatus::kSolved);
  make_random_ocp(reused->qp, rng, 3);
  fresh->qp = reused->qp;
  ASSERT_EQ(solve_ocp_qp(reused->qp, OcpSettings{}, reused->ws, reused->sol), QpStatus::kSolved);
  ASSERT_EQ(solve_ocp_qp(fresh->qp, OcpSettings{}, fresh->ws, fresh->sol), QpStatus::kSolved);
  for (int k = 0; k <= 3; ++k) {
    EXPECT_EQ(reused->sol.x[k], fresh->sol.x[k]) << k;
    EXPECT_EQ(reused->sol.u[k], fresh->sol.u[k]) << k;
    EXPECT_EQ(reused->sol.costate[k], fresh->sol.costate[k]) << k;
  }
}

TEST(OcpQp, ShorterHorizonAfterALongerOneMatchesAFreshWorkspace) {
  std::mt19937_64 rng(24);
  for (int n = 0; n < 3; ++n) {
    check_shorter_horizon_after_longer<0>(rng);
    check_shorter_horizon_after_longer<3>(rng);
  }
}

// [B A] with columns that are zero below some row (the MPC's force columns reach only the
// momentum rows): the square-root products skip those zeros (riccati.h, extents). Extents
// differ between and inside 4-row groups, one group of B is all zero, and some A columns end
// mid-group, so every branch of the skipping is exercised; the dense solver is the oracle.
TEST(OcpQp, DynamicsWithZeroTailsMatchDense) {
  constexpr int kNx = 12, kNu = 12, kN = 5;
  auto f = std::make_unique<OcpFixture<kNx, kNu, kN, 3, 0>>();
  std::mt19937_64 rng(31);
  const int b_rows[kNu] = {3, 3, 2, 3, 9, 12, 7, 0, 0, 0, 0, 0};
  for (int n = 0; n < 20; ++n) {
    make_random_ocp(f->qp, rng, kN);
    for (int k = 0; k < kN; ++k) {
      auto& s = f->qp.stages[k];
      for (int j = 0; j < kNu; ++j) s.B.col(j).tail(kNx - b_rows[j]).setZero();
      for (int j = 0; j < kNx; ++j) {
        const int rows = std::min(kNx, (j + 2 + n + k) % (kNx + 1));
        s.A.col(j).tail(kNx - rows).setZero();
      }
    }
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    expect_kkt(f->qp, ocp_kkt(f->qp, f->sol), 1e-10);
    expect_matches_dense<kNx, kNu, kN, 3, 0, kN>(*f, 1e-10);
  }
}

TEST(OcpQp, MpcSizeRandomProblemsSatisfyKkt) {
  auto f = std::make_unique<OcpFixture<38, 50, 12, 12, 20>>();
  std::mt19937_64 rng(24);
  for (int n = 0; n < 3; ++n) {
    make_random_ocp(f->qp, rng, 12);
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    expect_kkt(f->qp, ocp_kkt(f->qp, f->sol), 1e-8);
  }
}

TEST(OcpQp, EmptyHorizonReturnsInitialState) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 3>>();
  std::mt19937_64 rng(25);
  make_random_ocp(f->qp, rng, 0);
  ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved);
  EXPECT_EQ(f->sol.x[0], f->qp.x_initial);
  // A terminal state constraint the fixed x₀ violates: infeasible, finite output.
  f->qp.stages[0].h(0) = f->qp.stages[0].Gx.row(0).dot(f->qp.x_initial) - 1.0;
  const QpStatus s = solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol);
  EXPECT_TRUE(s == QpStatus::kInfeasible || s == QpStatus::kMaxIterations) << to_string(s);
  EXPECT_TRUE(f->sol.x[0].allFinite());
}

TEST(OcpQp, InfeasibleInequalitiesAreReported) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 3>>();
  std::mt19937_64 rng(26);
  make_random_ocp(f->qp, rng, 5);
  auto& s = f->qp.stages[2];
  s.Gx.row(1) = -s.Gx.row(0);
  s.Gu.row(1) = -s.Gu.row(0);
  s.h(0) = -1.0;
  s.h(1) = -1.0;  // g ≤ −1 and −g ≤ −1
  const QpStatus st = solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol);
  EXPECT_TRUE(st == QpStatus::kInfeasible || st == QpStatus::kMaxIterations) << to_string(st);
  for (int k = 0; k <= 5; ++k) EXPECT_TRUE(f->sol.x[k].allFinite() && f->sol.lambda[k].allFinite());
}

TEST(OcpQp, DependentStageEqualitiesAreReported) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 0>>();
  std::mt19937_64 rng(27);
  make_random_ocp(f->qp, rng, 5);
  auto& s = f->qp.stages[2];
  s.num_eq = 2;
  s.D.row(1) = 3.0 * s.D.row(0);
  s.C.row(1) = 3.0 * s.C.row(0);
  s.e(1) = 3.0 * s.e(0);
  EXPECT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kRankDeficient);
  f->qp.stages[5].num_eq = 1;  // terminal equalities are not supported
  EXPECT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kBadInput);
}

TEST(OcpQp, IllConditionedCostMatchesDense) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 3>>();
  std::mt19937_64 rng(28);
  for (int n = 0; n < 10; ++n) {
    make_random_ocp(f->qp, rng, 5);
    // State weights 1e-4, one input weight 1e4 (scaling [Q Sᵀ; S R] by diag(1e-2, 1) keeps it PSD).
    for (int k = 0; k <= 5; ++k) {
      f->qp.stages[k].Q *= 1e-4;
      f->qp.stages[k].S *= 1e-2;
      f->qp.stages[k].R(0, 0) += 1e4;
    }
    // λ/s spans ~20 decades at 1e-10 complementarity here, past what the factorization
    // resolves; the documented remedy is a looser complementarity tolerance.
    OcpSettings settings;
    settings.complementarity_tolerance = 1e-8;
    ASSERT_EQ(solve_ocp_qp(f->qp, settings, f->ws, f->sol), QpStatus::kSolved) << n << " " << f->sol.iterations;
    expect_matches_dense<4, 3, 5, 2, 3, 5>(*f, 1e-6);
  }
}

// No state cost: the cost-to-go Pₖ is singular (P_T = 0 exactly, the others of low rank), so
// the square-root product is refused and the general product [B A]ᵀPₖ₊₁[B A] is used. The
// dense solver needs a definite Hessian, so the oracle is the KKT certificate (sufficient for
// a convex QP).
TEST(OcpQp, SemidefiniteCostToGoSatisfiesKkt) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 3>>();
  std::mt19937_64 rng(32);
  for (int n = 0; n < 10; ++n) {
    make_random_ocp(f->qp, rng, 5);
    for (int k = 0; k <= 5; ++k) {
      f->qp.stages[k].Q.setZero();
      f->qp.stages[k].S.setZero();
    }
    if (n % 2 == 1) f->qp.stages[5].Q(0, 0) = 1.0;  // rank one terminal cost
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    expect_kkt(f->qp, ocp_kkt(f->qp, f->sol), 1e-8);
    // Equality-only: one factorization, exact.
    auto g = std::make_unique<OcpFixture<4, 3, 5, 2, 0>>();
    make_random_ocp(g->qp, rng, 5);
    for (int k = 0; k <= 5; ++k) {
      g->qp.stages[k].Q.setZero();
      g->qp.stages[k].S.setZero();
    }
    ASSERT_EQ(solve_ocp_qp(g->qp, OcpSettings{}, g->ws, g->sol), QpStatus::kSolved);
    EXPECT_FALSE(g->ws.riccati.stage[5].p_factored);  // P_T = 0: stage T−1 takes the general path
    expect_kkt(g->qp, ocp_kkt(g->qp, g->sol), 1e-10);
  }
}

// riccati_factor_solve (the backward vector recursion inside the matrix pass) against
// riccati_factor then riccati_solve: the same arithmetic, so bit for bit, with equalities,
// barrier weights and linear terms, semidefinite cost-to-go (the general product path) and a
// horizon shorter than the capacity after a longer one.
TEST(OcpQp, FusedFactorSolveIsTheSeparatePassesBitForBit) {
  using Fixture = OcpFixture<38, 50, 12, 30, 20>;
  auto f = std::make_unique<Fixture>();
  auto g = std::make_unique<Fixture>();
  std::mt19937_64 rng(41);
  for (int n = 0; n < 6; ++n) {
    const int T = n == 5 ? 7 : 12;
    make_random_ocp(f->qp, rng, T);
    if (n >= 3) {  // no state cost: P_T = 0, the previous stages' Pₖ of low rank
      for (int k = 0; k <= T; ++k) {
        f->qp.stages[k].Q.setZero();
        f->qp.stages[k].S.setZero();
      }
    }
    for (int k = 0; k <= T; ++k) {
      for (int i = 0; i < 20; ++i) {
        f->ws.riccati.stage[k].w(i) = uniform(rng, 0.0, 10.0);
        f->ws.riccati.stage[k].rho(i) = gaussian(rng);
      }
      g->ws.riccati.stage[k].w = f->ws.riccati.stage[k].w;
      g->ws.riccati.stage[k].rho = f->ws.riccati.stage[k].rho;
    }
    copy_vectors(f->qp, f->ws.vec);
    copy_vectors(f->qp, g->ws.vec);
    ASSERT_EQ(riccati_factor(f->qp, f->ws.riccati), QpStatus::kSolved) << n;
    riccati_solve(f->qp, f->ws.riccati, f->ws.vec, f->sol);
    ASSERT_EQ(riccati_factor_solve(f->qp, g->ws.riccati, g->ws.vec, g->sol), QpStatus::kSolved) << n;
    int factored = 0;
    for (int k = 0; k <= T; ++k) {
      EXPECT_EQ(f->sol.x[k], g->sol.x[k]) << n << " " << k;
      EXPECT_EQ(f->sol.u[k], g->sol.u[k]) << n << " " << k;
      EXPECT_EQ(f->sol.costate[k], g->sol.costate[k]) << n << " " << k;
      EXPECT_EQ(f->sol.nu[k], g->sol.nu[k]) << n << " " << k;
      factored += g->ws.riccati.stage[k].p_factored ? 1 : 0;
    }
    if (n >= 3) {
      EXPECT_LT(factored, T + 1);  // the general product path was taken
    }
    EXPECT_GT(f->sol.u[0].cwiseAbs().maxCoeff(), 0.0);
  }
}

// f and g (the same stages, g with NaN where the solver is promised zeros) solved fused and g
// again in separate passes: the same x, u, costates and multipliers, bit for bit.
template <class Fixture>
void expect_same_solution_bit_for_bit(Fixture& f, Fixture& g, int T, int n) {
  copy_vectors(f.qp, f.ws.vec);
  copy_vectors(g.qp, g.ws.vec);
  ASSERT_EQ(riccati_factor_solve(f.qp, f.ws.riccati, f.ws.vec, f.sol), QpStatus::kSolved) << n;
  ASSERT_EQ(riccati_factor_solve(g.qp, g.ws.riccati, g.ws.vec, g.sol), QpStatus::kSolved) << n;
  for (int k = 0; k <= T; ++k) {
    EXPECT_EQ(f.sol.x[k], g.sol.x[k]) << n << " " << k;
    EXPECT_EQ(f.sol.u[k], g.sol.u[k]) << n << " " << k;
    EXPECT_EQ(f.sol.costate[k], g.sol.costate[k]) << n << " " << k;
    EXPECT_EQ(f.sol.nu[k], g.sol.nu[k]) << n << " " << k;
  }
  EXPECT_GT(f.sol.u[0].cwiseAbs().maxCoeff(), 0.0);
  ASSERT_EQ(riccati_factor(g.qp, g.ws.riccati), QpStatus::kSolved) << n;
  riccati_solve(g.qp, g.ws.riccati, g.ws.vec, g.sol);
  for (int k = 0; k <= T; ++k) EXPECT_EQ(f.sol.u[k], g.sol.u[k]) << n << " " << k;
}

// OcpStage::s_zero and r_dense: the Riccati recursion does not read S, nor R outside its
// leading block and diagonal (NaN there must not reach the result), and returns bit for bit
// the solution of the same stages with those zeros read, on the extents path (B with zero
// tails), the dense one, and a semidefinite cost-to-go (no Q).
TEST(OcpQp, StageCostStructureIsNotReadAndGivesTheSameSolutionBitForBit) {
  constexpr int kDense = 22;  // not a multiple of 4: a column strip straddles it
  using Fixture = OcpFixture<38, 50, 12, 12, 0>;
  auto f = std::make_unique<Fixture>();
  auto g = std::make_unique<Fixture>();
  std::mt19937_64 rng(43);
  for (int n = 0; n < 6; ++n) {
    const int T = 12;
    make_random_ocp(f->qp, rng, T);
    for (int k = 0; k <= T; ++k) {
      auto& s = f->qp.stages[k];
      s.S.setZero();
      const Eigen::Matrix<double, 50, 1> diagonal = s.R.diagonal();
      s.R.bottomRows(50 - kDense).setZero();
      s.R.rightCols(50 - kDense).setZero();
      s.R.diagonal() = diagonal;
      if (n % 2 == 0) s.B.bottomRows(30).leftCols(24).setZero();  // force-like columns: extents
      if (n >= 4) s.Q.setZero();  // P_T = 0: the general product path
    }
    g->qp = f->qp;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (int k = 0; k <= T; ++k) {
      auto& s = g->qp.stages[k];
      s.S.setConstant(nan);
      s.s_zero = true;
      for (int j = 0; j < 50; ++j) {
        for (int i = 0; i < 50; ++i) {
          if ((i >= kDense || j >= kDense) && i / 4 != j / 4) s.R(i, j) = nan;  // but 4×4 diagonal blocks
        }
      }
      s.r_dense = kDense;
    }
    expect_same_solution_bit_for_bit(*f, *g, T, n);
  }
}

// OcpQp::ab_groups_declared: the matrix pass reads only the declared row groups of A and B
// (NaN in the undeclared groups of a column step must not reach the result), and the solution
// is bit for bit the undeclared one, at MPC-like structure (A the identity but in a few rows,
// short force columns), on the extents and the general (semidefinite cost-to-go) paths, fused
// and in separate passes.
TEST(OcpQp, DeclaredDynamicsRowGroupsGiveTheSameSolutionBitForBit) {
  constexpr int kNx = 38, kNu = 50, kN = 12;
  using Fixture = OcpFixture<kNx, kNu, kN, 12, 0>;
  auto f = std::make_unique<Fixture>();
  auto g = std::make_unique<Fixture>();
  std::mt19937_64 rng(47);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto a_groups = [](int j) { return static_cast<std::uint16_t>(0b111 | 1u << (j / 4)); };
  auto b_groups = [](int j) { return static_cast<std::uint16_t>(j < 24 ? 0b11 : 0b111 | 1u << ((12 + j - 24) / 4)); };
  for (int n = 0; n < 4; ++n) {
    const int T = kN;
    make_random_ocp(f->qp, rng, T);
    for (int k = 0; k <= T; ++k) {
      auto& s = f->qp.stages[k];
      for (int j = 0; j < kNx; ++j) {
        for (int i = 0; i < kNx; ++i) {
          if ((a_groups(j) >> (i / 4) & 1u) == 0) s.A(i, j) = 0.0;
          if (i >= 12 && i != j) s.A(i, j) = 0.0;  // joint rows: the identity (inside declared groups too)
        }
        if (j >= 12) s.A(j, j) = 1.0;
      }
      for (int j = 0; j < kNu; ++j) {
        for (int i = 0; i < kNx; ++i) {
          if ((b_groups(j) >> (i / 4) & 1u) == 0 || (j < 24 && i >= 6)) s.B(i, j) = 0.0;
          if (j >= 24 && i >= 12 && i != 12 + j - 24) s.B(i, j) = 0.0;
        }
      }
      if (n >= 2) {  // P_T = 0: the general product path
        s.Q.setZero();
        s.S.setZero();
      }
    }
    g->qp = f->qp;
    g->qp.ab_groups_declared = true;
    for (int j = 0; j < kNx; ++j) g->qp.a_groups[j] = a_groups(j);
    for (int j = 0; j < kNu; ++j) g->qp.b_groups[j] = b_groups(j);
    // Poison what no 4-column step declares: a column's rows outside the groups its step reads.
    const auto poison = [&](auto& M, int cols, const auto& groups) {
      for (int j = 0; j < cols; ++j) {
        const int step = j / 4 * 4;
        unsigned read = groups(j);
        if (step + 4 <= cols) read = groups(step) | groups(step + 1) | groups(step + 2) | groups(step + 3);
        for (int i = 0; i < kNx; ++i) {
          if ((read >> (i / 4) & 1u) == 0) M(i, j) = nan;
        }
      }
    };
    for (int k = 0; k < T; ++k) {
      poison(g->qp.stages[k].A, kNx, a_groups);
      poison(g->qp.stages[k].B, kNu, b_groups);
    }
    expect_same_solution_bit_for_bit(*f, *g, T, n);
  }
}

// PrefetchPlan's bookkeeping against hand-counted cache lines: a range's lines (partial lines
// at both ends count whole), ranges that touch merge, a different kind does not, and a range
// beyond the capacity is counted as dropped; issue() walks the plan in slices.
TEST(OcpQp, PrefetchPlanCountsWholeLinesAndMergesNeighbours) {
  alignas(64) static double buffer[64]{};  // 8 lines
  PrefetchPlan<2> plan;
  plan.add(buffer + 1, 2 * sizeof(double), false);  // inside line 0
  EXPECT_EQ(plan.lines(), 1);
  plan.add(buffer + 7, 2 * sizeof(double), false);  // lines 0–1: extends the range
  EXPECT_EQ(plan.lines(), 2);
  EXPECT_EQ(plan.ranges(), 1);
  plan.add(buffer + 16, 8 * sizeof(double), false);  // line 2, right after: merges
  EXPECT_EQ(plan.lines(), 3);
  EXPECT_EQ(plan.ranges(), 1);
  plan.add(buffer + 24, sizeof(double), true);  // line 3, written: a new range
  EXPECT_EQ(plan.ranges(), 2);
  plan.add(buffer + 48, sizeof(double), false);  // line 6: past the capacity
  EXPECT_EQ(plan.dropped(), 1);
  EXPECT_EQ(plan.lines(), 4);
  EXPECT_TRUE(plan.covers(buffer + 23));
  EXPECT_TRUE(plan.covers(buffer + 31));
  EXPECT_FALSE(plan.covers(buffer + 32));
  EXPECT_FALSE(plan.covers(buffer + 48));
  plan.issue(3);
  plan.issue(3);  // past the end: nothing more
  plan.finish();
  plan.clear();
  EXPECT_EQ(plan.lines(), 0);
  EXPECT_EQ(plan.dropped(), 0);
  EXPECT_FALSE(plan.covers(buffer));
}

// The matrix pass prefetches stage k − 1's lines while it factors stage k (prefetch.h). The
// plan must name what that stage's pass touches, or the prefetch is wasted: at MPC structure
// (declared row groups of A and B, s_zero, r_dense, equalities on some stages), every entry of
// a stage's R, S, Q, A, B, C, D and factor storage outside its plan's lines is set to NaN, and
// the fused factor-solve returns bit for bit the unpoisoned solution (nothing outside was read)
// and leaves the poisoned storage NaN (nothing outside was written). The plan fits its
// capacity and is not the whole stage (the known zeros stay unfetched).
TEST(OcpQp, PrefetchPlanCoversWhatTheMatrixPassTouches) {
  constexpr int kNx = 38, kNu = 50, kN = 12, kNc = 12, kDense = 24;
  using Fixture = OcpFixture<kNx, kNu, kN, kNc, 0>;
  auto f = std::make_unique<Fixture>();
  auto g = std::make_unique<Fixture>();
  std::mt19937_64 rng(53);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Columns of one 4-column step declare different groups (the first one also rows 36–39):
  // the transpose reads the step's union.
  auto a_groups = [](int j) { return static_cast<std::uint16_t>(0b111 | 1u << (j / 4) | (j % 4 == 0 ? 1u << 9 : 0u)); };
  auto b_groups = [](int j) { return static_cast<std::uint16_t>(j < 24 ? 0b11 : 0b111 | 1u << ((12 + j - 24) / 4)); };
  const int T = kN;
  make_random_ocp(f->qp, rng, T);
  f->qp.ab_groups_declared = true;
  for (int j = 0; j < kNx; ++j) f->qp.a_groups[j] = a_groups(j);
  for (int j = 0; j < kNu; ++j) f->qp.b_groups[j] = b_groups(j);
  for (int k = 0; k <= T; ++k) {
    auto& s = f->qp.stages[k];
    for (int j = 0; j < kNx; ++j) {
      for (int i = 0; i < kNx; ++i) {
        if ((a_groups(j) >> (i / 4) & 1u) == 0 || (i >= 12 && i != j)) s.A(i, j) = 0.0;
      }
      if (j >= 12) s.A(j, j) = 1.0;
    }
    for (int j = 0; j < kNu; ++j) {
      for (int i = 0; i < kNx; ++i) {
        if ((b_groups(j) >> (i / 4) & 1u) == 0 || (j < 24 && i >= 6) || (j >= 24 && i >= 12 && i != 12 + j - 24)) {
          s.B(i, j) = 0.0;
        }
      }
    }
    s.S.setZero();
    s.s_zero = true;
    const Eigen::Matrix<double, kNu, 1> diagonal = s.R.diagonal();
    s.R.bottomRows(kNu - kDense).setZero();
    s.R.rightCols(kNu - kDense).setZero();
    s.R.diagonal() = diagonal;
    s.r_dense = kDense;
  }
  g->qp = f->qp;
  copy_vectors(f->qp, f->ws.vec);
  copy_vectors(g->qp, g->ws.vec);
  ASSERT_EQ(riccati_factor_solve(f->qp, f->ws.riccati, f->ws.vec, f->sol), QpStatus::kSolved);

  auto& rw = g->ws.riccati;
  constexpr int kLd = RiccatiLayout<kNx, kNu, kNc>::kLd;
  int stage_lines = 0, planned_lines = 0, with_equalities = 0;
  const auto poison = [&](auto& M, const auto& plan) {
    for (int i = 0; i < M.size(); ++i) {
      if (!plan.covers(M.data() + i)) M.data()[i] = nan;
    }
  };
  for (int k = 0; k < T; ++k) {
    riccati_detail::plan_factor_prefetch(g->qp, rw, &g->ws.vec, k);
    const auto& plan = rw.prefetch;
    ASSERT_EQ(plan.dropped(), 0) << k;
    auto& s = g->qp.stages[k];
    with_equalities += s.num_eq > 0 ? 1 : 0;
    poison(s.R, plan);
    poison(s.S, plan);
    poison(s.Q, plan);
    poison(s.A, plan);
    poison(s.B, plan);
    poison(s.C, plan);
    poison(s.D, plan);
    auto& L = rw.stage[k].L;
    for (double& l : L) {
      if (!plan.covers(&l)) l = nan;
    }
    stage_lines += static_cast<int>((sizeof(L) + sizeof(s.R) + sizeof(s.S) + sizeof(s.Q) + sizeof(s.A) + sizeof(s.B) +
                                     sizeof(s.C) + sizeof(s.D)) / kCacheLine);
    planned_lines += plan.lines();
  }
  ASSERT_GT(with_equalities, 0);
  ASSERT_LT(with_equalities, T);
  // The poison must be somewhere the pass could have read: the known zeros and upper triangles.
  EXPECT_LT(planned_lines, stage_lines * 2 / 3);
  ASSERT_EQ(riccati_factor_solve(g->qp, rw, g->ws.vec, g->sol), QpStatus::kSolved);
  for (int k = 0; k <= T; ++k) {
    EXPECT_EQ(f->sol.x[k], g->sol.x[k]) << k;
    EXPECT_EQ(f->sol.u[k], g->sol.u[k]) << k;
    EXPECT_EQ(f->sol.nu[k], g->sol.nu[k]) << k;
  }
  EXPECT_GT(f->sol.u[0].cwiseAbs().maxCoeff(), 0.0);
  for (int k = 0; k < T; ++k) {
    riccati_detail::plan_factor_prefetch(g->qp, rw, &g->ws.vec, k);
    int unwritten = 0;
    for (int i = 0; i < kLd * kLd; ++i) {
      const double* l = rw.stage[k].L.data() + i;
      if (!rw.prefetch.covers(l)) {
        EXPECT_TRUE(std::isnan(*l)) << "stage " << k << " entry " << i << " written outside the plan";
        ++unwritten;
      }
    }
    EXPECT_GT(unwritten, kLd * kLd / 4) << k;  // the upper triangle is left out
  }
}

TEST(OcpQp, IterationCapIsHonoured) {
  auto f = std::make_unique<OcpFixture<4, 3, 5, 2, 3>>();
  std::mt19937_64 rng(29);
  make_random_ocp(f->qp, rng, 5);
  OcpSettings capped;
  capped.max_iterations = 2;
  EXPECT_EQ(solve_ocp_qp(f->qp, capped, f->ws, f->sol), QpStatus::kMaxIterations);
  EXPECT_EQ(f->sol.iterations, 2);
  EXPECT_GT(f->sol.residual + f->sol.complementarity, 0.0);
  for (int k = 0; k <= 5; ++k) EXPECT_TRUE(f->sol.x[k].allFinite());
}

// The MPC re-solves a slightly changed problem every tick, starting from the last solution.
TEST(OcpQp, WarmStartReachesSameSolutionInFewerIterations) {
  auto f = std::make_unique<OcpFixture<38, 50, 12, 12, 20>>();
  auto cold = std::make_unique<OcpFixture<38, 50, 12, 12, 20>>();
  std::mt19937_64 rng(31);
  int cold_iterations = 0, warm_iterations = 0;
  for (int n = 0; n < 4; ++n) {
    make_random_ocp(f->qp, rng, 12);
    ASSERT_EQ(solve_ocp_qp(f->qp, OcpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    for (int k = 0; k <= 12; ++k) f->qp.stages[k].q *= 1.01;
    cold->qp = f->qp;
    ASSERT_EQ(solve_ocp_qp(cold->qp, OcpSettings{}, cold->ws, cold->sol), QpStatus::kSolved);
    OcpSettings warm;
    warm.warm_start = true;
    ASSERT_EQ(solve_ocp_qp(f->qp, warm, f->ws, f->sol), QpStatus::kSolved);
    expect_kkt(f->qp, ocp_kkt(f->qp, f->sol), 1e-8);
    // Both stop at the interior-point tolerance, so they agree to about √(complementarity).
    for (int k = 0; k < 12; ++k) {
      EXPECT_LE((f->sol.u[k] - cold->sol.u[k]).cwiseAbs().maxCoeff(), 1e-4 * (1.0 + cold->sol.u[k].cwiseAbs().maxCoeff()));
    }
    cold_iterations += cold->sol.iterations;
    warm_iterations += f->sol.iterations;
  }
  EXPECT_LT(warm_iterations, cold_iterations);
}

TEST(OcpQp, SolveDoesNotAllocateAtMpcSize) {
  auto f = std::make_unique<OcpFixture<38, 50, 60, 12, 20>>();
  std::mt19937_64 rng(30);
  make_random_ocp(f->qp, rng, 60);
  OcpSettings settings;
  settings.max_iterations = 3;
  OcpSettings warm = settings;
  warm.warm_start = true;
  {
    kuavo::test::AllocTrap trap;
    solve_ocp_qp(f->qp, settings, f->ws, f->sol);
    solve_ocp_qp(f->qp, warm, f->ws, f->sol);
    EXPECT_EQ(trap.count(), 0u) << trap.first_size_bytes();
  }
  EXPECT_EQ(f->sol.iterations, 3);
  for (int k = 0; k <= 60; ++k) EXPECT_TRUE(f->sol.u[k].allFinite());
}

}  // namespace
}  // namespace kuavo::qp::test
