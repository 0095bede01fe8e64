// Riccati recursion for the OCP of ocp_qp.h with stage-wise state-input equalities, split into
// a matrix pass (riccati_factor, O(T·(NX+NU)³)) and a vector pass (riccati_solve, O(T·(NX+NU)²))
// so the interior-point method can solve twice per factorization.
//
// Per stage, with Pₖ₊₁ the cost-to-go Hessian, the stage's KKT block in the order [u; ν; x]
//   K = [ H_uu   Dᵀ   H_ux ]      H = [R S; Sᵀ Q] + [B A]ᵀ Pₖ₊₁ [B A]   (+ Gᵀ W G, barrier)
//       [ D      0    C    ]
//       [ H_xu   Cᵀ   H_xx ]
// is factored K = L·diag(+I, −I, ·)·Lᵀ over its u and ν columns only, in place:
//   u columns (Cholesky, d = +1): L_uu = Lu (H_uu = Lu Luᵀ), L_νu = Yᵀ = D Lu⁻ᵀ, L_xu = X = H_xu Lu⁻ᵀ;
//   ν columns (d = −1, the pivot block is −M, M = YᵀY = Lm Lmᵀ): L_νν = Lm, L_xν = −(Lm⁻¹G)ᵀ
//   with G = C − YᵀXᵀ; and the x block left over is the Schur complement
//   Pₖ = H_xx − X Xᵀ + (Lm⁻¹G)ᵀ(Lm⁻¹G),
// the same quantities as the classical range-space elimination (Y, M, G), but computed by one
// signed Cholesky sweep with one set of kernels instead of a chain of small Eigen products.
// Rank test on the ν pivots as before (kRankDeficient), a non-positive u pivot is kNotConvex.
//
// Speed (riccati_kernels.h): [B A]ᵀPₖ₊₁[B A] is formed as ZᵀZ with Z = Lpᵀ[B A], Pₖ₊₁ = Lp·Lpᵀ
// (a triangular product at half the flops of P·[B A], then the lower triangle of a symmetric
// product); a left-looking blocked Cholesky over 4-column panels whose updates are the same
// 8×4 FMA tiles; the x block's Schur complement is one lower-triangular product. Storage is
// padded to multiples of 4 rows (u padding carries an identity pivot, ν padding a −1 pivot,
// x padding zero rows with an identity pivot), so every tile is whole. R, S and Q are not copied
// into the factor storage: the u, x-u and x blocks' products write R + ZᵀZ, Sᵀ + ZᵀZ and
// Q + ZᵀZ, reading R, S and Q in their tiles' epilogues (kernels::Update::kSum, kSumT), where at
// MPC size (the horizon's data beyond L2) their first touch overlaps the FMAs instead of
// stalling a copy loop. Known zeros are not fetched at all: a stage without S (s_zero), R
// beyond its leading block and diagonal (r_dense), the rows of A and B outside their declared
// row groups (OcpQp::ab_groups_declared), and in the vector passes every zero 4-row group of
// A and B (found by the transpose): at MPC size each stage's data is fetched from beyond L2 in
// every call, so what is not read is what the call no longer waits for. And what is read is
// asked for ahead: while stage k is factored, stage k − 1's lines are prefetched in slices
// between its kernels (prefetch.h; after the planning task's idle the horizon's data comes from
// beyond the caches, and the pass otherwise waits for it line by line).
// Square-root recursion with the classical statuses: the sweep goes on into the x block, whose
// Schur complement Pₖ is factored in place (Pₖ = Lp·Lpᵀ, the next stage's Lp, no copy). Pₖ need
// not be definite (singular Q; barrier weights spread over 15 decades in the interior point):
// if its Cholesky fails, the x block is re-formed and left holding Pₖ itself, and stage k−1 uses
// Yt = [B A]ᵀPₖ and Yt·[B A] instead, so the statuses keep their classical meaning (only the
// Quu and M pivots can fail) and the pure square-root method's failure mode does not exist.
// (Continuing the left-looking panel sweep over the x columns instead measured ~8 % slower
// than one Schur product then an in-place Cholesky, at equal flops.)
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "controllers/qp/ocp_qp.h"
#include "controllers/qp/prefetch.h"
#include "controllers/qp/riccati_kernels.h"

namespace kuavo::qp {

// Row/column layout of a stage's factor storage: [u (NU, padded) ; ν (NC, padded) ; x (NX, padded)].
template <int NX, int NU, int NC>
struct RiccatiLayout {
  static constexpr int kUp = kernels::round_up4(NU);
  static constexpr int kNu = kUp;                        // first ν row
  static constexpr int kCp = kernels::round_up4(NC);
  static constexpr int kXo = kUp + kCp;                  // first x row
  static constexpr int kXp = kernels::round_up4(NX);
  static constexpr int kLd = kXo + kXp;                  // leading dimension (rows)
};

template <int NX, int NU, int NC, int NG>
struct RiccatiStage {
  using Layout = RiccatiLayout<NX, NU, NC>;
  // Lower triangle of L (see above), column-major, kLd × kLd. The x block holds the cost-to-go:
  // its Cholesky factor Lp (Pₖ = Lp·Lpᵀ, lower, zeros above the diagonal inside the 4×4
  // diagonal chunks, identity on the padding) when p_factored, otherwise Pₖ itself, both
  // triangles (semidefinite Pₖ: singular Q).
  alignas(64) std::array<double, Layout::kLd * Layout::kLd> L{};
  bool p_factored = false;
  Eigen::Matrix<double, NX, 1> p = Eigen::Matrix<double, NX, 1>::Zero();
  Eigen::Matrix<double, NU, 1> k0 = Eigen::Matrix<double, NU, 1>::Zero();   // Lu⁻¹ qu
  Eigen::Matrix<double, NC, 1> gm = Eigen::Matrix<double, NC, 1>::Zero();   // Lm⁻¹γ
  // Inverses of L's 4×4 diagonal blocks in the u and ν columns and their transposes
  // (kernels::invert_diag4; block b at 16·b), for the vector pass's triangular solves.
  alignas(32) std::array<double, 4 * (Layout::kUp + Layout::kCp)> dinv{};
  alignas(32) std::array<double, 4 * (Layout::kUp + Layout::kCp)> dinvT{};
  // The 4-row groups in which each column of B and A has a nonzero entry (kernels::transpose,
  // set by the matrix pass; NX ≤ 64): the backward vector recursion's and the forward
  // rollout's products fetch only those (the MPC's A is the identity but in 9 rows, its force
  // columns of B reach 6 rows).
  std::array<std::uint16_t, NU> b_groups{};
  std::array<std::uint16_t, NX> a_groups{};
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
  using Layout = RiccatiLayout<NX, NU, NC>;
  std::array<RiccatiStage<NX, NU, NC, NG>, N + 1> stage{};
  // [B A]ᵀ in the stage layout (ν rows and padding rows stay zero), and Yt = [B A]ᵀPₖ₊₁
  // (or Zᵀ = [B A]ᵀLp when Pₖ₊₁ is factored).
  alignas(64) std::array<double, Layout::kLd * NX> BAt{};
  alignas(64) std::array<double, Layout::kLd * NX> Yt{};
  // Per 4-row group of BAt: 1 + the last row in which the group's columns of [B A] are
  // nonzero (0: all zero). Zᵀ = [B A]ᵀLp is zero in the same columns (Lp is lower).
  std::array<int, Layout::kLd / 4> extent{};
  std::array<int, NU> last_b{};  // 1 + the last nonzero row of each column of B (kernels::transpose)
  std::array<int, NX> last_a{};  // and of A
  Eigen::Matrix<double, NG, NU> GuW = Eigen::Matrix<double, NG, NU>::Zero();  // √W Gu
  Eigen::Matrix<double, NG, NX> GxW = Eigen::Matrix<double, NG, NX>::Zero();  // √W Gx
  Eigen::Matrix<double, NX, 1> v = Eigen::Matrix<double, NX, 1>::Zero();
  Eigen::Matrix<double, NX, 1> lpt_v = Eigen::Matrix<double, NX, 1>::Zero();  // Lpᵀ·v
  Eigen::Matrix<double, NU, 1> qu = Eigen::Matrix<double, NU, 1>::Zero();
  Eigen::Matrix<double, NU, 1> t = Eigen::Matrix<double, NU, 1>::Zero();
  Eigen::Matrix<double, NC, 1> gamma = Eigen::Matrix<double, NC, 1>::Zero();
  // The next stage's lines, asked for while this one runs (prefetch.h).
  PrefetchPlan<320> prefetch;
};

namespace riccati_detail {

// Whether the matrix pass records B's and A's nonzero row groups (RiccatiStage::b_groups) for
// the forward rollout: the transpose's bit masks cover 64 rows.
template <int NX>
inline constexpr bool kRowGroups = NX <= 64;

// Stage equalities whose Cholesky pivots of M = D Quu⁻¹ Dᵀ spread by more than this ratio
// (condition number of M beyond 1e14, about 1/ε) are treated as dependent.
inline constexpr double kRankPivotRatio = 1e-7;

// The next stage's prefetch plan goes out in this many slices over a stage's steps.
inline constexpr int kPrefetchSlices = 8;

template <int NX, int NU, int NC>
using FactorMap = Eigen::Map<Eigen::Matrix<double, RiccatiLayout<NX, NU, NC>::kLd, RiccatiLayout<NX, NU, NC>::kLd>>;
template <int NX, int NU, int NC>
using ConstFactorMap =
    Eigen::Map<const Eigen::Matrix<double, RiccatiLayout<NX, NU, NC>::kLd, RiccatiLayout<NX, NU, NC>::kLd>>;

// Barrier term Gᵀ W G of the x block (x_only) or of the u and x-u blocks (!x_only), lower
// triangles. Sets the rows √W G it uses.
template <int NX, int NU, int NC, int NG>
void add_barrier_hessian(const OcpStage<NX, NU, NC, NG>& s, const RiccatiStage<NX, NU, NC, NG>& w,
                         Eigen::Matrix<double, NG, NU>& GuW, Eigen::Matrix<double, NG, NX>& GxW, bool x_only,
                         double* L) {
  if constexpr (NG > 0) {
    using Layout = RiccatiLayout<NX, NU, NC>;
    const int m = s.num_ineq;
    if (m == 0) return;
    FactorMap<NX, NU, NC> K(L);
    for (int i = 0; i < m; ++i) {
      const double sw = std::sqrt(w.w(i));
      if (x_only) {
        GxW.row(i) = sw * s.Gx.row(i);
      } else {
        GuW.row(i) = sw * s.Gu.row(i);
      }
    }
    if (x_only) {
      K.template block<NX, NX>(Layout::kXo, Layout::kXo).template selfadjointView<Eigen::Lower>().rankUpdate(
          GxW.topRows(m).transpose());
      return;
    }
    K.template topLeftCorner<NU, NU>().template selfadjointView<Eigen::Lower>().rankUpdate(
        GuW.topRows(m).transpose());
    K.template block<NX, NU>(Layout::kXo, 0).noalias() += GxW.topRows(m).transpose() * GuW.topRows(m);
  } else {
    (void)s, (void)w, (void)GuW, (void)GxW, (void)x_only, (void)L;
  }
}

// Structure of [B A] that the square-root products exploit (bit for bit the dense products:
// only exact zero terms at the end of each inner sum are skipped). A column of [B A] that is
// zero below row e gives a row of Zᵀ = [B A]ᵀLp that is zero from column e on, because Lp is
// lower triangular. The centroidal MPC's B has force columns with 6 nonzero rows (CoM velocity,
// momentum) of 38 and its A the joints' identity: ~20 % of the matrix pass's flops.
// From last_b, last_a (1 + each column's last nonzero row, from kernels::transpose): the
// extent of each 4-row group of BAt. Returns false if every column reaches the last row (dense
// [B A]: the caller keeps its whole-matrix products, whose constant inner extent the compiler
// specializes).
template <int NX, int NU, int NC>
bool column_extents(const int* last_b, const int* last_a, int* extent) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  for (int g = 0; g < Layout::kLd / 4; ++g) extent[g] = 0;
  for (int j = 0; j < NU; ++j) extent[j / 4] = std::max(extent[j / 4], last_b[j]);
  bool tails = false;
  for (int j = 0; j < NU; ++j) tails |= extent[j / 4] < NX;
  for (int j = 0; j < NX; ++j) {
    int& e = extent[(Layout::kXo + j) / 4];
    e = std::max(e, last_a[j]);
  }
  for (int j = 0; j < NX; ++j) tails |= extent[(Layout::kXo + j) / 4] < NX;
  return tails;
}

// A run of 4-row groups from row i (< m, relative to row0) that one product takes with one
// inner extent, the largest of the run's: rows [i, end), extent max_extent. A run grows while
// the groups' extents stay within kRunSlack of the first's, up to kRunRows rows, so the MPC's
// extents (a different one every 4 rows: a joint-velocity column reaches its joint's row)
// make 8–24-row tiles instead of 4-row ones, which have only 4 accumulators, half an FMA
// pipe's latency cover. The terms past a row's own extent are exact zeros (those entries of
// [B A]ᵀ and so of Zᵀ are zero), and adding a zero product never changes an accumulator that
// starts at +0 (it cannot become −0): bit for bit the per-extent products. A zero-extent
// group (no product) is a run of its own.
struct ExtentRun {
  int end;
  int max_extent;
};
inline constexpr int kRunSlack = 8;
inline constexpr int kRunRows = 24;
inline ExtentRun extent_run(const int* extent, int row0, int i, int m) {
  const int e = extent[(row0 + i) / 4];
  ExtentRun run{i + 4, e};
  if (e == 0) return run;
  while (run.end < m && run.end - i < kRunRows) {
    const int next = extent[(row0 + run.end) / 4];
    if (next == 0 || next > e + kRunSlack || next < e - kRunSlack) break;
    run.max_extent = std::max(run.max_extent, next);
    run.end += 4;
  }
  return run;
}

// C[rows i0…i1, columns j0…j1) = S there (Sᵀ for kSumT; rows past add.rows: zero): where a
// kSum (kSumT) product has no terms.
template <kernels::Update kSum>
void copy_addend(int i0, int i1, int j0, int j1, const kernels::Addend& add, double* C, int ldc) {
  for (int j = j0; j < j1; ++j) {
    for (int i = i0; i < i1; ++i) {
      if (i >= add.rows) {  // (add.s may be null: no addend, OcpStage::s_zero)
        C[i + j * ldc] = 0.0;
        continue;
      }
      C[i + j * ldc] = kSum == kernels::Update::kSumT ? add.s[j + i * add.ld] : add.s[i + j * add.ld];
    }
  }
}

// C[m×n] = S + Zᵀ_rows·(Zᵀ_cols)ᵀ (kSum; kSumT: Sᵀ + …, S from add), the rows of Zᵀ from row0,
// its columns' rows from col0 (multiples of 4), each 4-row strip against each run of row groups
// of equal extent over the shorter of the two extents; S copied where the extents leave no
// terms. kLower: C is a diagonal block (row0 == col0), only rows from each strip's diagonal on.
template <bool kLower, kernels::Update kSum = kernels::Update::kSum>
void add_product_by_extents(const int* extent, int row0, int m, int col0, int n, const double* Zt, int ld,
                            double* C, const kernels::Addend& add) {
  for (int j = 0; j < n; j += 4) {
    const int ej = extent[(col0 + j) / 4];
    const int nj = std::min(4, n - j);
    int i = kLower ? j : 0;
    if (ej == 0) {
      copy_addend<kSum>(i, m, j, j + nj, add, C, ld);
      continue;
    }
    while (i < m) {
      const ExtentRun run = extent_run(extent, row0, i, m);
      const int k = std::min(run.max_extent, ej);
      if (k > 0) {
        kernels::gemm<true, kSum>(run.end - i, nj, k, Zt + row0 + i, ld, Zt + col0 + j, ld, C + i + j * ld, ld,
                                  add.offset<kSum>(i, j));
      } else {
        copy_addend<kSum>(i, run.end, j, j + nj, add, C, ld);
      }
      i = run.end;
    }
  }
}

// Zᵀ[m×NX] = [B A]ᵀ(rows row0 … row0+m)·Lp, skipping what the extents make zero (those
// entries are set to zero).
template <int NX>
void zt_product_by_extents(const int* extent, int row0, int m, const double* BAt, const double* Lp, int ld,
                           double* Zt) {
  using kernels::gemm;
  using kernels::Update;
  for (int j = 0; j < NX; j += 4) {
    int i = 0;
    while (i < m) {
      const ExtentRun run = extent_run(extent, row0, i, m);
      const int k = std::max(0, run.max_extent - j);
      gemm<false, Update::kSet>(run.end - i, std::min(4, NX - j), k, BAt + row0 + i + j * ld, ld, Lp + j + j * ld,
                                ld, Zt + row0 + i + j * ld, ld);
      i = run.end;
    }
  }
}

// The lower triangle of a symmetric n×n S (column-major, lds) into D, each column from the
// first row of its 4×4 diagonal chunk (so the chunk's few entries above the diagonal are S's).
// Nothing reads the storage's upper triangle (beyond those chunks) in the u, ν and x blocks,
// and neither S's upper triangle (Q and R are symmetric, ocp_qp.h) nor D's are touched: at
// MPC size each stage's factor storage and data are touched once per factorization from
// beyond L2, and the upper triangles are ~40 % of R's and Q's cache lines and ~25 % of the
// storage's.
inline void copy_lower(int n, const double* S, int lds, double* D, int ldd) {
  for (int j = 0; j < n; ++j) {
    const double* s = S + j * lds;
    double* d = D + j * ldd;
    int i = j / 4 * 4;
#ifdef KUAVO_QP_KERNELS_SIMD
    for (; i + 4 <= n; i += 4) _mm256_storeu_pd(d + i, _mm256_loadu_pd(s + i));  // no memmove call per column
#endif
    for (; i < n; ++i) d[i] = s[i];
  }
}

// Q into the x block with its padding (zero rows, identity pivots), lower triangle (copy_lower).
// Without copy_q only the padding (Q then comes in as the addend of the x block's product).
template <int NX, int NU, int NC>
void load_x_block(const Eigen::Matrix<double, NX, NX>& Q, FactorMap<NX, NU, NC>& K, bool copy_q = true) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  constexpr int kXo = Layout::kXo, kXp = Layout::kXp;
  if (copy_q) copy_lower(NX, Q.data(), NX, K.data() + kXo * (Layout::kLd + 1), Layout::kLd);
  if constexpr (kXp > NX) {
    K.template block<kXp - NX, Layout::kLd>(kXo + NX, 0).setZero();
    for (int i = NX; i < kXp; ++i) K(kXo + i, kXo + i) = 1.0;
  }
}

// The stage's own blocks [R ·; D 0 ·; Sᵀ Cᵀ Q] into the lower triangle, with the padding
// (R and Q: copy_lower). Without cost_blocks R, S and Q are left out (the matrix pass adds them
// to [B A]ᵀPₖ₊₁[B A]'s u, x-u and x blocks as the products' addends, kernels::Update::kSum,
// kSumT).
template <int NX, int NU, int NC, int NG>
void load_stage(const OcpStage<NX, NU, NC, NG>& s, int ne_padded, FactorMap<NX, NU, NC>& K,
                bool cost_blocks = true) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  constexpr int kUp = Layout::kUp, kXo = Layout::kXo;
  if (cost_blocks) copy_lower(NU, s.R.data(), NU, K.data(), Layout::kLd);
  if constexpr (kUp > NU) {
    K.template block<kUp - NU, NU>(NU, 0).setZero();
    K.template block<kUp - NU, kUp - NU>(NU, NU).setIdentity();
    K.template block<Layout::kLd - kUp, kUp - NU>(kUp, NU).setZero();
  }
  if (cost_blocks) kernels::transpose(NU, NX, s.S.data(), NU, K.data() + kXo, Layout::kLd);
  load_x_block<NX, NU, NC>(s.Q, K, cost_blocks);
  if constexpr (NC > 0) {
    const int ne = s.num_eq;
    if (ne_padded == 0) return;
    K.block(kUp, 0, ne_padded, NU).setZero();
    K.block(kUp, 0, ne, NU) = s.D.topRows(ne);
    K.block(kUp, kUp, ne_padded, ne_padded).setZero();
    for (int i = ne; i < ne_padded; ++i) K(kUp + i, kUp + i) = -1.0;
    K.block(kXo, kUp, NX, ne_padded).setZero();
    kernels::transpose(ne, NX, s.C.data(), NC, K.data() + kXo + kUp * Layout::kLd, Layout::kLd);
  }
}

// Signed left-looking Cholesky of the u and ν columns (see the file comment), including their
// x rows. Returns kNotConvex / kRankDeficient / kSolved. With dinv, dinvT: also the inverses
// of the factored columns' 4×4 diagonal blocks (kernels::invert_diag4) for the vector pass.
template <int NX, int NU, int NC>
QpStatus factor_stage(double* L, int ne, int ne_padded, double* dinv = nullptr, double* dinvT = nullptr) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  using kernels::gemm;
  using kernels::Update;
  constexpr int kLd = Layout::kLd, kUp = Layout::kUp, kXo = Layout::kXo, kXp = Layout::kXp;
  const int row_end = kUp + ne_padded;  // u and used ν rows; then the x rows [kXo, kLd)
  for (int j = 0; j < row_end; j += 4) {
    const int ku = std::min(j, kUp), kc = j - ku;
    // Panel rows [j, row_end) and the x rows: − Σ_u L Lᵀ, + Σ_ν L Lᵀ of the columns before j.
    double* Pj = L + j * kLd;
    gemm<true, Update::kSub>(row_end - j, 4, ku, L + j, kLd, L + j, kLd, Pj + j, kLd);
    gemm<true, Update::kSub>(kXp, 4, ku, L + kXo, kLd, L + j, kLd, Pj + kXo, kLd);
    if (kc > 0) {
      gemm<true, Update::kAdd>(row_end - j, 4, kc, L + j + kUp * kLd, kLd, L + j + kUp * kLd, kLd, Pj + j, kLd);
      gemm<true, Update::kAdd>(kXp, 4, kc, L + kXo + kUp * kLd, kLd, L + j + kUp * kLd, kLd, Pj + kXo, kLd);
    }
    const bool input = j < kUp;
    if (!kernels::factor_panel4(L, kLd, j, row_end, kXo, kLd, input ? 1.0 : -1.0)) {
      return input ? QpStatus::kNotConvex : QpStatus::kRankDeficient;
    }
    // Padding pivots are identity (u) and −1 pivots (ν, factored as 1): whole 4×4 blocks.
    if (dinv != nullptr) kernels::invert_diag4(L, kLd, j, 4, dinv + 4 * j, dinvT + 4 * j);
  }
  if (ne > 0) {
    // Relative pivot test: D rows (nearly) dependent in the Quu⁻¹ metric.
    double min_pivot = std::numeric_limits<double>::infinity(), max_pivot = 0.0;
    for (int i = 0; i < ne; ++i) {
      const double d = L[(kUp + i) * (kLd + 1)];
      min_pivot = std::min(min_pivot, d);
      max_pivot = std::max(max_pivot, d);
    }
    if (!(min_pivot > kRankPivotRatio * max_pivot)) return QpStatus::kRankDeficient;
  }
  return QpStatus::kSolved;
}

// In-place Cholesky of the x block alone (the terminal stage: Pₜ = Q_T, no u or ν columns, whose
// storage may hold a longer horizon's stage). Returns false if not numerically definite.
template <int NX, int NU, int NC>
bool factor_x_block(double* L) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  constexpr int kLd = Layout::kLd, kXo = Layout::kXo, kXp = Layout::kXp;
  double* P = L + kXo * (kLd + 1);
  if (!kernels::cholesky(P, kLd, kXp)) return false;
  for (int j = 0; j < kXp; j += 4) {  // zeros above the diagonal where the triangular product reads
    for (int c = j + 1; c < j + 4; ++c) {
      for (int r = j; r < c; ++r) P[r + c * kLd] = 0.0;
    }
  }
  return true;
}

// The x block's Schur complement, lower triangle: H_xx − X Xᵀ + (Lm⁻¹G)ᵀ(Lm⁻¹G), from the
// factored u and ν columns.
template <int NX, int NU, int NC>
void subtract_schur_product(double* L, int ne_padded) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  using kernels::gemm;
  using kernels::Update;
  constexpr int kLd = Layout::kLd, kUp = Layout::kUp, kXo = Layout::kXo, kXp = Layout::kXp;
  double* P = L + kXo * (kLd + 1);
  gemm<true, Update::kSub, true>(kXp, NX, kUp, L + kXo, kLd, L + kXo, kLd, P, kLd);
  if (ne_padded > 0) {
    gemm<true, Update::kAdd, true>(kXp, NX, ne_padded, L + kXo + kUp * kLd, kLd, L + kXo + kUp * kLd, kLd, P, kLd);
  }
}

// The sweep continued over the x columns (d = +1): on return the x block's lower triangle is
// Lp with Pₖ = Lp·Lpᵀ = H_xx − X Xᵀ + (Lm⁻¹G)ᵀ(Lm⁻¹G), ready for the previous stage's
// triangular product. Returns false (x block clobbered) if Pₖ is not numerically definite.
template <int NX, int NU, int NC>
bool factor_cost_to_go(double* L, int ne_padded) {
  subtract_schur_product<NX, NU, NC>(L, ne_padded);
  return factor_x_block<NX, NU, NC>(L);
}

// The x block's upper triangle from its lower one.
template <int NX, int NU, int NC>
void symmetrize_x_block(double* L) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  constexpr int kLd = Layout::kLd;
  double* P = L + Layout::kXo * (kLd + 1);
  for (int j = 1; j < NX; ++j) {
    for (int i = 0; i < j; ++i) P[i + j * kLd] = P[j + i * kLd];
  }
}

// Fallback for a semidefinite Pₖ: the x block, re-formed as H_xx by the caller, becomes the
// Schur complement Pₖ itself, both triangles.
template <int NX, int NU, int NC>
void schur_cost_to_go(double* L, int ne_padded) {
  subtract_schur_product<NX, NU, NC>(L, ne_padded);
  symmetrize_x_block<NX, NU, NC>(L);
}

// Lower triangle of Q + [B A]ᵀPₖ₊₁[B A]'s x block into the x block of L (whose padding is set):
// ZᵀZ from Zᵀ in Yt when Pₖ₊₁ is factored, else Yt·A with Yt = [B A]ᵀPₖ₊₁ (A from At, its
// transpose in BAt's x rows, leading dimension kLd).
template <int NX, int NU, int NC>
void add_x_product(const double* Yt, const double* At, const int* extent, bool factored,
                   const Eigen::Matrix<double, NX, NX>& Q, double* L) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  using kernels::gemm;
  using kernels::Update;
  constexpr int kLd = Layout::kLd, kXo = Layout::kXo, kXp = Layout::kXp;
  const kernels::Addend q{Q.data(), NX, NX};
  double* P = L + kXo * (kLd + 1);
  if (factored && extent != nullptr) {
    add_product_by_extents<true>(extent, kXo, kXp, kXo, NX, Yt, kLd, P, q);
  } else if (factored) {
    gemm<true, Update::kSum, true>(kXp, NX, NX, Yt + kXo, kLd, Yt + kXo, kLd, P, kLd, q);
  } else {
    gemm<true, Update::kSum, true>(kXp, NX, NX, Yt + kXo, kLd, At, kLd, P, kLd, q);
  }
}

// out += Pₖ·v, from Lp (Pₖ = Lp·Lpᵀ) or from Pₖ itself. tmp: NX scratch.
template <int NX, int NU, int NC, int NG>
void add_cost_to_go_product(const RiccatiStage<NX, NU, NC, NG>& w, const Eigen::Matrix<double, NX, 1>& v,
                            Eigen::Matrix<double, NX, 1>& out, Eigen::Matrix<double, NX, 1>& tmp) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  const double* X = w.L.data() + Layout::kXo * (Layout::kLd + 1);
  if (w.p_factored) {
    kernels::trmv_lower_trans(NX, X, Layout::kLd, v.data(), tmp.data());
    kernels::trmv_lower_add(NX, X, Layout::kLd, tmp.data(), out.data());
  } else {
    kernels::gemv_n<kernels::Update::kAdd>(NX, NX, X, Layout::kLd, v.data(), out.data());
  }
}

// The vector pass's backward recursion at the terminal stage: p_T = q_T + G_xᵀρ_T.
template <int NX, int NU, int N, int NC, int NG>
void backward_vector_terminal(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                              const RiccatiVectors<NX, NU, N, NC>& vec) {
  const int T = qp.horizon;
  const auto& s = qp.stages[T];
  auto& w = ws.stage[T];
  w.p = vec.q[T];
  if constexpr (NG > 0) {
    if (s.num_ineq > 0) w.p.noalias() += s.Gx.topRows(s.num_ineq).transpose() * w.rho.head(s.num_ineq);
  }
}

// One stage k < T of the backward recursion (stage k factored, stage k+1's p set): p_k, k0_k, gm_k.
template <int NX, int NU, int N, int NC, int NG>
void backward_vector_stage(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                           const RiccatiVectors<NX, NU, N, NC>& vec, int k) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  using kernels::Update;
  constexpr int kLd = Layout::kLd, kUp = Layout::kUp, kXo = Layout::kXo;
  const auto& s = qp.stages[k];
  auto& w = ws.stage[k];
  const double* L = w.L.data();
  ws.v = ws.stage[k + 1].p;
  add_cost_to_go_product(ws.stage[k + 1], vec.b[k], ws.v, ws.lpt_v);
  ws.qu = vec.r[k];
  w.p = vec.q[k];
  if constexpr (kRowGroups<NX>) {  // over the nonzero row groups (the matrix pass's): bit for bit
    kernels::gemv_t_groups<Update::kAdd>(NX, NU, s.B.data(), NX, ws.v.data(), ws.qu.data(), w.b_groups.data());
    kernels::gemv_t_groups<Update::kAdd>(NX, NX, s.A.data(), NX, ws.v.data(), w.p.data(), w.a_groups.data());
  } else {
    kernels::gemv_t<Update::kAdd>(NX, NU, s.B.data(), NX, ws.v.data(), ws.qu.data());
    kernels::gemv_t<Update::kAdd>(NX, NX, s.A.data(), NX, ws.v.data(), w.p.data());
  }
  if constexpr (NG > 0) {
    const int m = s.num_ineq;
    if (m > 0) {
      ws.qu.noalias() += s.Gu.topRows(m).transpose() * w.rho.head(m);
      w.p.noalias() += s.Gx.topRows(m).transpose() * w.rho.head(m);
    }
  }
  w.k0 = ws.qu;
  kernels::trsv_lower(NU, L, kLd, w.dinv.data(), w.k0.data());                         // Lu⁻¹qu
  kernels::gemv_n<Update::kSub>(NX, NU, L + kXo, kLd, w.k0.data(), w.p.data());        // − X k0
  if constexpr (NC > 0) {
    const int ne = s.num_eq;
    if (ne > 0) {
      double* gm = w.gm.data();
      for (int i = 0; i < ne; ++i) gm[i] = -vec.e[k](i);
      kernels::gemv_n<Update::kSub>(ne, NU, L + kUp, kLd, w.k0.data(), gm);             // − Yᵀk0
      kernels::trsv_lower(ne, L + kUp * (kLd + 1), kLd, w.dinv.data() + 4 * kUp, gm);
      kernels::gemv_n<Update::kSub>(NX, ne, L + kXo + kUp * kLd, kLd, gm, w.p.data());  // + (Lm⁻¹G)ᵀ gm
    }
  }
}

// The lines stage k's matrix pass (and its backward vector step) will touch, in about the
// order it touches them. Written: its factor storage's lower triangle (from each column's 4×4
// diagonal chunk; the ν block whole) and diagonal-block inverses. Read: R (its leading r_dense
// block and diagonal), S (unless s_zero), Q's lower triangle, B's and A's columns over their
// declared row groups (all rows when none are declared), C and D (with equalities) and the
// stage's vectors. Not the inequality rows Gx, Gu (the MPC has none).
template <int NX, int NU, int N, int NC, int NG>
void plan_factor_prefetch(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                          const RiccatiVectors<NX, NU, N, NC>* vec, int k) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  constexpr int kLd = Layout::kLd;
  auto& plan = ws.prefetch;
  plan.clear();
  const auto& s = qp.stages[k];
  const auto& w = ws.stage[k];
  for (int j = 0; j < kLd; ++j) {  // the ν block is written whole (load_stage)
    const int row0 = j >= Layout::kUp && j < Layout::kXo ? Layout::kUp : j / 4 * 4;
    plan.add_column(w.L.data(), kLd, j, row0, kLd, true);
  }
  plan.add(w.dinv.data(), sizeof(w.dinv), true);
  plan.add(w.dinvT.data(), sizeof(w.dinvT), true);
  const int r_rows = std::clamp(s.r_dense, 0, NU);
  for (int j = 0; j < NU; ++j) {
    plan.add_column(s.R.data(), NU, j, j < r_rows ? j / 4 * 4 : j, j < r_rows ? r_rows : j + 1, false);
  }
  if (!s.s_zero) plan.add(s.S.data(), sizeof(s.S), false);
  for (int j = 0; j < NX; ++j) plan.add_column(s.Q.data(), NX, j, j / 4 * 4, NX, false);
  for (int j = 0; j < NU + NX; ++j) {
    const bool b = j < NU;
    const int col = b ? j : j - NU, cols = b ? NU : NX;
    const double* m = b ? s.B.data() : s.A.data();
    if (!kRowGroups<NX> || !qp.ab_groups_declared) {
      plan.add_column(m, NX, col, 0, NX, false);
      continue;
    }
    // The transpose reads a whole 4-column step over the union of its columns' groups.
    const auto groups_of = [&](int c) -> unsigned { return b ? qp.b_groups[c] : qp.a_groups[c]; };
    const int step = col / 4 * 4;
    unsigned groups = groups_of(col);  // bit g: rows [4g, 4g + 4)
    if (step + 4 <= cols) groups = groups_of(step) | groups_of(step + 1) | groups_of(step + 2) | groups_of(step + 3);
    if (groups == 0) continue;
    const int lo = 4 * __builtin_ctz(groups), hi = std::min(NX, 4 * (32 - __builtin_clz(groups)));
    plan.add_column(m, NX, col, lo, hi, false);
  }
  if constexpr (NC > 0) {
    if (s.num_eq > 0) {
      plan.add(s.C.data(), sizeof(s.C), false);
      plan.add(s.D.data(), sizeof(s.D), false);
    }
  }
  if (vec != nullptr) {
    plan.add(vec->b[k].data(), sizeof(vec->b[k]), false);
    plan.add(vec->q[k].data(), sizeof(vec->q[k]), false);
    plan.add(vec->r[k].data(), sizeof(vec->r[k]), false);
    if constexpr (NC > 0) plan.add(vec->e[k].data(), sizeof(vec->e[k]), false);
  }
}

// The matrix pass; with vec, also the vector pass's backward recursion, stage by stage right
// after each stage's factorization while its factor, Pₖ₊₁ and [B A] are still in cache (at MPC
// size the horizon's data lives beyond L2, and the separate backward pass reads it all again).
template <int NX, int NU, int N, int NC, int NG>
QpStatus factor_pass(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                     const RiccatiVectors<NX, NU, N, NC>* vec) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  using kernels::gemm;
  using kernels::Update;
  constexpr int kLd = Layout::kLd, kUp = Layout::kUp, kXo = Layout::kXo, kXp = Layout::kXp;
  constexpr bool kGroups = kRowGroups<NX>;
  const int T = qp.horizon;
  {
    auto& wT = ws.stage[T];
    double* L = wT.L.data();
    FactorMap<NX, NU, NC> K(L);
    load_x_block<NX, NU, NC>(qp.stages[T].Q, K);
    add_barrier_hessian(qp.stages[T], wT, ws.GuW, ws.GxW, true, L);
    wT.p_factored = factor_x_block<NX, NU, NC>(L);
    if (!wT.p_factored) {
      load_x_block<NX, NU, NC>(qp.stages[T].Q, K);
      add_barrier_hessian(qp.stages[T], wT, ws.GuW, ws.GxW, true, L);
      symmetrize_x_block<NX, NU, NC>(L);
    }
    if (vec != nullptr) backward_vector_terminal(qp, ws, *vec);
  }
  for (int k = T - 1; k >= 0; --k) {
    const auto& s = qp.stages[k];
    auto& w = ws.stage[k];
    double* L = w.L.data();
    const int ne = NC > 0 ? s.num_eq : 0;
    const int ne_padded = kernels::round_up4(ne);
    FactorMap<NX, NU, NC> K(L);
    // Stage k − 1's lines, a slice after each of this stage's steps (prefetch.h).
    if (k > 0) plan_factor_prefetch(qp, ws, vec, k - 1); else ws.prefetch.clear();
    const int slice = (ws.prefetch.lines() + kPrefetchSlices - 1) / kPrefetchSlices;
    load_stage(s, ne_padded, K, false);  // R, S, Q: the addends of the products below
    ws.prefetch.issue(slice);

    if (kGroups && qp.ab_groups_declared) {  // reads only the declared groups (ocp_qp.h)
      kernels::transpose_declared(NX, NU, s.B.data(), NX, ws.BAt.data(), kLd, ws.last_b.data(), w.b_groups.data(),
                                  qp.b_groups.data());
      kernels::transpose_declared(NX, NX, s.A.data(), NX, ws.BAt.data() + kXo, kLd, ws.last_a.data(),
                                  w.a_groups.data(), qp.a_groups.data());
    } else {
      kernels::transpose(NX, NU, s.B.data(), NX, ws.BAt.data(), kLd, ws.last_b.data(),
                         kGroups ? w.b_groups.data() : nullptr);
      kernels::transpose(NX, NX, s.A.data(), NX, ws.BAt.data() + kXo, kLd, ws.last_a.data(),
                         kGroups ? w.a_groups.data() : nullptr);
    }
    ws.prefetch.issue(slice);
    double* Yt = ws.Yt.data();
    const auto& next = ws.stage[k + 1];
    const double* P_next = next.L.data() + kXo * (kLd + 1);  // Lp or P
    const int* extent = nullptr;  // set if [B A] has zero tails and Pₖ₊₁ is factored
    // u block: R + [B A]ᵀPₖ₊₁[B A]; R's rows past r_dense read as zero, its diagonal there
    // added after the product (p + R is R + p, and 0 + p is p: no product is −0).
    const int r_rows = std::clamp(s.r_dense, 0, NU);
    const kernels::Addend r{s.R.data(), NU, r_rows};
    // x-u block: Sᵀ + …; with s_zero no addend (reads as zero, and 0 + product is the
    // product: the tiles' sums start at +0, so no product is −0).
    const kernels::Addend st = s.s_zero ? kernels::Addend{} : kernels::Addend{s.S.data(), NU, NX};
    if (next.p_factored) {
      // Zᵀ = [B A]ᵀLp (u and x rows), then the lower triangle of ZᵀZ (over the extents).
      if (column_extents<NX, NU, NC>(ws.last_b.data(), ws.last_a.data(), ws.extent.data())) {
        extent = ws.extent.data();
        zt_product_by_extents<NX>(extent, 0, kUp, ws.BAt.data(), P_next, kLd, Yt);
        ws.prefetch.issue(slice);
        zt_product_by_extents<NX>(extent, kXo, kXp, ws.BAt.data(), P_next, kLd, Yt);
        ws.prefetch.issue(slice);
        add_product_by_extents<true>(extent, 0, kUp, 0, NU, Yt, kLd, L, r);
        ws.prefetch.issue(slice);
        add_product_by_extents<false, Update::kSumT>(extent, kXo, kXp, 0, NU, Yt, kLd, L + kXo, st);
      } else {
        kernels::trmm_right_lower(kUp, NX, ws.BAt.data(), kLd, P_next, kLd, Yt, kLd);
        kernels::trmm_right_lower(kXp, NX, ws.BAt.data() + kXo, kLd, P_next, kLd, Yt + kXo, kLd);
        gemm<true, Update::kSum, true>(kUp, NU, NX, Yt, kLd, Yt, kLd, L, kLd, r);
        gemm<true, Update::kSumT>(kXp, NU, NX, Yt + kXo, kLd, Yt, kLd, L + kXo, kLd, st);
      }
    } else {
      // Yt = [B A]ᵀPₖ₊₁ (u and x rows), then the lower triangle of Yt·[B A].
      gemm<false, Update::kSet>(kUp, NX, NX, ws.BAt.data(), kLd, P_next, kLd, Yt, kLd);
      gemm<false, Update::kSet>(kXp, NX, NX, ws.BAt.data() + kXo, kLd, P_next, kLd, Yt + kXo, kLd);
      // [B A] from BAt (as op(B) = BAtᵀ: the same entries in the same order as from B and A,
      // and the rows OcpQp::ab_groups_declared leaves unread are zero there).
      gemm<true, Update::kSum, true>(kUp, NU, NX, Yt, kLd, ws.BAt.data(), kLd, L, kLd, r);
      gemm<true, Update::kSumT>(kXp, NU, NX, Yt + kXo, kLd, ws.BAt.data(), kLd, L + kXo, kLd, st);
    }
    for (int j = r_rows; j < NU; ++j) L[j * (kLd + 1)] += s.R(j, j);
    ws.prefetch.issue(slice);
    add_x_product<NX, NU, NC>(Yt, ws.BAt.data() + kXo, extent, next.p_factored, s.Q, L);
    add_barrier_hessian(s, w, ws.GuW, ws.GxW, true, L);
    add_barrier_hessian(s, w, ws.GuW, ws.GxW, false, L);
    ws.prefetch.issue(slice);

    const QpStatus f = factor_stage<NX, NU, NC>(L, ne, ne_padded, w.dinv.data(), w.dinvT.data());
    if (f != QpStatus::kSolved) return f;
    ws.prefetch.issue(slice);
    w.p_factored = factor_cost_to_go<NX, NU, NC>(L, ne_padded);
    if (!w.p_factored) {
      load_x_block<NX, NU, NC>(s.Q, K, false);
      add_x_product<NX, NU, NC>(Yt, ws.BAt.data() + kXo, extent, next.p_factored, s.Q, L);
      add_barrier_hessian(s, w, ws.GuW, ws.GxW, true, L);
      schur_cost_to_go<NX, NU, NC>(L, ne_padded);
    }
    ws.prefetch.issue(slice);
    if (vec != nullptr) backward_vector_stage(qp, ws, *vec, k);
    ws.prefetch.finish();
  }
  return QpStatus::kSolved;
}

// The forward rollout from the backward recursion's p, k0, gm: x, u, nu and (with costate)
// the costates of sol.
template <int NX, int NU, int N, int NC, int NG>
void forward_pass(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                  const RiccatiVectors<NX, NU, N, NC>& vec, OcpSolution<NX, NU, N, NC, NG>& sol,
                  bool costate = true) {
  using Layout = RiccatiLayout<NX, NU, NC>;
  using kernels::Update;
  constexpr int kLd = Layout::kLd, kUp = Layout::kUp, kXo = Layout::kXo;
  constexpr bool kGroups = kRowGroups<NX>;
  const int T = qp.horizon;
  sol.x[0] = vec.x_initial;
  for (int k = 0; k < T; ++k) {
    const auto& s = qp.stages[k];
    const auto& w = ws.stage[k];
    const double* L = w.L.data();
    if (costate) {
      sol.costate[k] = w.p;  // πₖ = pₖ + Pₖxₖ, while stage k's storage is in cache
      add_cost_to_go_product(w, sol.x[k], sol.costate[k], ws.lpt_v);
    }
    ws.t = w.k0;
    kernels::gemv_t<Update::kAdd>(NX, NU, L + kXo, kLd, sol.x[k].data(), ws.t.data());   // + Xᵀx
    if constexpr (NC > 0) {
      sol.nu[k].setZero();
      const int ne = s.num_eq;
      if (ne > 0) {
        double* nu = sol.nu[k].data();
        for (int i = 0; i < ne; ++i) nu[i] = w.gm(i);
        kernels::gemv_t<Update::kSub>(NX, ne, L + kXo + kUp * kLd, kLd, sol.x[k].data(), nu);
        kernels::trsv_lower_trans(ne, L + kUp * (kLd + 1), kLd, w.dinvT.data() + 4 * kUp, nu);
        kernels::gemv_t<Update::kAdd>(ne, NU, L + kUp, kLd, nu, ws.t.data());
      }
    }
    sol.u[k] = -ws.t;
    kernels::trsv_lower_trans(NU, L, kLd, w.dinvT.data(), sol.u[k].data());
    sol.x[k + 1] = vec.b[k];
    if constexpr (kGroups) {  // bit for bit the dense products, over the nonzero row groups
      kernels::gemv_n_groups(NX, NX, s.A.data(), NX, sol.x[k].data(), sol.x[k + 1].data(), w.a_groups.data());
      kernels::gemv_n_groups(NX, NU, s.B.data(), NX, sol.u[k].data(), sol.x[k + 1].data(), w.b_groups.data());
    } else {
      kernels::gemv_n<Update::kAdd>(NX, NX, s.A.data(), NX, sol.x[k].data(), sol.x[k + 1].data());
      kernels::gemv_n<Update::kAdd>(NX, NU, s.B.data(), NX, sol.u[k].data(), sol.x[k + 1].data());
    }
  }
  if (costate) {
    sol.costate[T] = ws.stage[T].p;
    add_cost_to_go_product(ws.stage[T], sol.x[T], sol.costate[T], ws.lpt_v);
  }
  if constexpr (NC > 0) sol.nu[T].setZero();
  sol.u[T].setZero();
}

}  // namespace riccati_detail

// Matrix pass over stages T … 0. Reads the barrier weights ws.stage[k].w. Returns kSolved,
// kNotConvex (a Quu not positive definite) or kRankDeficient (a Dₖ). Pₖ itself may be
// semidefinite (then it is kept unfactored and the previous stage takes the general product).
template <int NX, int NU, int N, int NC, int NG>
QpStatus riccati_factor(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws) {
  return riccati_detail::factor_pass(qp, ws, static_cast<const RiccatiVectors<NX, NU, N, NC>*>(nullptr));
}

// Vector pass and forward rollout: writes x, u, costate, nu of sol for the factorization in ws,
// the vectors vec and the barrier linear terms Gᵀρ (ρ in ws.stage[k].rho).
template <int NX, int NU, int N, int NC, int NG>
void riccati_solve(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                   const RiccatiVectors<NX, NU, N, NC>& vec, OcpSolution<NX, NU, N, NC, NG>& sol) {
  riccati_detail::backward_vector_terminal(qp, ws, vec);
  for (int k = qp.horizon - 1; k >= 0; --k) riccati_detail::backward_vector_stage(qp, ws, vec, k);
  riccati_detail::forward_pass(qp, ws, vec, sol);
}

// riccati_factor then riccati_solve in one sweep, with the same arithmetic (bit for bit): the
// backward vector recursion runs inside the matrix pass (see factor_pass). For one solve per
// factorization (the equality-only LQ problem, the MPC's real-time iteration). sol is written
// only on kSolved. Without costate sol.costate is not written: the rollout then does not read
// the cost-to-go factors (Pₖxₖ), ~15 % of its reads at MPC size.
template <int NX, int NU, int N, int NC, int NG>
QpStatus riccati_factor_solve(const OcpQp<NX, NU, N, NC, NG>& qp, RiccatiWorkspace<NX, NU, N, NC, NG>& ws,
                              const RiccatiVectors<NX, NU, N, NC>& vec, OcpSolution<NX, NU, N, NC, NG>& sol,
                              bool costate = true) {
  const QpStatus f = riccati_detail::factor_pass(qp, ws, &vec);
  if (f == QpStatus::kSolved) riccati_detail::forward_pass(qp, ws, vec, sol, costate);
  return f;
}

}  // namespace kuavo::qp
