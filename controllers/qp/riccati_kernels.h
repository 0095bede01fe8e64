// Register-blocked FMA kernels for the Riccati recursion's matrix pass (riccati.h).
//
// Why our own: at the Riccati's sizes (inner dimensions 38–90, blocks ≤ ~130 rows) Eigen's
// generic GEMM and LLT spend their time packing operands and reach 6–25 Gflop/s. Here an 8×4
// (or 4×4) tile of C lives in 8 AVX2 registers for the whole inner loop, A's columns stream
// from L1/L2 and B's entries are broadcast: two loads and four broadcasts feed eight FMAs, so
// the loop is FMA-bound. Everything is in place, no packing, no heap.
//
// Layout: column-major with the caller's leading dimensions. Row extents m must be multiples
// of 4 (the caller pads its storage with zero rows); column extents n and inner extents k are
// arbitrary. Without AVX2/FMA (another -march) the same functions run as plain loops.
//
// AVX-512 targets (__AVX512F__, e.g. -DKUAVO_ARCH=x86-64-v4: development machines, not the
// robot's i9-13900H, which stays on the AVX2 path) widen the tiles to zmm registers, where a
// 512-bit FMA does twice a ymm FMA's work at the same throughput: up to 24 (or 28) rows × 4
// columns per tile. Each entry of C still sums its k products one FMA at a time in order p =
// 0…k−1 and is then stored with the same (=, +=, −=), so the products are bit for bit those
// of the AVX2 kernels. The rest stays on the AVX2 code: zmm versions of the vector pass
// (gemv_n/gemv_t) and of factor_panel4's row updates measured no faster (N = 60, nx = 38,
// nu = 50: solve 292 vs 307 µs, factor 1.27 vs 1.27 ms, min CPU time).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#if (defined(__AVX2__) && defined(__FMA__)) || defined(__BMI2__)
#include <immintrin.h>
#endif
#if defined(__AVX2__) && defined(__FMA__)
#define KUAVO_QP_KERNELS_SIMD 1
#if defined(__AVX512F__)
#define KUAVO_QP_KERNELS_AVX512 1
#endif
#endif

namespace kuavo::qp::kernels {

// Unrolls a tile's loops over its register vectors and columns (a handful, compile-time
// bounds) before GCC decides where the accumulator arrays live. Without it GCC 12 kept the
// AVX2 tiles' acc[][] in registers *and* stored all eight to the stack on every inner iteration
// in some instantiations (out-of-line copies with run-time k, lda, ldb): eight 32-byte stores
// per eight FMAs, the ZᵀZ products at 22 instead of 38 Gflop/s and the MPC-size factorization
// 2.13 → 1.60 ms. Same instructions otherwise, so bit for bit.
#define KUAVO_UNROLL _Pragma("GCC unroll 8")


// What a product does with C. kSum: C = S + product, S a separate matrix (Addend), so a stage's
// own blocks (R, Q) need not be copied into the factor storage first: each tile reads its part
// of S in its epilogue, where the out-of-order core overlaps S's first touch (at MPC size from
// beyond L2) with the next tile's FMAs. The sum is the one kAdd forms on a copy, bit for bit.
// kSumT: C = Sᵀ + product (the x-u block's Sᵀ from the stage's S), each 4×4 block of Sᵀ
// transposed in registers.
enum class Update { kSet, kAdd, kSub, kSum, kSumT };

// S of a kSum (kSumT) product: column-major, leading dimension ld; C's rows [0, rows) are S's
// rows (columns) there. C's rows past them read as zero, through masked loads, so nothing
// beyond S's column (row) is read.
struct Addend {
  const double* s = nullptr;
  int ld = 0;
  int rows = 0;
  // The addend of C's block from (i, j): S(i, j) on, or Sᵀ(i, j) = S(j, i) for kSumT.
  template <Update kUpdate>
  Addend offset(int i, int j) const {
    if (s == nullptr) return {};
    return {kUpdate == Update::kSumT ? s + j + i * ld : s + i + j * ld, ld, rows - i};
  }
};

constexpr int round_up4(int n) { return (n + 3) / 4 * 4; }

// op(B)(p, j) for an NN product (B is k×n) or an NT product (B is n×k, C ±= A·Bᵀ).
template <bool kTransB>
inline const double* b_entry(const double* B, int ldb, int p, int j) {
  return kTransB ? B + j + p * ldb : B + p + j * ldb;
}

#ifdef KUAVO_QP_KERNELS_SIMD
// Lanes [0, r) of a 4-lane mask, r = 1…4.
inline __m256i row_mask(int r) {
  return _mm256_cmpgt_epi64(_mm256_set1_epi64x(r), _mm256_setr_epi64x(0, 1, 2, 3));
}

// The 4 rows of S at s whose row index, counted from s, is below rows; zero beyond.
inline __m256d addend_ymm(const double* s, int rows) {
  if (rows >= 4) return _mm256_loadu_pd(s);
  if (rows <= 0) return _mm256_setzero_pd();
  return _mm256_maskload_pd(s, row_mask(rows));
}

// Rows [0, 4) of Sᵀ's columns [0, nr) (nr = 1…4) from S at s (S's rows [0, nr), columns [0, 4)
// with leading dimension ld; columns from rows on, and S's rows past nr, read as zero): t[c] is
// Sᵀ's column c, i.e. S's row c.
inline void addend_t4(const double* s, int ld, int rows, int nr, __m256d t[4]) {
  __m256d q[4];
  const __m256i cols = row_mask(nr);
  for (int r = 0; r < 4; ++r) {
    q[r] = r >= rows ? _mm256_setzero_pd() : nr == 4 ? _mm256_loadu_pd(s + r * ld) : _mm256_maskload_pd(s + r * ld, cols);
  }
  const __m256d t0 = _mm256_unpacklo_pd(q[0], q[1]), t1 = _mm256_unpackhi_pd(q[0], q[1]);
  const __m256d t2 = _mm256_unpacklo_pd(q[2], q[3]), t3 = _mm256_unpackhi_pd(q[2], q[3]);
  t[0] = _mm256_permute2f128_pd(t0, t2, 0x20);
  t[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
  t[2] = _mm256_permute2f128_pd(t0, t2, 0x31);
  t[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
}

// C (=, +=, −=) x, or C = S + x (kSum, S's rows below rows) for one 4-row vector of C's column.
template <Update kUpdate>
inline void update_ymm(double* c, __m256d x, const double* s = nullptr, int rows = 0) {
  if constexpr (kUpdate == Update::kSum) {
    _mm256_storeu_pd(c, _mm256_add_pd(addend_ymm(s, rows), x));
  } else if constexpr (kUpdate == Update::kSet) {
    _mm256_storeu_pd(c, x);
  } else if constexpr (kUpdate == Update::kAdd) {
    _mm256_storeu_pd(c, _mm256_add_pd(_mm256_loadu_pd(c), x));
  } else {
    _mm256_storeu_pd(c, _mm256_sub_pd(_mm256_loadu_pd(c), x));
  }
}
#endif

// One MR×NR tile of C (MR = 4 or 8, NR = 1…4) over the inner extent k.
template <int MR, int NR, bool kTransB, Update kUpdate>
inline void tile(int k, const double* A, int lda, const double* B, int ldb, double* C, int ldc, Addend add = {}) {
  static_assert(MR == 4 || MR == 8, "tile rows");
  static_assert(NR >= 1 && NR <= 4, "tile columns");
#ifdef KUAVO_QP_KERNELS_SIMD
  constexpr int MV = MR / 4;
  __m256d acc[MV][NR];
  KUAVO_UNROLL
  for (int v = 0; v < MV; ++v) {
    KUAVO_UNROLL
    for (int j = 0; j < NR; ++j) acc[v][j] = _mm256_setzero_pd();
  }
  for (int p = 0; p < k; ++p) {
    __m256d a[MV];
    KUAVO_UNROLL
    for (int v = 0; v < MV; ++v) a[v] = _mm256_loadu_pd(A + p * lda + 4 * v);
    KUAVO_UNROLL
    for (int j = 0; j < NR; ++j) {
      const __m256d b = _mm256_broadcast_sd(b_entry<kTransB>(B, ldb, p, j));
      KUAVO_UNROLL
      for (int v = 0; v < MV; ++v) acc[v][j] = _mm256_fmadd_pd(a[v], b, acc[v][j]);
    }
  }
  if constexpr (kUpdate == Update::kSumT) {
    KUAVO_UNROLL
    for (int v = 0; v < MV; ++v) {
      __m256d t[4];
      addend_t4(add.s + 4 * v * add.ld, add.ld, add.rows - 4 * v, NR, t);
      KUAVO_UNROLL
      for (int j = 0; j < NR; ++j) _mm256_storeu_pd(C + j * ldc + 4 * v, _mm256_add_pd(t[j], acc[v][j]));
    }
  } else if constexpr (kUpdate == Update::kSum) {
    KUAVO_UNROLL
    for (int j = 0; j < NR; ++j) {
      KUAVO_UNROLL
      for (int v = 0; v < MV; ++v) {
        update_ymm<kUpdate>(C + j * ldc + 4 * v, acc[v][j], add.s + j * add.ld + 4 * v, add.rows - 4 * v);
      }
    }
  } else {
    KUAVO_UNROLL
    for (int j = 0; j < NR; ++j) {
      KUAVO_UNROLL
      for (int v = 0; v < MV; ++v) update_ymm<kUpdate>(C + j * ldc + 4 * v, acc[v][j]);
    }
  }
#else
  double acc[MR][NR] = {};
  for (int p = 0; p < k; ++p) {
    for (int j = 0; j < NR; ++j) {
      const double b = *b_entry<kTransB>(B, ldb, p, j);
      for (int i = 0; i < MR; ++i) acc[i][j] += A[p * lda + i] * b;
    }
  }
  for (int j = 0; j < NR; ++j) {
    for (int i = 0; i < MR; ++i) {
      double& c = C[j * ldc + i];
      if constexpr (kUpdate == Update::kSum) c = (i < add.rows ? add.s[j * add.ld + i] : 0.0) + acc[i][j];
      else if constexpr (kUpdate == Update::kSumT) c = (i < add.rows ? add.s[j + i * add.ld] : 0.0) + acc[i][j];
      else if constexpr (kUpdate == Update::kSet) c = acc[i][j];
      else if constexpr (kUpdate == Update::kAdd) c += acc[i][j];
      else c -= acc[i][j];
    }
  }
#endif
}

#ifdef KUAVO_QP_KERNELS_AVX512
// C (=, +=, −=) x, or C = S + x (kSum, S's rows below rows) for one 8-row vector of C's column.
template <Update kUpdate>
inline void update_zmm(double* c, __m512d x, const double* s = nullptr, int rows = 0) {
  if constexpr (kUpdate == Update::kSum) {
    const __m512d a = rows >= 8 ? _mm512_loadu_pd(s)
                                : _mm512_maskz_loadu_pd(static_cast<__mmask8>((1u << std::max(rows, 0)) - 1u), s);
    _mm512_storeu_pd(c, _mm512_add_pd(a, x));
  } else if constexpr (kUpdate == Update::kSet) {
    _mm512_storeu_pd(c, x);
  } else if constexpr (kUpdate == Update::kAdd) {
    _mm512_storeu_pd(c, _mm512_add_pd(_mm512_loadu_pd(c), x));
  } else {
    _mm512_storeu_pd(c, _mm512_sub_pd(_mm512_loadu_pd(c), x));
  }
}

// One (8·MZ + 4·kHalf)×NR tile of C: MZ zmm vectors of 8 rows, plus one ymm vector of 4 rows
// when kHalf (row counts are multiples of 4; the ymm half takes the low lane of the same
// broadcast). Per inner index MZ (+1) loads of A and NR broadcasts of B feed up to 16
// independent accumulators, enough to keep two 512-bit FMA pipes busy through their latency.
template <int MZ, bool kHalf, int NR, bool kTransB, Update kUpdate>
inline void tile_zmm(int k, const double* A, int lda, const double* B, int ldb, double* C, int ldc, Addend add = {}) {
  static_assert(MZ >= 1 && MZ <= 3, "tile zmm vectors");
  static_assert(NR >= 1 && NR <= 4, "tile columns");
  __m512d acc[MZ][NR];
  [[maybe_unused]] __m256d acc_h[NR];
  KUAVO_UNROLL
  for (int j = 0; j < NR; ++j) {
    KUAVO_UNROLL
    for (int v = 0; v < MZ; ++v) acc[v][j] = _mm512_setzero_pd();
    acc_h[j] = _mm256_setzero_pd();
  }
  for (int p = 0; p < k; ++p) {
    const double* Ap = A + p * lda;
    __m512d a[MZ];
    KUAVO_UNROLL
    for (int v = 0; v < MZ; ++v) a[v] = _mm512_loadu_pd(Ap + 8 * v);
    [[maybe_unused]] __m256d a_h;
    if constexpr (kHalf) a_h = _mm256_loadu_pd(Ap + 8 * MZ);
    KUAVO_UNROLL
    for (int j = 0; j < NR; ++j) {
      const __m512d b = _mm512_set1_pd(*b_entry<kTransB>(B, ldb, p, j));
      KUAVO_UNROLL
      for (int v = 0; v < MZ; ++v) acc[v][j] = _mm512_fmadd_pd(a[v], b, acc[v][j]);
      if constexpr (kHalf) acc_h[j] = _mm256_fmadd_pd(a_h, _mm512_castpd512_pd256(b), acc_h[j]);
    }
  }
  if constexpr (kUpdate == Update::kSumT) {
    KUAVO_UNROLL
    for (int v = 0; v < MZ; ++v) {
      __m256d lo[4], hi[4];
      addend_t4(add.s + 8 * v * add.ld, add.ld, add.rows - 8 * v, NR, lo);
      addend_t4(add.s + (8 * v + 4) * add.ld, add.ld, add.rows - 8 * v - 4, NR, hi);
      KUAVO_UNROLL
      for (int j = 0; j < NR; ++j) {
        const __m512d t = _mm512_insertf64x4(_mm512_castpd256_pd512(lo[j]), hi[j], 1);
        _mm512_storeu_pd(C + j * ldc + 8 * v, _mm512_add_pd(t, acc[v][j]));
      }
    }
    if constexpr (kHalf) {
      __m256d t[4];
      addend_t4(add.s + 8 * MZ * add.ld, add.ld, add.rows - 8 * MZ, NR, t);
      KUAVO_UNROLL
      for (int j = 0; j < NR; ++j) _mm256_storeu_pd(C + j * ldc + 8 * MZ, _mm256_add_pd(t[j], acc_h[j]));
    }
  } else if constexpr (kUpdate == Update::kSum) {
    KUAVO_UNROLL
    for (int j = 0; j < NR; ++j) {
      double* c = C + j * ldc;
      const double* s = add.s + j * add.ld;
      KUAVO_UNROLL
      for (int v = 0; v < MZ; ++v) update_zmm<kUpdate>(c + 8 * v, acc[v][j], s + 8 * v, add.rows - 8 * v);
      if constexpr (kHalf) update_ymm<kUpdate>(c + 8 * MZ, acc_h[j], s + 8 * MZ, add.rows - 8 * MZ);
    }
  } else {
    KUAVO_UNROLL
    for (int j = 0; j < NR; ++j) {
      double* c = C + j * ldc;
      KUAVO_UNROLL
      for (int v = 0; v < MZ; ++v) update_zmm<kUpdate>(c + 8 * v, acc[v][j]);
      if constexpr (kHalf) update_ymm<kUpdate>(c + 8 * MZ, acc_h[j]);
    }
  }
}
#endif

template <int NR, bool kTransB, Update kUpdate>
inline void tile_column(int i, int m, int k, const double* A, int lda, const double* B, int ldb, double* C,
                        int ldc, Addend add = {}) {
#ifdef KUAVO_QP_KERNELS_AVX512
  // 24-row tiles while more than 28 rows remain, then one tile for the last 4…28 (the stage
  // blocks: 52 u rows = 24 + 28, 40 x rows = 24 + 16), so no column ends in a short tile that
  // re-reads B for a few rows.
  for (; m - i > 28; i += 24) {
    tile_zmm<3, false, NR, kTransB, kUpdate>(k, A + i, lda, B, ldb, C + i, ldc, add.template offset<kUpdate>(i, 0));
  }
  const double* Ai = A + i;
  double* Ci = C + i;
  const Addend ai = add.template offset<kUpdate>(i, 0);
  switch (m - i) {
    case 28: tile_zmm<3, true, NR, kTransB, kUpdate>(k, Ai, lda, B, ldb, Ci, ldc, ai); break;
    case 24: tile_zmm<3, false, NR, kTransB, kUpdate>(k, Ai, lda, B, ldb, Ci, ldc, ai); break;
    case 20: tile_zmm<2, true, NR, kTransB, kUpdate>(k, Ai, lda, B, ldb, Ci, ldc, ai); break;
    case 16: tile_zmm<2, false, NR, kTransB, kUpdate>(k, Ai, lda, B, ldb, Ci, ldc, ai); break;
    case 12: tile_zmm<1, true, NR, kTransB, kUpdate>(k, Ai, lda, B, ldb, Ci, ldc, ai); break;
    case 8: tile_zmm<1, false, NR, kTransB, kUpdate>(k, Ai, lda, B, ldb, Ci, ldc, ai); break;
    case 4: tile<4, NR, kTransB, kUpdate>(k, Ai, lda, B, ldb, Ci, ldc, ai); break;
    default: break;  // m − i == 0
  }
#else
  for (; i + 8 <= m; i += 8) tile<8, NR, kTransB, kUpdate>(k, A + i, lda, B, ldb, C + i, ldc, add.template offset<kUpdate>(i, 0));
  if (i < m) tile<4, NR, kTransB, kUpdate>(k, A + i, lda, B, ldb, C + i, ldc, add.template offset<kUpdate>(i, 0));
#endif
}

// C[m×n] (=, +=, −=) A[m×k] · op(B), op(B) = B (NN) or Bᵀ (kTransB). m % 4 == 0.
// kLower: C's (0,0) lies on a symmetric matrix's diagonal and only its lower triangle is
// wanted: rows above each 4-column strip are skipped (tiles that straddle the diagonal are
// computed whole, so a few entries above it are written too: only inside the 4×4 diagonal
// chunks, since every strip's first tile starts on the diagonal, whatever its height).
// kSum: C = S + A·op(B) with S from add (there too the diagonal chunks' upper entries are read).
template <bool kTransB, Update kUpdate, bool kLower = false>
inline void gemm(int m, int n, int k, const double* A, int lda, const double* B, int ldb, double* C, int ldc,
                 Addend add = {}) {
  for (int j = 0; j < n; j += 4) {
    const int i = kLower ? j : 0;
    const double* Bj = b_entry<kTransB>(B, ldb, 0, j);
    double* Cj = C + j * ldc;
    const Addend aj = add.template offset<kUpdate>(0, j);
    switch (std::min(4, n - j)) {
      case 4: tile_column<4, kTransB, kUpdate>(i, m, k, A, lda, Bj, ldb, Cj, ldc, aj); break;
      case 3: tile_column<3, kTransB, kUpdate>(i, m, k, A, lda, Bj, ldb, Cj, ldc, aj); break;
      case 2: tile_column<2, kTransB, kUpdate>(i, m, k, A, lda, Bj, ldb, Cj, ldc, aj); break;
      default: tile_column<1, kTransB, kUpdate>(i, m, k, A, lda, Bj, ldb, Cj, ldc, aj); break;
    }
  }
}

// C[m×n] = A[m×n'] · L with L lower triangular n×n (its strict upper part inside the 4×4
// diagonal chunks must be zero; the rest of the upper part is not read). m % 4 == 0.
inline void trmm_right_lower(int m, int n, const double* A, int lda, const double* L, int ldl, double* C, int ldc) {
  for (int j = 0; j < n; j += 4) {
    gemm<false, Update::kSet>(m, std::min(4, n - j), n - j, A + j * lda, lda, L + j + j * ldl, ldl, C + j * ldc, ldc);
  }
}

// dst(j, i) = src(i, j) for an m×n column-major src. With last (n entries): also last[j] = 1 +
// the last row in which src's column j is nonzero (0: all zero; NaN counts as nonzero), found
// on the vectors the transpose loads anyway (for m ≤ 64, a bit mask of nonzero rows per column,
// branch-free) instead of a second, branchy scan of src. With groups (n entries, m ≤ 64): bit g
// of groups[j] set when column j has a nonzero in rows [4g, 4g + 4) (gemv_n_groups).
inline std::uint16_t nonzero_groups(unsigned long long rows) {
  rows |= rows >> 1;
  rows |= rows >> 2;  // bit 4g: any of rows 4g … 4g + 3
#ifdef __BMI2__
  return static_cast<std::uint16_t>(_pext_u64(rows, 0x1111111111111111ull));
#else
  unsigned g = 0;
  for (int b = 0; b < 16; ++b) g |= static_cast<unsigned>(rows >> (4 * b) & 1ull) << b;
  return static_cast<std::uint16_t>(g);
#endif
}
#ifdef KUAVO_QP_KERNELS_SIMD
// The 4×4 block at c0 (column-major, lds) transposed into d (ldd): the row pairs of columns
// (0, 2) and (1, 3) by 128-bit loads into the two halves (the insert takes any vector port,
// the cross-lane permute only the shuffle port), then one unpack per output row.
inline void transpose_block4(const double* c0, int lds, double* d, int ldd) {
  const __m256d h0 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(c0)), _mm_loadu_pd(c0 + 2 * lds), 1);
  const __m256d h1 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(c0 + lds)), _mm_loadu_pd(c0 + 3 * lds), 1);
  const __m256d h2 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(c0 + 2)), _mm_loadu_pd(c0 + 2 * lds + 2), 1);
  const __m256d h3 =
      _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(c0 + lds + 2)), _mm_loadu_pd(c0 + 3 * lds + 2), 1);
  _mm256_storeu_pd(d, _mm256_unpacklo_pd(h0, h1));
  _mm256_storeu_pd(d + ldd, _mm256_unpackhi_pd(h0, h1));
  _mm256_storeu_pd(d + 2 * ldd, _mm256_unpacklo_pd(h2, h3));
  _mm256_storeu_pd(d + 3 * ldd, _mm256_unpackhi_pd(h2, h3));
}

// Bits i … i + 3 of nz[c]: which of the 4 rows at c0 of column c (c = 0…3, lds apart) are
// nonzero (NaN counts as nonzero).
inline void mark_nonzero_rows4(const double* c0, int lds, int i, unsigned long long nz[4]) {
  const __m256d zero = _mm256_setzero_pd();
  KUAVO_UNROLL
  for (int c = 0; c < 4; ++c) {
    const int bits = _mm256_movemask_pd(_mm256_cmp_pd(_mm256_loadu_pd(c0 + c * lds), zero, _CMP_NEQ_UQ));
    nz[c] |= static_cast<unsigned long long>(bits) << i;
  }
}
#endif

inline void transpose(int m, int n, const double* src, int lds, double* dst, int ldd, int* last = nullptr,
                      std::uint16_t* groups = nullptr) {
  const bool masks = (last != nullptr || groups != nullptr) && m <= 64;
  int j = 0;
#ifdef KUAVO_QP_KERNELS_SIMD
  // Column groups outside, rows inside: src is read in address order (at MPC size each stage's
  // A and B are first touched here, from beyond L2, and a sequential read streams), one 4×4
  // block at a time (transpose_block4).
  for (; j + 4 <= n; j += 4) {
    const double* s0 = src + j * lds;
    unsigned long long nz[4] = {0, 0, 0, 0};  // bit r: row r of column j + c is nonzero
    int i = 0;
    for (; i + 4 <= m; i += 4) {
      const double* c0 = s0 + i;
      if (masks) {
        mark_nonzero_rows4(c0, lds, i, nz);
      }
      transpose_block4(c0, lds, dst + j + i * ldd, ldd);
    }
    for (; i < m; ++i) {
      for (int c = 0; c < 4; ++c) {
        const double x = s0[i + c * lds];
        dst[j + c + i * ldd] = x;
        if (masks) nz[c] |= static_cast<unsigned long long>(x != 0.0) << i;
      }
    }
    if (masks && last != nullptr) {
      for (int c = 0; c < 4; ++c) last[j + c] = nz[c] == 0 ? 0 : 64 - __builtin_clzll(nz[c]);
    }
    if (masks && groups != nullptr) {
      for (int c = 0; c < 4; ++c) groups[j + c] = nonzero_groups(nz[c]);
    }
  }
#endif
  const int j_vector_end = j;
  for (; j < n; ++j) {
    int l = 0;
    unsigned long long nz = 0;
    for (int i = 0; i < m; ++i) {
      dst[j + i * ldd] = src[i + j * lds];
      if (src[i + j * lds] != 0.0) {  // NaN too
        l = i + 1;
        if (i < 64) nz |= 1ull << i;
      }
    }
    if (last != nullptr) last[j] = l;
    if (groups != nullptr) groups[j] = nonzero_groups(nz);
  }
  if (last != nullptr && !masks) {  // m > 64: the vector loop's columns by a scan from the bottom
    for (int c = 0; c < j_vector_end; ++c) {
      int l = m;
      while (l > 0 && src[l - 1 + c * lds] == 0.0) --l;
      last[c] = l;
    }
  }
}

// transpose (with last and groups) of an m×n src (m ≤ 64) whose column j is zero outside the
// 4-row groups declared[j] (bit g: rows [4g, 4g + 4)), reading only the groups some column of
// each 4-column step declares: dst's other entries are written zero. On such a src the same
// dst, last and groups as transpose's, bit for bit. For [B A] of the MPC (A the identity but
// in 9 rows, B's force columns 6 rows deep): ~half of each column's cache lines not fetched.
inline void transpose_declared(int m, int n, const double* src, int lds, double* dst, int ldd, int* last,
                               std::uint16_t* groups, const std::uint16_t* declared) {
  int j = 0;
#ifdef KUAVO_QP_KERNELS_SIMD
  const __m256d zero = _mm256_setzero_pd();
  for (; j + 4 <= n; j += 4) {
    const unsigned read = static_cast<unsigned>(declared[j] | declared[j + 1] | declared[j + 2] | declared[j + 3]);
    const double* s0 = src + j * lds;
    unsigned long long nz[4] = {0, 0, 0, 0};
    int i = 0;
    for (; i + 4 <= m; i += 4) {
      if ((read >> (i / 4) & 1u) == 0) {
        for (int r = 0; r < 4; ++r) _mm256_storeu_pd(dst + j + (i + r) * ldd, zero);
        continue;
      }
      const double* c0 = s0 + i;
      mark_nonzero_rows4(c0, lds, i, nz);
      transpose_block4(c0, lds, dst + j + i * ldd, ldd);
    }
    const bool tail = (read >> (i / 4) & 1u) != 0;
    for (; i < m; ++i) {
      for (int c = 0; c < 4; ++c) {
        const double x = tail ? s0[i + c * lds] : 0.0;
        dst[j + c + i * ldd] = x;
        nz[c] |= static_cast<unsigned long long>(x != 0.0) << i;
      }
    }
    for (int c = 0; c < 4; ++c) {
      last[j + c] = nz[c] == 0 ? 0 : 64 - __builtin_clzll(nz[c]);
      groups[j + c] = nonzero_groups(nz[c]);
    }
  }
#endif
  for (; j < n; ++j) {
    unsigned long long nz = 0;
    for (int i = 0; i < m; ++i) {
      const double x = (declared[j] >> (i / 4) & 1u) != 0 ? src[i + j * lds] : 0.0;
      dst[j + i * ldd] = x;
      if (x != 0.0) nz |= 1ull << i;  // NaN too
    }
    last[j] = nz == 0 ? 0 : 64 - __builtin_clzll(nz);
    groups[j] = nonzero_groups(nz);
  }
}


// Factors the four columns [j, j+4) of a symmetric matrix S = L·diag(d)·Lᵀ in place (lower,
// column-major, leading dimension ld), d = ±1 for all four. The panel's rows are
// [j, row_end) ∪ [row2_begin, row2_end) (two ranges, so a block of unused rows can sit between
// them), and must already carry the updates of every column before j. On return the panel
// holds L: L(c,c) = √(d·a_c), L(r,c) = a_rc / (d·L(c,c)). Returns false at a pivot with
// d·a ≤ 0 or NaN (not definite with the expected sign).
inline bool factor_panel4(double* L, int ld, int j, int row_end, int row2_begin, int row2_end, double d) {
  // The 4×4 diagonal block S first, by elimination without square roots (S_rc2 −= S_rc·S_c2c/S_cc,
  // the LDLᵀ recurrence: the same Schur complements as the Cholesky sweep, whose L(r,c)·d·L(c2,c)
  // is S_rc·S_c2c/S_cc), so the chain from one pivot to the next is a divide, a multiply and an
  // FMA instead of a square root, a divide, the column's scaling and the update. The square roots
  // and reciprocals of the four pivots are independent and follow at once: l_c = √(d·S_cc),
  // inv_c = 1/(d·l_c), L(r,c) = S_rc·inv_c; and the factors f = d·L(c2,c) for the rows below.
  double sb[4][4];  // sb[r][c], r ≥ c
  for (int c = 0; c < 4; ++c) {
    for (int r = c; r < 4; ++r) sb[r][c] = L[(j + r) + (j + c) * ld];
  }
  for (int c = 0; c < 4; ++c) {
    if (!(d * sb[c][c] > 0.0)) return false;
    const double q = 1.0 / sb[c][c];
    for (int c2 = c + 1; c2 < 4; ++c2) {
      const double t = sb[c2][c] * q;
      for (int r = c2; r < 4; ++r) sb[r][c2] -= sb[r][c] * t;
    }
  }
  double inv[4];
  double f[4][4] = {};
  for (int c = 0; c < 4; ++c) {
    const double l = std::sqrt(d * sb[c][c]);
    inv[c] = 1.0 / (d * l);
    L[(j + c) * (ld + 1)] = l;
  }
  for (int c = 0; c < 4; ++c) {
    for (int r = c + 1; r < 4; ++r) {
      const double v = sb[r][c] * inv[c];
      L[(j + r) + (j + c) * ld] = v;
      f[c][r] = d * v;
    }
  }
  const auto rows_below = [&](int begin, int end) {
    int r = begin;
#ifdef KUAVO_QP_KERNELS_SIMD
    for (; r + 4 <= end; r += 4) {
      double* p = L + r + j * ld;
      __m256d v0 = _mm256_loadu_pd(p), v1 = _mm256_loadu_pd(p + ld);
      __m256d v2 = _mm256_loadu_pd(p + 2 * ld), v3 = _mm256_loadu_pd(p + 3 * ld);
      v0 = _mm256_mul_pd(v0, _mm256_set1_pd(inv[0]));
      v1 = _mm256_fnmadd_pd(_mm256_set1_pd(f[0][1]), v0, v1);
      v2 = _mm256_fnmadd_pd(_mm256_set1_pd(f[0][2]), v0, v2);
      v3 = _mm256_fnmadd_pd(_mm256_set1_pd(f[0][3]), v0, v3);
      v1 = _mm256_mul_pd(v1, _mm256_set1_pd(inv[1]));
      v2 = _mm256_fnmadd_pd(_mm256_set1_pd(f[1][2]), v1, v2);
      v3 = _mm256_fnmadd_pd(_mm256_set1_pd(f[1][3]), v1, v3);
      v2 = _mm256_mul_pd(v2, _mm256_set1_pd(inv[2]));
      v3 = _mm256_fnmadd_pd(_mm256_set1_pd(f[2][3]), v2, v3);
      v3 = _mm256_mul_pd(v3, _mm256_set1_pd(inv[3]));
      _mm256_storeu_pd(p, v0);
      _mm256_storeu_pd(p + ld, v1);
      _mm256_storeu_pd(p + 2 * ld, v2);
      _mm256_storeu_pd(p + 3 * ld, v3);
    }
#endif
    for (; r < end; ++r) {
      double* p = L + r + j * ld;
      for (int c = 0; c < 4; ++c) {
        p[c * ld] *= inv[c];
        for (int c2 = c + 1; c2 < 4; ++c2) p[c2 * ld] -= f[c][c2] * p[c * ld];
      }
    }
  };
  rows_below(j + 4, row_end);
  rows_below(row2_begin, row2_end);
  return true;
}

// In-place Cholesky S = L·Lᵀ of an n×n matrix, n % 4 == 0 (lower triangle read and written),
// left-looking over 4-column panels. Returns false if S is not numerically positive definite.
inline bool cholesky(double* L, int ld, int n) {
  for (int j = 0; j < n; j += 4) {
    gemm<true, Update::kSub>(n - j, 4, j, L + j, ld, L + j, ld, L + j + j * ld, ld);
    if (!factor_panel4(L, ld, j, n, n, n, 1.0)) return false;
  }
  return true;
}

// ---- Vector pass: matrix-vector products and triangular solves (riccati_solve). ----
// Any m, n (row remainders through masked loads, so nothing past row m is read or written).
// Eigen's gemv at these sizes (38–50) is its general blocked kernel with per-call setup.


#ifdef KUAVO_QP_KERNELS_SIMD
// y[m] += A[m×4]·[b0 b1 b2 b3] (each b broadcast in all lanes), A column-major (lda); rows past
// the last whole 4 through masked loads and stores.
inline void add_4_columns(int m, const double* A, int lda, __m256d b0, __m256d b1, __m256d b2, __m256d b3,
                          double* y) {
  int i = 0;
  for (; i + 4 <= m; i += 4) {
    __m256d acc = _mm256_loadu_pd(y + i);
    acc = _mm256_fmadd_pd(_mm256_loadu_pd(A + i), b0, acc);
    acc = _mm256_fmadd_pd(_mm256_loadu_pd(A + i + lda), b1, acc);
    acc = _mm256_fmadd_pd(_mm256_loadu_pd(A + i + 2 * lda), b2, acc);
    acc = _mm256_fmadd_pd(_mm256_loadu_pd(A + i + 3 * lda), b3, acc);
    _mm256_storeu_pd(y + i, acc);
  }
  if (i < m) {
    const __m256i tail = row_mask(m - i);
    __m256d acc = _mm256_maskload_pd(y + i, tail);
    acc = _mm256_fmadd_pd(_mm256_maskload_pd(A + i, tail), b0, acc);
    acc = _mm256_fmadd_pd(_mm256_maskload_pd(A + i + lda, tail), b1, acc);
    acc = _mm256_fmadd_pd(_mm256_maskload_pd(A + i + 2 * lda, tail), b2, acc);
    acc = _mm256_fmadd_pd(_mm256_maskload_pd(A + i + 3 * lda, tail), b3, acc);
    _mm256_maskstore_pd(y + i, tail, acc);
  }
}
#endif

// y[m] (+=, −=) A[m×n]·x, A column-major (lda), kSet not supported (callers add into y).
template <Update kUpdate>
inline void gemv_n(int m, int n, const double* A, int lda, const double* x, double* y) {
  static_assert(kUpdate != Update::kSet, "gemv_n accumulates");
  constexpr double sign = kUpdate == Update::kAdd ? 1.0 : -1.0;
#ifdef KUAVO_QP_KERNELS_SIMD
  const int m4 = m / 4 * 4;
  const __m256i tail = row_mask(m - m4);
  int j = 0;
  for (; j + 4 <= n; j += 4) {
    add_4_columns(m, A + j * lda, lda, _mm256_set1_pd(sign * x[j]), _mm256_set1_pd(sign * x[j + 1]),
                  _mm256_set1_pd(sign * x[j + 2]), _mm256_set1_pd(sign * x[j + 3]), y);
  }
  for (; j < n; ++j) {
    const __m256d b = _mm256_set1_pd(sign * x[j]);
    const double* a = A + j * lda;
    int i = 0;
    for (; i < m4; i += 4) _mm256_storeu_pd(y + i, _mm256_fmadd_pd(_mm256_loadu_pd(a + i), b, _mm256_loadu_pd(y + i)));
    if (i < m) {
      _mm256_maskstore_pd(y + i, tail,
                          _mm256_fmadd_pd(_mm256_maskload_pd(a + i, tail), b, _mm256_maskload_pd(y + i, tail)));
    }
  }
#else
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < m; ++i) y[i] += sign * A[i + j * lda] * x[j];
  }
#endif
}

// y[m] += A[m×n]·x, skipping the 4-row groups in which A's columns are zero: groups[j] has
// bit g set when column j has a nonzero entry in rows [4g, 4g + 4) (transpose's groups),
// m ≤ 64. Bit for bit gemv_n<kAdd>: a group is skipped only where all the columns of a
// 4-column step (or the single remainder column) are zero, whose products are exact zeros,
// and every entry of y takes the remaining products in gemv_n's order. For the forward
// rollout's A and B (the MPC's: A the identity but in 9 rows, B's force columns 6 rows deep):
// of each column only the nonzero groups' cache lines are fetched.
inline void gemv_n_groups(int m, int n, const double* A, int lda, const double* x, double* y,
                          const std::uint16_t* groups) {
#ifdef KUAVO_QP_KERNELS_SIMD
  const int m4 = m / 4 * 4;
  const __m256i tail = row_mask(m - m4);
  int j = 0;
  for (; j + 4 <= n; j += 4) {
    unsigned g = static_cast<unsigned>(groups[j] | groups[j + 1] | groups[j + 2] | groups[j + 3]);
    const double* a = A + j * lda;
    const __m256d b0 = _mm256_set1_pd(x[j]), b1 = _mm256_set1_pd(x[j + 1]);
    const __m256d b2 = _mm256_set1_pd(x[j + 2]), b3 = _mm256_set1_pd(x[j + 3]);
    while (g != 0) {
      const int i = 4 * __builtin_ctz(g);
      g &= g - 1;
      if (i < m4) {
        __m256d acc = _mm256_loadu_pd(y + i);
        acc = _mm256_fmadd_pd(_mm256_loadu_pd(a + i), b0, acc);
        acc = _mm256_fmadd_pd(_mm256_loadu_pd(a + i + lda), b1, acc);
        acc = _mm256_fmadd_pd(_mm256_loadu_pd(a + i + 2 * lda), b2, acc);
        acc = _mm256_fmadd_pd(_mm256_loadu_pd(a + i + 3 * lda), b3, acc);
        _mm256_storeu_pd(y + i, acc);
      } else {
        __m256d acc = _mm256_maskload_pd(y + i, tail);
        acc = _mm256_fmadd_pd(_mm256_maskload_pd(a + i, tail), b0, acc);
        acc = _mm256_fmadd_pd(_mm256_maskload_pd(a + i + lda, tail), b1, acc);
        acc = _mm256_fmadd_pd(_mm256_maskload_pd(a + i + 2 * lda, tail), b2, acc);
        acc = _mm256_fmadd_pd(_mm256_maskload_pd(a + i + 3 * lda, tail), b3, acc);
        _mm256_maskstore_pd(y + i, tail, acc);
      }
    }
  }
  for (; j < n; ++j) {
    unsigned g = groups[j];
    const __m256d b = _mm256_set1_pd(x[j]);
    const double* a = A + j * lda;
    while (g != 0) {
      const int i = 4 * __builtin_ctz(g);
      g &= g - 1;
      if (i < m4) {
        _mm256_storeu_pd(y + i, _mm256_fmadd_pd(_mm256_loadu_pd(a + i), b, _mm256_loadu_pd(y + i)));
      } else {
        _mm256_maskstore_pd(y + i, tail,
                            _mm256_fmadd_pd(_mm256_maskload_pd(a + i, tail), b, _mm256_maskload_pd(y + i, tail)));
      }
    }
  }
#else
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < m; ++i) {
      if (groups[j] >> (i / 4) & 1u) y[i] += A[i + j * lda] * x[j];
    }
  }
#endif
}

// y (=, +=, −=) d: the scalar update of the matrix-vector products.
template <Update kUpdate>
inline void update_scalar(double& y, double d) {
  if constexpr (kUpdate == Update::kSet) y = d;
  else if constexpr (kUpdate == Update::kAdd) y += d;
  else y -= d;
}

#ifdef KUAVO_QP_KERNELS_SIMD
// y[0..3] (=, +=, −=) [Σc0, Σc1, Σc2, Σc3], the lane sums of four column accumulators.
template <Update kUpdate>
inline void update_lane_sums4(double* y, __m256d c0, __m256d c1, __m256d c2, __m256d c3) {
  const __m256d h01 = _mm256_hadd_pd(c0, c1), h23 = _mm256_hadd_pd(c2, c3);
  const __m256d sum = _mm256_add_pd(_mm256_permute2f128_pd(h01, h23, 0x20), _mm256_permute2f128_pd(h01, h23, 0x31));
  if constexpr (kUpdate == Update::kSet) {
    _mm256_storeu_pd(y, sum);
  } else if constexpr (kUpdate == Update::kAdd) {
    _mm256_storeu_pd(y, _mm256_add_pd(_mm256_loadu_pd(y), sum));
  } else {
    _mm256_storeu_pd(y, _mm256_sub_pd(_mm256_loadu_pd(y), sum));
  }
}

// c0…c3 += the 4 rows at a of four columns (lda apart) times xv, lane by lane; kMasked: only
// the rows mask sets are loaded (a column's tail).
template <bool kMasked>
inline void fma_columns4(const double* a, int lda, __m256i mask, __m256d xv, __m256d& c0, __m256d& c1, __m256d& c2,
                         __m256d& c3) {
  const auto load = [mask](const double* p) {
    if constexpr (kMasked) {
      return _mm256_maskload_pd(p, mask);
    } else {
      return _mm256_loadu_pd(p);
    }
  };
  c0 = _mm256_fmadd_pd(load(a), xv, c0);
  c1 = _mm256_fmadd_pd(load(a + lda), xv, c1);
  c2 = _mm256_fmadd_pd(load(a + 2 * lda), xv, c2);
  c3 = _mm256_fmadd_pd(load(a + 3 * lda), xv, c3);
}

// The lane sum of one column accumulator.
inline double lane_sum(__m256d c) {
  const __m128d h = _mm_add_pd(_mm256_castpd256_pd128(c), _mm256_extractf128_pd(c, 1));
  return _mm_cvtsd_f64(_mm_add_sd(h, _mm_unpackhi_pd(h, h)));
}
#endif

// y[n] (=, +=, −=) Aᵀ·x for a column-major A[m×n] (lda).
template <Update kUpdate>
inline void gemv_t(int m, int n, const double* A, int lda, const double* x, double* y) {
#ifdef KUAVO_QP_KERNELS_SIMD
  const int m4 = m / 4 * 4;
  const __m256i tail = row_mask(m - m4);
  const __m256d x_tail = m4 < m ? _mm256_maskload_pd(x + m4, tail) : _mm256_setzero_pd();
  int j = 0;
  for (; j + 4 <= n; j += 4) {
    const double* a = A + j * lda;
    __m256d c0 = _mm256_setzero_pd(), c1 = _mm256_setzero_pd(), c2 = _mm256_setzero_pd(), c3 = _mm256_setzero_pd();
    for (int i = 0; i < m4; i += 4) {
      fma_columns4<false>(a + i, lda, tail, _mm256_loadu_pd(x + i), c0, c1, c2, c3);
    }
    if (m4 < m) {
      fma_columns4<true>(a + m4, lda, tail, x_tail, c0, c1, c2, c3);
    }
    update_lane_sums4<kUpdate>(y + j, c0, c1, c2, c3);
  }
  for (; j < n; ++j) {
    const double* a = A + j * lda;
    __m256d c = _mm256_setzero_pd();
    for (int i = 0; i < m4; i += 4) c = _mm256_fmadd_pd(_mm256_loadu_pd(a + i), _mm256_loadu_pd(x + i), c);
    if (m4 < m) c = _mm256_fmadd_pd(_mm256_maskload_pd(a + m4, tail), x_tail, c);
    update_scalar<kUpdate>(y[j], lane_sum(c));
  }
#else
  for (int j = 0; j < n; ++j) {
    double d = 0.0;
    for (int i = 0; i < m; ++i) d += A[i + j * lda] * x[i];
    update_scalar<kUpdate>(y[j], d);
  }
#endif
}

// y[n] (=, +=, −=) Aᵀ·x over the 4-row groups in which A's columns are nonzero (groups as in
// gemv_n_groups), m ≤ 64. Bit for bit gemv_t: a 4-column step skips a row group only where all
// its columns are zero there, and the column sums start at +0, which adding exact zeros
// leaves unchanged (a sum that starts at +0 is never −0).
template <Update kUpdate>
inline void gemv_t_groups(int m, int n, const double* A, int lda, const double* x, double* y,
                          const std::uint16_t* groups) {
#ifdef KUAVO_QP_KERNELS_SIMD
  const int m4 = m / 4 * 4;
  const __m256i tail = row_mask(m - m4);
  const __m256d x_tail = m4 < m ? _mm256_maskload_pd(x + m4, tail) : _mm256_setzero_pd();
  int j = 0;
  for (; j + 4 <= n; j += 4) {
    const double* a = A + j * lda;
    unsigned g = static_cast<unsigned>(groups[j] | groups[j + 1] | groups[j + 2] | groups[j + 3]);
    __m256d c0 = _mm256_setzero_pd(), c1 = _mm256_setzero_pd(), c2 = _mm256_setzero_pd(), c3 = _mm256_setzero_pd();
    while (g != 0) {
      const int i = 4 * __builtin_ctz(g);
      g &= g - 1;
      if (i < m4) {
        fma_columns4<false>(a + i, lda, tail, _mm256_loadu_pd(x + i), c0, c1, c2, c3);
      } else {
        fma_columns4<true>(a + m4, lda, tail, x_tail, c0, c1, c2, c3);
      }
    }
    update_lane_sums4<kUpdate>(y + j, c0, c1, c2, c3);
  }
  for (; j < n; ++j) {
    const double* a = A + j * lda;
    unsigned g = groups[j];
    __m256d c = _mm256_setzero_pd();
    while (g != 0) {
      const int i = 4 * __builtin_ctz(g);
      g &= g - 1;
      if (i < m4) {
        c = _mm256_fmadd_pd(_mm256_loadu_pd(a + i), _mm256_loadu_pd(x + i), c);
      } else {
        c = _mm256_fmadd_pd(_mm256_maskload_pd(a + m4, tail), x_tail, c);
      }
    }
    update_scalar<kUpdate>(y[j], lane_sum(c));
  }
#else
  for (int j = 0; j < n; ++j) {
    double d = 0.0;
    for (int i = 0; i < m; ++i) {
      if (groups[j] >> (i / 4) & 1u) d += A[i + j * lda] * x[i];
    }
    update_scalar<kUpdate>(y[j], d);
  }
#endif
}

// ---- Triangular solves by the inverses of the 4×4 diagonal blocks. ----
// A column sweep divides by each pivot in turn, a ~20-cycle chain per row (50 rows: most of a
// solve's time). With the inverse of each 4×4 diagonal block stored at factorization time
// (invert_diag4), a block's unknowns come out of one 4×4 product, so a block costs a few
// FMA latencies instead of four divide-and-update steps (as BLASFEO keeps the inverted
// diagonal). The inverse is formed by substitution from the block, so x differs from the
// sweep's by rounding only.

// The inverse X of the jb×jb lower-triangular diagonal block of L at (j, j), jb = 1…4, as a
// 4×4 column-major X (Binv, 16 entries) and Xᵀ (BinvT), identity beyond jb, zero above the
// diagonal.
inline void invert_diag4(const double* L, int ld, int j, int jb, double* Binv, double* BinvT) {
  double X[4][4] = {};  // X[r][c]
  for (int c = 0; c < 4; ++c) X[c][c] = c < jb ? 1.0 / L[(j + c) * (ld + 1)] : 1.0;
  for (int c = 0; c < jb; ++c) {
    for (int r = c + 1; r < jb; ++r) {
      double sum = 0.0;
      for (int k = c; k < r; ++k) sum += L[(j + r) + (j + k) * ld] * X[k][c];
      X[r][c] = -sum * X[r][r];
    }
  }
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      Binv[r + 4 * c] = X[r][c];
      BinvT[r + 4 * c] = X[c][r];
    }
  }
}

#ifdef KUAVO_QP_KERNELS_SIMD
// M·v for a 4×4 column-major M: two independent halves, then their sum (12 cycles of latency).
inline __m256d mul4x4(const double* M, __m256d v) {
  const __m256d v0 = _mm256_permute4x64_pd(v, 0x00), v1 = _mm256_permute4x64_pd(v, 0x55);
  const __m256d v2 = _mm256_permute4x64_pd(v, 0xAA), v3 = _mm256_permute4x64_pd(v, 0xFF);
  const __m256d a = _mm256_fmadd_pd(_mm256_loadu_pd(M + 4), v1, _mm256_mul_pd(_mm256_loadu_pd(M), v0));
  const __m256d b = _mm256_fmadd_pd(_mm256_loadu_pd(M + 12), v3, _mm256_mul_pd(_mm256_loadu_pd(M + 8), v2));
  return _mm256_add_pd(a, b);
}
#endif

// x ← L⁻¹x, L lower triangular n×n (upper part not read), Binv its diagonal blocks' inverses
// (invert_diag4 for j = 0, 4, …, block b at Binv + 16·b).
inline void trsv_lower(int n, const double* L, int ld, const double* Binv, double* x) {
#ifdef KUAVO_QP_KERNELS_SIMD
  for (int j = 0; j < n; j += 4) {
    const int jb = std::min(4, n - j);
    const __m256i mask = row_mask(jb);
    const __m256d xb = mul4x4(Binv + 4 * j, jb == 4 ? _mm256_loadu_pd(x + j) : _mm256_maskload_pd(x + j, mask));
    if (jb < 4) {
      _mm256_maskstore_pd(x + j, mask, xb);
      return;  // the last block: nothing below
    }
    _mm256_storeu_pd(x + j, xb);
    // x[j+4 …] −= L(j+4 …, j…j+3)·xb (an FMA with −xb, sign flipped exactly, is the FNMA with xb).
    const __m256d nb = _mm256_xor_pd(xb, _mm256_set1_pd(-0.0));
    add_4_columns(n - j - 4, L + j + 4 + j * ld, ld, _mm256_permute4x64_pd(nb, 0x00), _mm256_permute4x64_pd(nb, 0x55),
                  _mm256_permute4x64_pd(nb, 0xAA), _mm256_permute4x64_pd(nb, 0xFF), x + j + 4);
  }
#else
  for (int j = 0; j < n; j += 4) {
    const int jb = std::min(4, n - j);
    const double* M = Binv + 4 * j;
    double xb[4] = {};
    for (int c = 0; c < jb; ++c) {
      for (int r = 0; r < jb; ++r) xb[r] += M[r + 4 * c] * x[j + c];
    }
    for (int r = 0; r < jb; ++r) x[j + r] = xb[r];
    for (int c = 0; c < jb; ++c) {
      for (int i = j + jb; i < n; ++i) x[i] -= L[i + (j + c) * ld] * xb[c];
    }
  }
#endif
}

// x ← L⁻ᵀx, L lower triangular n×n (upper part not read), BinvT the transposes of its
// diagonal blocks' inverses (invert_diag4). Each solved block updates the unknowns above it,
// the next block's first, so the chain from block to block is one 4-row product.
inline void trsv_lower_trans(int n, const double* L, int ld, const double* BinvT, double* x) {
  if (n <= 0) return;
#ifdef KUAVO_QP_KERNELS_SIMD
  for (int j = (n - 1) / 4 * 4; j >= 0; j -= 4) {
    const int jb = std::min(4, n - j);
    const __m256i mask = row_mask(jb);
    __m256d xb;
    if (jb == 4) {
      xb = mul4x4(BinvT + 4 * j, _mm256_loadu_pd(x + j));
      _mm256_storeu_pd(x + j, xb);
    } else {
      xb = mul4x4(BinvT + 4 * j, _mm256_maskload_pd(x + j, mask));
      _mm256_maskstore_pd(x + j, mask, xb);
    }
    // x[c…c+3] −= L(j…j+3, c…c+3)ᵀ·xb, the block just above first.
    for (int c = j - 4; c >= 0; c -= 4) {
      const double* a = L + j + c * ld;
      __m256d p0, p1, p2, p3;
      if (jb == 4) {
        p0 = _mm256_mul_pd(_mm256_loadu_pd(a), xb);
        p1 = _mm256_mul_pd(_mm256_loadu_pd(a + ld), xb);
        p2 = _mm256_mul_pd(_mm256_loadu_pd(a + 2 * ld), xb);
        p3 = _mm256_mul_pd(_mm256_loadu_pd(a + 3 * ld), xb);
      } else {
        p0 = _mm256_mul_pd(_mm256_maskload_pd(a, mask), xb);
        p1 = _mm256_mul_pd(_mm256_maskload_pd(a + ld, mask), xb);
        p2 = _mm256_mul_pd(_mm256_maskload_pd(a + 2 * ld, mask), xb);
        p3 = _mm256_mul_pd(_mm256_maskload_pd(a + 3 * ld, mask), xb);
      }
      const __m256d h01 = _mm256_hadd_pd(p0, p1), h23 = _mm256_hadd_pd(p2, p3);
      const __m256d sum =
          _mm256_add_pd(_mm256_permute2f128_pd(h01, h23, 0x20), _mm256_permute2f128_pd(h01, h23, 0x31));
      _mm256_storeu_pd(x + c, _mm256_sub_pd(_mm256_loadu_pd(x + c), sum));
    }
  }
#else
  for (int j = (n - 1) / 4 * 4; j >= 0; j -= 4) {
    const int jb = std::min(4, n - j);
    const double* M = BinvT + 4 * j;
    double xb[4] = {};
    for (int c = 0; c < jb; ++c) {
      for (int r = 0; r < jb; ++r) xb[r] += M[r + 4 * c] * x[j + c];
    }
    for (int r = 0; r < jb; ++r) x[j + r] = xb[r];
    for (int c = 0; c < j; ++c) {
      for (int r = 0; r < jb; ++r) x[c] -= L[j + r + c * ld] * xb[r];
    }
  }
#endif
}

// y = Lᵀx and y += L·x for a lower triangular L whose strict upper part inside the 4×4
// diagonal chunks is zero (the cost-to-go factor's storage; the rest above is not read).
inline void trmv_lower_trans(int n, const double* L, int ld, const double* x, double* y) {
  for (int j = 0; j < n; j += 4) gemv_t<Update::kSet>(n - j, std::min(4, n - j), L + j + j * ld, ld, x + j, y + j);
}
inline void trmv_lower_add(int n, const double* L, int ld, const double* x, double* y) {
  for (int j = 0; j < n; j += 4) gemv_n<Update::kAdd>(n - j, std::min(4, n - j), L + j + j * ld, ld, x + j, y + j);
}

}  // namespace kuavo::qp::kernels
