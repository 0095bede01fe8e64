// The Riccati's FMA kernels (riccati_kernels.h) and its per-stage signed factorization against
// plain Eigen products and factorizations, at the sizes of interest (MPC stage blocks, padded
// remainders, empty inner dimensions).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <memory>
#include <cmath>
#include <cstdint>
#include <vector>
#include <limits>
#include <random>

#include "controllers/qp/riccati.h"
#include "controllers/qp/riccati_kernels.h"
#include "tests/qp/dense_qp_fixtures.h"

namespace kuavo::qp::test {
namespace {

using Eigen::MatrixXd;
using kernels::Update;

// Relative to the operands' scale: the kernels and Eigen sum in different orders.
constexpr double kTolerance = 1e-13;

MatrixXd random_matrix(int rows, int cols, std::mt19937_64& rng) {
  MatrixXd m(rows, cols);
  fill_gaussian(m, rng);
  return m;
}

template <bool kTransB, Update kUpdate, bool kLower>
void check_gemm(int m, int n, int k, std::mt19937_64& rng) {
  const int ld = m + 4;  // leading dimensions larger than the extents, as in the stage blocks
  const MatrixXd A = random_matrix(ld, k, rng);
  const MatrixXd B = kTransB ? random_matrix(n + 3, k, rng) : random_matrix(k + 3, n, rng);
  const MatrixXd C0 = random_matrix(ld, n, rng);
  MatrixXd C = C0;
  kernels::gemm<kTransB, kUpdate, kLower>(m, n, k, A.data(), static_cast<int>(A.rows()), B.data(),
                                          static_cast<int>(B.rows()), C.data(), static_cast<int>(C.rows()));
  MatrixXd product = kTransB ? MatrixXd(A.topRows(m) * B.topRows(n).transpose())
                             : MatrixXd(A.topRows(m) * B.topRows(k));
  MatrixXd expected = C0.topRows(m);
  if (kUpdate == Update::kSet) expected = product;
  if (kUpdate == Update::kAdd) expected += product;
  if (kUpdate == Update::kSub) expected -= product;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < ld; ++i) {
      if (i >= m || (kLower && i < j / 4 * 4)) {
        EXPECT_EQ(C(i, j), C0(i, j)) << "outside the product: " << i << "," << j;  // untouched
      } else if (!kLower || i >= j) {
        EXPECT_NEAR(C(i, j), expected(i, j), kTolerance * (1.0 + k) * 10.0) << m << "x" << n << "x" << k << " at " << i << "," << j;
      }
    }
  }
}

// C = S + A·op(B) (kSum) or Sᵀ + A·op(B) (kSumT) with the addend's first s_rows rows (the rest
// read as zero): against Eigen, and bit for bit against kAdd on a copy of the addend (what the
// matrix pass did before it folded R, S and Q into the products). S's storage past the addend's
// rows and columns holds NaN, so a load past them would show; C's old contents must not matter.
template <bool kTransB, bool kLower, Update kSum>
void check_gemm_sum(int m, int n, int k, int s_rows, std::mt19937_64& rng) {
  const int ld = m + 4;
  const MatrixXd A = random_matrix(ld, k, rng);
  const MatrixXd B = kTransB ? random_matrix(n + 3, k, rng) : random_matrix(k + 3, n, rng);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const MatrixXd addend = random_matrix(s_rows, n, rng);  // C's rows [0, s_rows)
  MatrixXd S = kSum == Update::kSumT ? MatrixXd::Constant(n + 3, s_rows + 3, nan) : MatrixXd::Constant(s_rows + 3, n, nan);
  if (kSum == Update::kSumT) {
    S.topLeftCorner(n, s_rows) = addend.transpose();
  } else {
    S.topRows(s_rows) = addend;
  }
  MatrixXd S_ext = MatrixXd::Zero(ld, n);  // the addend, zero below its rows
  S_ext.topRows(std::min(s_rows, m)) = addend.topRows(std::min(s_rows, m));
  const MatrixXd C0 = random_matrix(ld, n, rng);
  MatrixXd C = C0;
  kernels::gemm<kTransB, kSum, kLower>(m, n, k, A.data(), static_cast<int>(A.rows()), B.data(),
                                       static_cast<int>(B.rows()), C.data(), ld,
                                       kernels::Addend{S.data(), static_cast<int>(S.rows()), s_rows});
  MatrixXd C_add = C0;
  C_add.topRows(m) = S_ext.topRows(m);
  kernels::gemm<kTransB, Update::kAdd, kLower>(m, n, k, A.data(), static_cast<int>(A.rows()), B.data(),
                                               static_cast<int>(B.rows()), C_add.data(), ld);
  const MatrixXd product = kTransB ? MatrixXd(A.topRows(m) * B.topRows(n).transpose())
                                   : MatrixXd(A.topRows(m) * B.topRows(k));
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < ld; ++i) {
      if (i >= m || (kLower && i < j / 4 * 4)) {
        EXPECT_EQ(C(i, j), C0(i, j)) << "outside the product: " << i << "," << j;
      } else {
        EXPECT_EQ(C(i, j), C_add(i, j)) << m << "x" << n << "x" << k << " rows " << s_rows << " at " << i << "," << j;
        if (!kLower || i >= j) {
          EXPECT_NEAR(C(i, j), S_ext(i, j) + product(i, j), kTolerance * (1.0 + k) * 10.0) << i << "," << j;
        }
      }
    }
  }
}

TEST(RiccatiKernels, ProductsOntoASeparateAddendMatchEigenAndTheCopiedSum) {
  std::mt19937_64 rng(106);
  for (const int m : {4, 8, 12, 20, 28, 40, 52}) {
    for (const int n : {1, 2, 4, 38, 50}) {
      for (const int k : {0, 1, 38}) {
        for (const int s_rows : {m, m - 2, m - 5, m - 11, 1}) {
          if (s_rows < 1) continue;
          check_gemm_sum<true, true, Update::kSum>(m, n, k, s_rows, rng);
          check_gemm_sum<false, true, Update::kSum>(m, n, k, s_rows, rng);
          check_gemm_sum<true, false, Update::kSum>(m, n, k, s_rows, rng);
          check_gemm_sum<true, false, Update::kSumT>(m, n, k, s_rows, rng);
          check_gemm_sum<false, false, Update::kSumT>(m, n, k, s_rows, rng);
        }
      }
    }
  }
}

TEST(RiccatiKernels, ProductsMatchEigen) {
  std::mt19937_64 rng(101);
  for (const int m : {4, 8, 12, 40, 52, 92}) {
    for (const int n : {1, 2, 3, 4, 5, 38, 50}) {
      for (const int k : {0, 1, 3, 38, 52}) {
        check_gemm<false, Update::kSet, false>(m, n, k, rng);
        check_gemm<false, Update::kAdd, false>(m, n, k, rng);
        check_gemm<true, Update::kSub, false>(m, n, k, rng);
        check_gemm<true, Update::kAdd, true>(m, n, k, rng);
        check_gemm<false, Update::kAdd, true>(m, n, k, rng);
      }
    }
  }
}

TEST(RiccatiKernels, TransposeAndTriangularProductMatchEigen) {
  std::mt19937_64 rng(102);
  for (const int m : {1, 3, 4, 38, 50}) {
    for (const int n : {1, 5, 38, 50}) {
      const MatrixXd src = random_matrix(m + 2, n, rng);
      MatrixXd dst = MatrixXd::Zero(n + 1, m);
      kernels::transpose(m, n, src.data(), m + 2, dst.data(), n + 1);
      EXPECT_EQ(dst.topRows(n), src.topRows(m).transpose());
      EXPECT_EQ(dst.row(n).norm(), 0.0);
    }
  }
  // The columns' last nonzero rows, against a plain scan from the end: zero tails of every
  // length (whole, none, remainders past the 4-row vectors), −0, NaN and infinities count as
  // nonzero except −0, and rows past m (the leading-dimension padding) are not looked at;
  // 63, 64: the last rows of the per-column bit masks, 65, 70: the scan beyond them.
  for (const int m : {1, 3, 4, 7, 38, 63, 64, 65, 70}) {
    for (const int n : {1, 5, 38, 50}) {
      MatrixXd src = random_matrix(m + 2, n, rng);
      for (int j = 0; j < n; ++j) {
        const int tail = static_cast<int>(rng() % static_cast<unsigned>(m + 1));  // zero rows at the end
        for (int i = m - tail; i < m; ++i) src(i, j) = 0.0;
        if (j % 7 == 3 && tail < m) src(m - tail - 1, j) = std::numeric_limits<double>::quiet_NaN();
        if (j % 7 == 5 && tail < m) src(m - tail - 1, j) = -std::numeric_limits<double>::infinity();
        if (j % 5 == 1 && tail > 0) src(m - 1, j) = -0.0;
        src(m, j) = src(m + 1, j) = 1.0;  // beyond the extent: never a column's last row
      }
      MatrixXd dst = MatrixXd::Zero(n + 1, m);
      std::vector<int> last(n, -1);
      kernels::transpose(m, n, src.data(), m + 2, dst.data(), n + 1, last.data());
      for (int j = 0; j < n; ++j) {
        int expected = m;
        while (expected > 0 && src(expected - 1, j) == 0.0) --expected;
        EXPECT_EQ(last[j], expected) << m << "x" << n << " column " << j;
        for (int i = 0; i < m; ++i) {
          if (std::isnan(src(i, j))) {
            EXPECT_TRUE(std::isnan(dst(j, i)));
          } else {
            EXPECT_EQ(dst(j, i), src(i, j));
          }
        }
      }
    }
  }
  for (const int m : {4, 40, 52}) {
    for (const int n : {1, 4, 6, 38}) {
      const MatrixXd A = random_matrix(m, n, rng);
      MatrixXd L = random_matrix(n + 2, n, rng);
      // Zeros above the diagonal inside the 4×4 diagonal chunks, garbage elsewhere above it.
      for (int j = 0; j < n; ++j) {
        for (int i = j / 4 * 4; i < j; ++i) L(i, j) = 0.0;
      }
      MatrixXd C = MatrixXd::Constant(m, n, 7.0);
      kernels::trmm_right_lower(m, n, A.data(), m, L.data(), n + 2, C.data(), m);
      const MatrixXd expected = A * L.topRows(n).triangularView<Eigen::Lower>();
      EXPECT_LE((C - expected).cwiseAbs().maxCoeff(), kTolerance * 10.0 * (1.0 + n)) << m << "x" << n;
    }
  }
}

TEST(RiccatiKernels, CholeskyMatchesEigenAndRefusesIndefinite) {
  std::mt19937_64 rng(103);
  for (const int n : {4, 8, 40, 52}) {
    const MatrixXd M = random_matrix(n + 3, n, rng);
    const MatrixXd S = M.transpose() * M + 0.1 * MatrixXd::Identity(n, n);
    MatrixXd L = S;
    ASSERT_TRUE(kernels::cholesky(L.data(), n, n));
    const MatrixXd expected = S.llt().matrixL();
    const MatrixXd mine = L.triangularView<Eigen::Lower>();
    EXPECT_LE((mine - expected).cwiseAbs().maxCoeff(), 1e-11) << n;
    MatrixXd indefinite = S;
    indefinite(n - 1, n - 1) = -1.0;
    EXPECT_FALSE(kernels::cholesky(indefinite.data(), n, n));
  }
}

double max_abs(const Eigen::VectorXd& v) { return v.size() == 0 ? 0.0 : v.cwiseAbs().maxCoeff(); }

// The vector-pass kernels: every row remainder (masked loads), column remainders, leading
// dimensions larger than the extents, and nothing written past the extent.
TEST(RiccatiKernels, MatrixVectorProductsMatchEigen) {
  std::mt19937_64 rng(106);
  for (const int m : {0, 1, 2, 3, 4, 5, 7, 12, 38, 50}) {
    for (const int n : {1, 2, 3, 4, 5, 9, 38, 50}) {
      const int lda = m + 3;
      const MatrixXd A = random_matrix(lda, n, rng);
      const Eigen::VectorXd xn = random_matrix(n, 1, rng), xm = random_matrix(m + 1, 1, rng);
      const double tol = kTolerance * 10.0 * (1.0 + std::max(m, n));
      Eigen::VectorXd y0 = random_matrix(m + 1, 1, rng), y = y0;  // one guard entry past m
      kernels::gemv_n<Update::kAdd>(m, n, A.data(), lda, xn.data(), y.data());
      EXPECT_LE(max_abs(y.head(m) - (y0.head(m) + A.topRows(m) * xn)), tol) << m << "x" << n;
      EXPECT_EQ(y(m), y0(m));
      y = y0;
      kernels::gemv_n<Update::kSub>(m, n, A.data(), lda, xn.data(), y.data());
      EXPECT_LE(max_abs(y.head(m) - (y0.head(m) - A.topRows(m) * xn)), tol) << m << "x" << n;
      EXPECT_EQ(y(m), y0(m));
      const Eigen::VectorXd z0 = random_matrix(n + 1, 1, rng);
      const Eigen::VectorXd atx = A.topRows(m).transpose() * xm.head(m);
      Eigen::VectorXd z = z0;
      kernels::gemv_t<Update::kSet>(m, n, A.data(), lda, xm.data(), z.data());
      EXPECT_LE(max_abs(z.head(n) - atx), tol) << m << "x" << n;
      EXPECT_EQ(z(n), z0(n));
      z = z0;
      kernels::gemv_t<Update::kAdd>(m, n, A.data(), lda, xm.data(), z.data());
      EXPECT_LE(max_abs(z.head(n) - (z0.head(n) + atx)), tol) << m << "x" << n;
      z = z0;
      kernels::gemv_t<Update::kSub>(m, n, A.data(), lda, xm.data(), z.data());
      EXPECT_LE(max_abs(z.head(n) - (z0.head(n) - atx)), tol) << m << "x" << n;
      EXPECT_EQ(z(n), z0(n));
    }
  }
}

// gemv_n_groups over the transpose's row groups: bit for bit gemv_n on matrices whose
// columns are zero in random 4-row groups (the MPC's A and B: identity rows, short force
// columns), with row remainders, remainder columns and one all-zero column group. The groups
// themselves against a plain scan (NaN counts as nonzero).
TEST(RiccatiKernels, MatrixVectorProductOverNonzeroRowGroupsIsGemvBitForBit) {
  std::mt19937_64 rng(108);
  for (const int m : {1, 3, 4, 7, 12, 38, 63, 64}) {
    for (const int n : {1, 3, 4, 5, 9, 38, 50}) {
      const int lda = m + 3;
      MatrixXd A = random_matrix(lda, n, rng);
      for (int j = 0; j < n; ++j) {
        for (int g = 0; 4 * g < m; ++g) {
          const bool all_zero_group = j >= 4 && j < 8;  // a whole 4-column step without terms
          if (all_zero_group || rng() % 3 != 0) A.block(4 * g, j, std::min(4, m - 4 * g), 1).setZero();
        }
        if (j % 7 == 2) A(m - 1, j) = std::numeric_limits<double>::quiet_NaN();
        A(m, j) = A(m + 1, j) = A(m + 2, j) = 1.0;  // rows past m: never a group's
      }
      MatrixXd At = MatrixXd::Zero(n, m);
      std::vector<std::uint16_t> groups(n, 0xdead);
      kernels::transpose(m, n, A.data(), lda, At.data(), n, nullptr, groups.data());
      for (int j = 0; j < n; ++j) {
        unsigned expected = 0;
        for (int i = 0; i < m; ++i) {
          if (A(i, j) != 0.0) expected |= 1u << (i / 4);
        }
        EXPECT_EQ(groups[j], expected) << m << "x" << n << " column " << j;
      }
      for (int i = 0; i < m; ++i) A.row(i) = A.row(i).unaryExpr([](double v) { return std::isnan(v) ? 0.5 : v; });
      const Eigen::VectorXd x = random_matrix(n, 1, rng);
      const Eigen::VectorXd y0 = random_matrix(m + 1, 1, rng);  // one guard entry past m
      Eigen::VectorXd y = y0, z = y0;
      kernels::gemv_n<Update::kAdd>(m, n, A.data(), lda, x.data(), y.data());
      kernels::gemv_n_groups(m, n, A.data(), lda, x.data(), z.data(), groups.data());
      for (int i = 0; i <= m; ++i) EXPECT_EQ(z(i), y(i)) << m << "x" << n << " row " << i;
    }
  }
}

// transpose_declared reads only the declared row groups (NaN beyond them, where no column of
// the 4-column step declares the group, never reaches the result) and gives transpose's dst,
// last and groups bit for bit; gemv_t_groups over those groups is gemv_t bit for bit
// (set, add, subtract), with row remainders and remainder columns.
TEST(RiccatiKernels, DeclaredRowGroupsTransposeAndProductAreTheDenseOnesBitForBit) {
  std::mt19937_64 rng(109);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const int m : {1, 3, 4, 7, 12, 38, 63, 64}) {
    for (const int n : {1, 3, 4, 5, 9, 38, 50}) {
      const int groups_m = (m + 3) / 4;
      MatrixXd A = random_matrix(m, n, rng);
      std::vector<std::uint16_t> declared(n);
      for (int j = 0; j < n; ++j) {
        declared[j] = static_cast<std::uint16_t>(rng() & ((1u << groups_m) - 1));
        if (j % 5 == 4) declared[j] = 0;
        for (int g = 0; g < groups_m; ++g) {
          if ((declared[j] >> g & 1u) == 0) A.block(4 * g, j, std::min(4, m - 4 * g), 1).setZero();
          else if (rng() % 4 == 0) A.block(4 * g, j, std::min(4, m - 4 * g), 1).setZero();  // declared, zero
        }
      }
      MatrixXd poisoned = A;  // NaN where no column of the step (or the remainder column) declares
      for (int j = 0; j < n; ++j) {
        const int step = j / 4 * 4;
        unsigned read = declared[j];
        if (step + 4 <= n) read = declared[step] | declared[step + 1] | declared[step + 2] | declared[step + 3];
        for (int i = 0; i < m; ++i) {
          if ((read >> (i / 4) & 1u) == 0) poisoned(i, j) = nan;
        }
      }
      MatrixXd dense_t = MatrixXd::Constant(n, m, 5.0), declared_t = MatrixXd::Constant(n, m, 5.0);
      std::vector<int> last(n), last_d(n);
      std::vector<std::uint16_t> groups(n), groups_d(n);
      kernels::transpose(m, n, A.data(), m, dense_t.data(), n, last.data(), groups.data());
      kernels::transpose_declared(m, n, poisoned.data(), m, declared_t.data(), n, last_d.data(), groups_d.data(),
                                  declared.data());
      for (int j = 0; j < n; ++j) {
        EXPECT_EQ(last_d[j], last[j]) << m << "x" << n << " column " << j;
        EXPECT_EQ(groups_d[j], groups[j]) << m << "x" << n << " column " << j;
        for (int i = 0; i < m; ++i) EXPECT_EQ(declared_t(j, i), dense_t(j, i)) << m << "x" << n;
      }
      const Eigen::VectorXd x = random_matrix(m, 1, rng);
      const Eigen::VectorXd y0 = random_matrix(n + 1, 1, rng);  // one guard entry past n
      Eigen::VectorXd y = y0, z = y0;
      kernels::gemv_t<Update::kSet>(m, n, A.data(), m, x.data(), y.data());
      kernels::gemv_t_groups<Update::kSet>(m, n, A.data(), m, x.data(), z.data(), groups.data());
      for (int j = 0; j <= n; ++j) EXPECT_EQ(z(j), y(j)) << m << "x" << n << " set " << j;
      y = y0, z = y0;
      kernels::gemv_t<Update::kAdd>(m, n, A.data(), m, x.data(), y.data());
      kernels::gemv_t_groups<Update::kAdd>(m, n, A.data(), m, x.data(), z.data(), groups.data());
      for (int j = 0; j <= n; ++j) EXPECT_EQ(z(j), y(j)) << m << "x" << n << " add " << j;
      y = y0, z = y0;
      kernels::gemv_t<Update::kSub>(m, n, A.data(), m, x.data(), y.data());
      kernels::gemv_t_groups<Update::kSub>(m, n, A.data(), m, x.data(), z.data(), groups.data());
      for (int j = 0; j <= n; ++j) EXPECT_EQ(z(j), y(j)) << m << "x" << n << " sub " << j;
    }
  }
}

TEST(RiccatiKernels, TriangularSolvesAndProductsMatchEigen) {
  std::mt19937_64 rng(107);
  for (const int n : {1, 2, 3, 4, 5, 7, 12, 38, 50}) {
    const int ld = n + 2;
    MatrixXd L = random_matrix(ld, n, rng);
    for (int j = 0; j < n; ++j) L(j, j) = 2.0 + std::abs(L(j, j));  // well conditioned
    const auto Lt = L.topRows(n).triangularView<Eigen::Lower>();
    const Eigen::VectorXd b = random_matrix(n, 1, rng);
    // The solves take the inverses of the 4×4 diagonal blocks (the last one jb×jb, padded
    // with the identity): check those against Eigen's inverse first.
    std::vector<double> binv(16 * ((n + 3) / 4)), binvt(binv.size());
    for (int j = 0; j < n; j += 4) {
      const int jb = std::min(4, n - j);
      kernels::invert_diag4(L.data(), ld, j, jb, binv.data() + 4 * j, binvt.data() + 4 * j);
      const Eigen::Map<const Eigen::Matrix4d> X(binv.data() + 4 * j), Xt(binvt.data() + 4 * j);
      Eigen::Matrix4d expected = Eigen::Matrix4d::Identity();
      expected.topLeftCorner(jb, jb) =
          MatrixXd(L.block(j, j, jb, jb).triangularView<Eigen::Lower>()).inverse();
      EXPECT_LE((X - expected).cwiseAbs().maxCoeff(), 1e-14) << n << " block " << j;
      EXPECT_EQ(Xt, X.transpose());
    }
    Eigen::VectorXd x = b;
    kernels::trsv_lower(n, L.data(), ld, binv.data(), x.data());
    EXPECT_LE((Lt * x - b).cwiseAbs().maxCoeff(), 1e-12) << n;
    x = b;
    kernels::trsv_lower_trans(n, L.data(), ld, binvt.data(), x.data());
    EXPECT_LE((Lt.transpose() * x - b).cwiseAbs().maxCoeff(), 1e-12) << n;
    // The triangular products read the 4×4 diagonal chunks whole: zeros above the diagonal there.
    for (int j = 0; j < n; ++j) {
      for (int i = j / 4 * 4; i < j; ++i) L(i, j) = 0.0;
    }
    const MatrixXd Ld = L.topRows(n).triangularView<Eigen::Lower>();
    Eigen::VectorXd y = Eigen::VectorXd::Constant(n + 1, 5.0);
    kernels::trmv_lower_trans(n, L.data(), ld, b.data(), y.data());
    EXPECT_LE((y.head(n) - Ld.transpose() * b).cwiseAbs().maxCoeff(), kTolerance * 10.0 * (1.0 + n)) << n;
    EXPECT_EQ(y(n), 5.0);
    const Eigen::VectorXd y0 = y;
    kernels::trmv_lower_add(n, L.data(), ld, b.data(), y.data());
    EXPECT_LE((y.head(n) - y0.head(n) - Ld * b).cwiseAbs().maxCoeff(), kTolerance * 10.0 * (1.0 + n)) << n;
    EXPECT_EQ(y(n), 5.0);
  }
}

// One stage of the signed sweep: Lu, X, Yᵀ, Lm, −(Lm⁻¹G)ᵀ and the cost-to-go's factor Lp against
// the classical range-space formulas with Eigen's LLT, with padding in every block.
template <int NX, int NU, int NC>
void check_stage(int ne, std::mt19937_64& rng) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  constexpr int kLd = Layout::kLd, kUp = Layout::kUp, kXo = Layout::kXo;
  const MatrixXd M = random_matrix(NX + NU + 3, NX + NU, rng);
  const MatrixXd H = M.transpose() * M / double(NX + NU) + 0.05 * MatrixXd::Identity(NX + NU, NX + NU);
  auto stage = std::make_unique<OcpStage<NX, NU, NC, 0>>();
  auto& s = *stage;
  s.R = H.topLeftCorner(NU, NU);
  s.S = H.block(0, NU, NU, NX);
  s.Q = H.bottomRightCorner(NX, NX);
  fill_gaussian(s.C, rng);
  fill_gaussian(s.D, rng);
  s.num_eq = ne;
  auto w = std::make_unique<RiccatiStage<NX, NU, NC, 0>>();
  w->L.fill(3.0);  // stale data from an earlier problem must not matter
  riccati_detail::FactorMap<NX, NU, NC> K(w->L.data());
  const int ne_padded = kernels::round_up4(ne);
  riccati_detail::load_stage(s, ne_padded, K);
  ASSERT_EQ((riccati_detail::factor_stage<NX, NU, NC>(w->L.data(), ne, ne_padded, w->dinv.data(), w->dinvT.data())),
            QpStatus::kSolved);
  // The inverses of the u and used ν columns' 4×4 diagonal blocks (padding pivots included).
  for (int j = 0; j < kUp + ne_padded; j += 4) {
    const Eigen::Map<const Eigen::Matrix4d> X(w->dinv.data() + 4 * j), Xt(w->dinvT.data() + 4 * j);
    const Eigen::Matrix4d block = K.template block<4, 4>(j, j).template triangularView<Eigen::Lower>();
    EXPECT_LE((X * block - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-13) << "block " << j;
    EXPECT_EQ(Xt, X.transpose());
  }
  ASSERT_TRUE((riccati_detail::factor_cost_to_go<NX, NU, NC>(w->L.data(), ne_padded)));

  const Eigen::LLT<MatrixXd> llt(MatrixXd(s.R));
  const MatrixXd Lu = llt.matrixL();
  const MatrixXd X = llt.matrixL().solve(MatrixXd(s.S)).transpose();
  MatrixXd P = MatrixXd(s.Q) - X * X.transpose();
  const double tol = 1e-11;
  EXPECT_LE((MatrixXd(K.template topLeftCorner<NU, NU>().template triangularView<Eigen::Lower>()) - Lu).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((K.template block<NX, NU>(kXo, 0) - X).cwiseAbs().maxCoeff(), tol);
  if (ne > 0) {
    const MatrixXd Y = llt.matrixL().solve(MatrixXd(s.D.topRows(ne).transpose()));
    const Eigen::LLT<MatrixXd> m_llt(Y.transpose() * Y);
    const MatrixXd G = MatrixXd(s.C.topRows(ne)) - Y.transpose() * X.transpose();
    const MatrixXd GmT = m_llt.matrixL().solve(G).transpose();
    P += GmT * GmT.transpose();
    EXPECT_LE((K.block(kUp, 0, ne, NU) - Y.transpose()).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((MatrixXd(K.block(kUp, kUp, ne, ne).template triangularView<Eigen::Lower>()) - MatrixXd(m_llt.matrixL())).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((K.block(kXo, kUp, NX, ne) + GmT).cwiseAbs().maxCoeff(), tol);
  }
  // The x block is Lp (P = Lp·Lpᵀ), zeros above the diagonal inside its 4×4 diagonal chunks.
  const MatrixXd Lp = K.template block<NX, NX>(kXo, kXo).template triangularView<Eigen::Lower>();
  EXPECT_LE((Lp * Lp.transpose() - P).cwiseAbs().maxCoeff(), tol) << "P, ne = " << ne;
  EXPECT_LE((Lp - MatrixXd(P.llt().matrixL())).cwiseAbs().maxCoeff(), tol) << "Lp, ne = " << ne;
  for (int j = 0; j < NX; ++j) {
    for (int i = j / 4 * 4; i < j; ++i) EXPECT_EQ(K(kXo + i, kXo + j), 0.0) << i << "," << j;
  }
  (void)kLd;
}

TEST(RiccatiKernels, StageFactorizationMatchesRangeSpaceFormulas) {
  std::mt19937_64 rng(104);
  for (int ne = 0; ne <= 3; ++ne) check_stage<5, 6, 3>(ne, rng);
  for (const int ne : {0, 6, 12}) check_stage<38, 50, 12>(ne, rng);
  check_stage<38, 50, 30>(15, rng);
}

TEST(RiccatiKernels, StageFactorizationReportsStatuses) {
  std::mt19937_64 rng(105);
  using Layout = RiccatiLayout<5, 6, 3>;
  OcpStage<5, 6, 3, 0> s;
  fill_gaussian(s.C, rng);
  fill_gaussian(s.D, rng);
  auto w = std::make_unique<RiccatiStage<5, 6, 3, 0>>();
  riccati_detail::FactorMap<5, 6, 3> K(w->L.data());
  s.R(2, 2) = -1.0;  // indefinite Quu
  riccati_detail::load_stage(s, 0, K);
  EXPECT_EQ((riccati_detail::factor_stage<5, 6, 3>(w->L.data(), 0, 0)), QpStatus::kNotConvex);
  s.R(2, 2) = 1.0;
  s.num_eq = 2;
  s.D.row(1) = 2.0 * s.D.row(0);  // dependent equalities
  riccati_detail::load_stage(s, 4, K);
  EXPECT_EQ((riccati_detail::factor_stage<5, 6, 3>(w->L.data(), 2, 4)), QpStatus::kRankDeficient);
  static_assert(Layout::kLd == 8 + 4 + 8);
}

}  // namespace
}  // namespace kuavo::qp::test
