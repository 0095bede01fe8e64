// Dense QP (Goldfarb–Idnani): KKT certificates on random WBC/IK-sized problems, degenerate
// cases, warm start, the iteration cap and zero allocation.
#include <gtest/gtest.h>

#include <Eigen/QR>

#include <memory>
#include <random>

#include "controllers/qp/dense_qp_solver.h"
#include "tests/qp/dense_qp_fixtures.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::qp::test {
namespace {

// Tolerances of the certificate. The solver stops at 1e-9 normalized violation; rows are
// O(10) long, so 1e-7 leaves a margin of 10 for roundoff. Stationarity is relative to the gradient.
constexpr double kPrimalTol = 1e-7;
constexpr double kStationarityTol = 1e-9;
constexpr double kComplementarityTol = 1e-7;

template <int NV, int NE, int NI>
struct Fixture {
  DenseQp<NV, NE, NI> qp;
  DenseQpWorkspace<NV, NE, NI> ws;
  DenseQpSolution<NV, NE, NI> sol;
};

void expect_kkt(const KktResiduals& k, double scale = 1.0) {
  EXPECT_LE(k.equality, kPrimalTol * scale);
  EXPECT_LE(k.inequality, kPrimalTol * scale);
  EXPECT_LE(k.stationarity, kStationarityTol * scale);
  EXPECT_LE(k.dual_sign, 0.0);
  EXPECT_LE(k.complementarity, kComplementarityTol * scale);
}

template <int NV, int NE, int NI>
void random_problems_satisfy_kkt(int count, std::uint64_t seed) {
  auto f = std::make_unique<Fixture<NV, NE, NI>>();
  std::mt19937_64 rng(seed);
  int total_active = 0;
  for (int n = 0; n < count; ++n) {
    make_random_dense_qp(f->qp, rng);
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    expect_kkt(dense_kkt(f->qp, f->sol));
    total_active += f->sol.working_set_size;
  }
  // The problems must actually exercise the inequalities.
  EXPECT_GT(total_active, count * 5);
}

TEST(DenseQp, WbcSizeRandomProblemsSatisfyKkt) { random_problems_satisfy_kkt<82, 32, 92>(40, 1); }
TEST(DenseQp, ReducedWbcSizeRandomProblemsSatisfyKkt) { random_problems_satisfy_kkt<56, 18, 60>(60, 2); }
TEST(DenseQp, SmallRandomProblemsSatisfyKkt) { random_problems_satisfy_kkt<8, 2, 6>(300, 3); }

// The WBC's Hessian: a dense block over the accelerations, a diagonal weight on the contact
// forces, and friction rows over the forces alone. The solver factors only the dense block
// (DenseQpWorkspace::dense_size); a coupling entry anywhere left of the diagonal in a row must
// put that row in the block. Cases: the WBC pattern (block 34 of 58), one coupling entry far
// down the first column (row 40: the block grows to 41 over diagonal rows 34..39), and a
// diagonal H (no block). KKT certificate on each; the block size against the construction.
TEST(DenseQp, BlockDiagonalHessianSatisfiesKkt) {
  constexpr int kNv = 58, kDense = 34;
  auto f = std::make_unique<Fixture<kNv, 6, 60>>();
  std::mt19937_64 rng(11);
  int total_active = 0;
  for (int n = 0; n < 60; ++n) {
    make_random_dense_qp(f->qp, rng);
    const int pattern = n % 3;
    const Eigen::MatrixXd dense = f->qp.H.topLeftCorner(kDense, kDense);
    f->qp.H.setZero();
    for (int i = 0; i < kNv; ++i) f->qp.H(i, i) = uniform(rng, 0.5, 2.0);
    if (pattern != 2) f->qp.H.topLeftCorner(kDense, kDense) = dense;
    if (pattern == 1) {
      f->qp.H(40, 0) = 0.3;
      f->qp.H(0, 40) = 0.3;
    }
    // Friction-like rows on the trailing variables only (their L⁻¹n skips the block), all
    // constraints re-centred on a new feasible point.
    f->qp.C.topRows(30).leftCols(kDense).setZero();
    Eigen::VectorXd x_feasible(kNv);
    for (int i = 0; i < kNv; ++i) x_feasible(i) = gaussian(rng);
    f->qp.b = f->qp.A * x_feasible;
    for (int i = 0; i < 60; ++i) {
      const double cx = f->qp.C.row(i).dot(x_feasible);
      f->qp.c_lower(i) = cx - uniform(rng, 0.0, 2.0);
      f->qp.c_upper(i) = cx + uniform(rng, 0.0, 2.0);
    }
    for (int j = 0; j < kNv; ++j) {
      f->qp.x_lower(j) = x_feasible(j) - uniform(rng, 0.1, 3.0);
      f->qp.x_upper(j) = x_feasible(j) + uniform(rng, 0.1, 3.0);
    }
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    expect_kkt(dense_kkt(f->qp, f->sol));
    EXPECT_EQ(f->ws.dense_size, pattern == 0 ? kDense : pattern == 1 ? 41 : 0) << n;
    total_active += f->sol.working_set_size;
    // The warm start imposes the working set as one block (V column by column): same solution.
    auto warm = std::make_unique<DenseQpSolution<kNv, 6, 60>>(f->sol);
    DenseQpSettings settings;
    settings.warm_start = true;
    ASSERT_EQ(solve_dense_qp(f->qp, settings, f->ws, *warm), QpStatus::kSolved) << n;
    expect_kkt(dense_kkt(f->qp, *warm));
    EXPECT_LE((warm->x - f->sol.x).cwiseAbs().maxCoeff(), 1e-8) << n;
  }
  EXPECT_GT(total_active, 60 * 5);
}

TEST(DenseQp, BoundsOnlyIkSizeSatisfiesKkt) {
  auto f = std::make_unique<Fixture<34, 0, 0>>();
  std::mt19937_64 rng(4);
  for (int n = 0; n < 50; ++n) {
    make_random_dense_qp(f->qp, rng);
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    expect_kkt(dense_kkt(f->qp, f->sol));
  }
}

// With H = I the solution is the projection of −g onto the box: an oracle by hand.
TEST(DenseQp, BoxProjectionMatchesClosedForm) {
  auto f = std::make_unique<Fixture<34, 0, 0>>();
  std::mt19937_64 rng(5);
  f->qp.H.setIdentity();
  for (int j = 0; j < 34; ++j) {
    f->qp.g(j) = 3.0 * gaussian(rng);
    f->qp.x_lower(j) = -1.0;
    f->qp.x_upper(j) = 0.5;
  }
  ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved);
  for (int j = 0; j < 34; ++j) EXPECT_NEAR(f->sol.x(j), std::clamp(-f->qp.g(j), -1.0, 0.5), 1e-12);
}

TEST(DenseQp, RedundantEqualitiesAreSkipped) {
  auto f = std::make_unique<Fixture<20, 8, 10>>();
  std::mt19937_64 rng(6);
  for (int n = 0; n < 20; ++n) {
    make_random_dense_qp(f->qp, rng);
    // Row 5 repeats row 1; row 7 is a combination of rows 0 and 2 (consistent right-hand sides).
    f->qp.A.row(5) = f->qp.A.row(1);
    f->qp.b(5) = f->qp.b(1);
    f->qp.A.row(7) = 2.0 * f->qp.A.row(0) - 0.5 * f->qp.A.row(2);
    f->qp.b(7) = 2.0 * f->qp.b(0) - 0.5 * f->qp.b(2);
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    expect_kkt(dense_kkt(f->qp, f->sol));
    // Inconsistent copy: no x satisfies both.
    f->qp.b(5) += 1.0;
    EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kInfeasible);
    EXPECT_TRUE(f->sol.x.allFinite());
  }
}

TEST(DenseQp, IllConditionedHessian) {
  auto f = std::make_unique<Fixture<40, 10, 30>>();
  std::mt19937_64 rng(7);
  for (int n = 0; n < 20; ++n) {
    make_random_dense_qp(f->qp, rng);
    // Eigenvalues spread over 1e-6 … 1e2 (condition number 1e8), random eigenvectors.
    Eigen::MatrixXd M(40, 40);
    fill_gaussian(M, rng);
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(M);
    const Eigen::MatrixXd Q = qr.householderQ();
    Eigen::VectorXd eig(40);
    for (int i = 0; i < 40; ++i) eig(i) = std::pow(10.0, -6.0 + 8.0 * i / 39.0);
    f->qp.H = Q * eig.asDiagonal() * Q.transpose();
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    // Stationarity is limited by cond(H)·ε relative to ‖H x‖; allow it.
    const KktResiduals k = dense_kkt(f->qp, f->sol);
    EXPECT_LE(k.equality, 1e-6);
    EXPECT_LE(k.inequality, 1e-6);
    EXPECT_LE(k.stationarity, 1e-6);
    EXPECT_LE(k.dual_sign, 0.0);
    EXPECT_LE(k.complementarity, 1e-6);
  }
}

TEST(DenseQp, InfeasibleInequalitiesAreReported) {
  auto f = std::make_unique<Fixture<10, 2, 4>>();
  std::mt19937_64 rng(8);
  make_random_dense_qp(f->qp, rng);
  // Row 1 = −row 0 with bounds that demand c·x ≥ 1 and c·x ≤ −1.
  f->qp.C.row(1) = -f->qp.C.row(0);
  f->qp.c_lower(0) = 1.0;
  f->qp.c_upper(0) = kInfinity;
  f->qp.c_lower(1) = 1.0;
  f->qp.c_upper(1) = kInfinity;
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kInfeasible);
  EXPECT_TRUE(f->sol.x.allFinite());
  // Equality x0 = 5 against the bound x0 ≤ 1.
  make_random_dense_qp(f->qp, rng);
  f->qp.A.row(0).setZero();
  f->qp.A(0, 0) = 1.0;
  f->qp.b(0) = 5.0;
  f->qp.x_upper(0) = 1.0;
  f->qp.x_lower(0) = -1.0;
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kInfeasible);
  // Crossed bounds are rejected up front.
  make_random_dense_qp(f->qp, rng);
  f->qp.x_lower(3) = f->qp.x_upper(3) + 1.0;
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kInfeasible);
}

// WBC-sized problems made infeasible with a pair of nearly opposite rows: c·x ≥ 1 and
// (−c + 1e-9·e)·x ≥ 1 need 1e-9·e·x ≥ 2, impossible inside the box (|x| < 10, ‖e‖₁ < 10³).
// The pair is nearly dependent, so roundoff lets GI take ever larger steps on it; the solver
// must still say kInfeasible within the cap (the multiplier limit), not run into the cap.
template <int NV, int NE, int NI>
void nearly_opposite_rows_are_infeasible(std::uint64_t seed) {
  auto f = std::make_unique<Fixture<NV, NE, NI>>();
  std::mt19937_64 rng(seed);
  for (int n = 0; n < 30; ++n) {
    make_random_dense_qp(f->qp, rng);
    f->qp.C.row(1) = -f->qp.C.row(0);
    for (int j = 0; j < NV; ++j) f->qp.C(1, j) += 1e-9 * gaussian(rng);
    f->qp.c_lower(0) = 1.0;
    f->qp.c_upper(0) = kInfinity;
    f->qp.c_lower(1) = 1.0;
    f->qp.c_upper(1) = kInfinity;
    EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kInfeasible) << n;
    EXPECT_TRUE(f->sol.x.allFinite());
  }
}

TEST(DenseQp, NearlyDependentInfeasibleRowsAreReportedBeforeTheCap) {
  nearly_opposite_rows_are_infeasible<58, 6, 60>(15);
  nearly_opposite_rows_are_infeasible<82, 32, 92>(16);
}

// A generous multiplier limit must not turn a feasible problem with large multipliers into
// kInfeasible: scale the cost by 1e6 (multipliers scale with it; the data scale too).
TEST(DenseQp, LargeMultipliersOfAFeasibleProblemAreNotInfeasibility) {
  auto f = std::make_unique<Fixture<56, 18, 60>>();
  std::mt19937_64 rng(17);
  for (int n = 0; n < 10; ++n) {
    make_random_dense_qp(f->qp, rng, 10.0, 1e-4);
    f->qp.H *= 1e6;
    f->qp.g *= 1e6;
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    const KktResiduals k = dense_kkt(f->qp, f->sol);
    EXPECT_LE(k.equality, kPrimalTol);
    EXPECT_LE(k.inequality, kPrimalTol);
    EXPECT_LE(k.stationarity, kStationarityTol);
    EXPECT_LE(k.dual_sign, 0.0);
    EXPECT_LE(k.complementarity, kComplementarityTol * 1e6);  // |z|·distance: z is 1e6 larger
    EXPECT_GT(f->sol.z_bound.cwiseAbs().maxCoeff(), 1e6);
  }
}

TEST(DenseQp, BadInputIsRejected) {
  auto f = std::make_unique<Fixture<10, 2, 4>>();
  std::mt19937_64 rng(9);
  make_random_dense_qp(f->qp, rng);
  f->qp.H(0, 0) = -1.0;
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kNotConvex);
  make_random_dense_qp(f->qp, rng);
  f->qp.g(2) = std::nan("");
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kBadInput);
  make_random_dense_qp(f->qp, rng);
  f->qp.c_upper(1) = std::nan("");
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kBadInput);
}

// Infinite entries of H, g, A, b or C (not only NaN) are bad input: the finiteness check
// is a vectorized sum, which must still see a single inf among the zeros.
TEST(DenseQp, InfiniteDataIsRejected) {
  auto f = std::make_unique<Fixture<58, 6, 60>>();
  std::mt19937_64 rng(18);
  for (int n = 0; n < 20; ++n) {
    make_random_dense_qp(f->qp, rng);
    const int i = n % 58, j = (7 * n) % 58, r = n % 60;
    const double bad = (n % 2 == 0) ? kInfinity : -kInfinity;
    switch (n % 5) {
      case 0: f->qp.H(i, j) = bad; break;
      case 1: f->qp.g(i) = bad; break;
      case 2: f->qp.A(n % 6, j) = bad; break;
      case 3: f->qp.b(n % 6) = bad; break;
      default: f->qp.C(r, j) = bad; break;
    }
    EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kBadInput) << n;
  }
  // Infinite bounds are not bad input (a disabled side), NaN bounds are.
  make_random_dense_qp(f->qp, rng);
  f->qp.x_upper.setConstant(kInfinity);
  f->qp.c_lower(3) = -kInfinity;
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved);
  f->qp.x_lower(5) = std::nan("");
  EXPECT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kBadInput);
}

// Variables on very different scales (the WBC's accelerations and forces: cost weights from
// 1e-4 to 1e3): the GI loop picks the constraint to add by violation in the metric of
// diag(H), which must not change the answer. Oracle: the KKT conditions.
TEST(DenseQp, BadlyScaledVariablesSatisfyKkt) {
  auto f = std::make_unique<Fixture<58, 6, 60>>();
  std::mt19937_64 rng(19);
  int total_active = 0;
  for (int n = 0; n < 30; ++n) {
    make_random_dense_qp(f->qp, rng);
    // x = S x̃ with S from 1e-2 to 1e2: H → S H S, g → S g, A → A S, C → C S, bounds / S.
    Eigen::Matrix<double, 58, 1> s;
    for (int j = 0; j < 58; ++j) s(j) = std::pow(10.0, uniform(rng, -2.0, 2.0));
    f->qp.H = s.asDiagonal() * f->qp.H * s.asDiagonal();
    f->qp.g = s.asDiagonal() * f->qp.g;
    f->qp.A = f->qp.A * s.asDiagonal();
    f->qp.C = f->qp.C * s.asDiagonal();
    f->qp.x_lower = f->qp.x_lower.cwiseQuotient(s);
    f->qp.x_upper = f->qp.x_upper.cwiseQuotient(s);
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved) << n;
    expect_kkt(dense_kkt(f->qp, f->sol));
    total_active += f->sol.working_set_size;
  }
  EXPECT_GT(total_active, 30 * 5);
}

// The counters account for every working-set change: their sum is the iteration count.
TEST(DenseQp, CountersAddUpToIterations) {
  auto f = std::make_unique<Fixture<56, 18, 60>>();
  std::mt19937_64 rng(20);
  DenseQpSettings warm;
  warm.warm_start = true;
  for (int n = 0; n < 20; ++n) {
    make_random_dense_qp(f->qp, rng);  // a new problem: the previous working set is a poor guess
    ASSERT_EQ(solve_dense_qp(f->qp, n % 3 == 0 ? DenseQpSettings{} : warm, f->ws, f->sol), QpStatus::kSolved);
    const DenseQpCounters& c = f->ws.counters;
    EXPECT_EQ(c.guess_imposed + c.guess_dropped + c.additions + c.blocking_drops, f->sol.iterations) << n;
    // Every row at the end was imposed or added and not dropped since.
    EXPECT_EQ(c.guess_imposed - c.guess_dropped + c.additions - c.blocking_drops, f->sol.working_set_size) << n;
  }
}

TEST(DenseQp, IterationCapReturnsWorkingSetMinimizer) {
  auto f = std::make_unique<Fixture<56, 18, 60>>();
  std::mt19937_64 rng(10);
  make_random_dense_qp(f->qp, rng);
  ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved);
  ASSERT_GT(f->sol.iterations, 4);
  DenseQpSettings capped;
  capped.max_iterations = 3;
  EXPECT_EQ(solve_dense_qp(f->qp, capped, f->ws, f->sol), QpStatus::kMaxIterations);
  EXPECT_EQ(f->sol.iterations, 3);
  EXPECT_TRUE(f->sol.x.allFinite());
  // Equalities hold and the multipliers are those of the working set (stationarity).
  const KktResiduals k = dense_kkt(f->qp, f->sol);
  EXPECT_LE(k.equality, kPrimalTol);
  EXPECT_LE(k.stationarity, kStationarityTol);
  EXPECT_LE(k.dual_sign, 0.0);
}

// The WBC re-solves a slightly changed problem every 2 ms.
template <int NV, int NE, int NI>
void warm_start_is_same_and_cheaper(std::uint64_t seed) {
  auto f = std::make_unique<Fixture<NV, NE, NI>>();
  auto cold = std::make_unique<DenseQpSolution<NV, NE, NI>>();
  std::mt19937_64 rng(seed);
  int cold_iterations = 0, warm_iterations = 0;
  for (int n = 0; n < 20; ++n) {
    make_random_dense_qp(f->qp, rng);
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol), QpStatus::kSolved);
    for (int j = 0; j < NV; ++j) f->qp.g(j) += 1e-3 * gaussian(rng);
    ASSERT_EQ(solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, *cold), QpStatus::kSolved);
    DenseQpSettings warm;
    warm.warm_start = true;
    ASSERT_EQ(solve_dense_qp(f->qp, warm, f->ws, f->sol), QpStatus::kSolved);
    EXPECT_LE((f->sol.x - cold->x).cwiseAbs().maxCoeff(), 1e-8);
    expect_kkt(dense_kkt(f->qp, f->sol));
    EXPECT_LE(f->sol.iterations, cold->iterations);
    cold_iterations += cold->iterations;
    warm_iterations += f->sol.iterations;
  }
  EXPECT_LT(warm_iterations, cold_iterations);
}

TEST(DenseQp, WarmStartReachesSameSolutionInFewerIterations) {
  warm_start_is_same_and_cheaper<82, 32, 92>(11);
  warm_start_is_same_and_cheaper<56, 18, 60>(12);
}

// A wrong guess (another problem's working set) must still give the right answer.
TEST(DenseQp, WarmStartFromWrongGuessIsStillCorrect) {
  auto f = std::make_unique<Fixture<56, 18, 60>>();
  std::mt19937_64 rng(13);
  DenseQpSettings warm;
  warm.warm_start = true;
  for (int n = 0; n < 20; ++n) {
    make_random_dense_qp(f->qp, rng);
    ASSERT_EQ(solve_dense_qp(f->qp, warm, f->ws, f->sol), QpStatus::kSolved);
    expect_kkt(dense_kkt(f->qp, f->sol));
  }
}

TEST(DenseQp, SolvesDoNotAllocate) {
  auto f = std::make_unique<Fixture<82, 32, 92>>();
  std::mt19937_64 rng(14);
  make_random_dense_qp(f->qp, rng);
  DenseQpSettings warm;
  warm.warm_start = true;
  {
    kuavo::test::AllocTrap trap;
    solve_dense_qp(f->qp, DenseQpSettings{}, f->ws, f->sol);
    solve_dense_qp(f->qp, warm, f->ws, f->sol);
    EXPECT_EQ(trap.count(), 0u) << trap.first_size_bytes();
  }
  EXPECT_EQ(f->sol.status, QpStatus::kSolved);
}

}  // namespace
}  // namespace kuavo::qp::test
