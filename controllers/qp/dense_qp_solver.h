// Dense QP solver: the Goldfarb–Idnani dual active-set method (Math. Prog. 27, 1983) in its
// range-space form, with a warm start from the previous working set.
//
// Why this method: the WBC and IK Hessians are strictly convex by construction (task weights
// plus regularization), which is exactly GI's requirement; it needs no feasible starting point
// (the WBC has none at hand); every iterate is dual feasible, so after the cap one still has the
// minimizer over a subset of the constraints; and each working-set change costs O(NV²).
//
// Why the range-space form: with H = L Lᵀ and the working-set normals N, GI needs the
// projection of L⁻¹n onto the span of V = L⁻¹N and onto its complement. QuadProg keeps the
// full orthogonal basis J = L⁻ᵀQ (NV² numbers that every added constraint updates). Here only V
// and the triangle R of V = Q R are kept (RᵀR = NᵀH⁻¹N): the projection of v = L⁻¹n is
// V R⁻¹R⁻ᵀVᵀv, taken twice so that what roundoff leaves after the first pass is removed
// ("twice is enough", as in Gram–Schmidt). The gain is the start: the equalities and the warm
// start's working set enter as one block — one triangular solve for V, one symmetric product
// and one Cholesky for R, all matrix-matrix work — instead of one Householder update of J per
// constraint. Dropping a constraint deletes a column of V and restores R with Givens rotations.
//
// Warm start: the equalities and the previous working set are imposed as equalities (in one
// block; one at a time, with the exact dependency test, if a pivot of the block says some are
// nearly dependent), then members with a negative multiplier are dropped (all of them, then
// re-solved, until none is negative). The
// result is a valid GI starting point (the minimizer over a working set, dual feasible), so
// correctness never depends on the guess; a good guess only removes the add/drop iterations.
//
// Real-time: no allocation, no exceptions; cost ≈ NV³/3 (Cholesky of H) + NV²·q (V) + NV·q²/2
// (R) for a working set of q rows, plus (max_iterations) · O(NV² + NV·q).
#pragma once

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "controllers/finite.h"
#include "controllers/qp/dense_qp.h"

namespace kuavo::qp {
namespace dense_detail {

// A block working set whose Cholesky pivot leaves less than this fraction (squared) of a
// column's length outside the span of the others is redone one constraint at a time with the
// exact (twice projected) test. The Gram matrix carries roundoff ε·κ(V)², so its pivots can
// only be trusted well above ε; 1e-8 (1e-4 of the length) keeps R well conditioned.
inline constexpr double kBlockPivotTolerance = 1e-8;
// Projection passes: a second pass is taken when the first one's estimated error (relative to
// the part of v outside the span) exceeds kSecondPassTolerance — 1e-12, three decades below
// the primal tolerance, so that the steps' accuracy never limits the result.
inline constexpr double kRoundoff = 2.2e-16;
inline constexpr double kSecondPassTolerance = 1e-12;

// Constraint code helpers: the GI constraint is nᵀx ≥ bound (inequalities, code = 2·row + side)
// or nᵀx = bound (equalities, code = −1 − row).
template <int NV, int NE, int NI>
struct Codes {
  static int row(ConstraintCode c) { return c >> 1; }
  static bool upper(ConstraintCode c) { return (c & 1) != 0; }
  static bool is_bound(ConstraintCode c) { return row(c) >= NI; }

  static double bound(const DenseQp<NV, NE, NI>& qp, ConstraintCode c) {
    if constexpr (NE > 0) {
      if (c < 0) return qp.b(-1 - c);
    }
    const int i = row(c);
    if (i < NI) return upper(c) ? -qp.c_upper(i) : qp.c_lower(i);
    return upper(c) ? -qp.x_upper(i - NI) : qp.x_lower(i - NI);
  }
  // nᵀv
  template <typename V>
  static double dot(const DenseQp<NV, NE, NI>& qp, ConstraintCode c, const V& v) {
    if constexpr (NE > 0) {
      if (c < 0) return qp.A.row(-1 - c).dot(v);
    }
    const int i = row(c);
    const double s = upper(c) ? -1.0 : 1.0;
    if constexpr (NI > 0) {
      if (i < NI) return s * qp.C.row(i).dot(v);
    }
    return s * v(i - NI);
  }
  // out = n
  template <typename V>
  static void normal(const DenseQp<NV, NE, NI>& qp, ConstraintCode c, V&& out) {
    if constexpr (NE > 0) {
      if (c < 0) {
        out = qp.A.row(-1 - c).transpose();
        return;
      }
    }
    const int i = row(c);
    const double s = upper(c) ? -1.0 : 1.0;
    if constexpr (NI > 0) {
      if (i < NI) {
        out = s * qp.C.row(i).transpose();
        return;
      }
    }
    out.setZero();
    out(i - NI) = s;
  }
};

// The triangular solves of every iteration, column-oriented with fixed sizes: each step scales
// one entry and updates the rest with one contiguous column (a vectorized axpy), where a
// dot-product form would wait on a horizontal sum per entry (2-3× slower at NV = 58).
// x ← L⁻¹x for x zero above `first` (a bound's normal ±eⱼ: L⁻¹n is zero above j too).
// Both skip what L's block structure makes zero (dense_qp.h, dense_size): past the dense
// block a solve is a scaling.
template <int NV, int NE, int NI>
void solve_lower(const DenseQpWorkspace<NV, NE, NI>& ws, double* x, int first = 0) {
  const double* L = ws.L.data();
  const int kd = ws.dense_size;
  for (int j = first; j < kd; ++j) {
    const double xj = x[j] * ws.inv_diag[j];
    x[j] = xj;
    const double* col = L + j * NV;
    for (int i = j + 1; i < kd; ++i) x[i] -= xj * col[i];
  }
  for (int j = std::max(first, kd); j < NV; ++j) x[j] *= ws.inv_diag[j];
}
// x ← L⁻ᵀx, with Lᵀ's columns from ws.Lt.
template <int NV, int NE, int NI>
void solve_lower_transpose(const DenseQpWorkspace<NV, NE, NI>& ws, double* x) {
  const double* U = ws.Lt.data();
  const int kd = ws.dense_size;
  for (int j = NV - 1; j >= kd; --j) x[j] *= ws.inv_diag[j];
  for (int j = kd - 1; j >= 0; --j) {
    const double xj = x[j] * ws.inv_diag[j];
    x[j] = xj;
    const double* col = U + j * NV;
    for (int i = 0; i < j; ++i) x[i] -= xj * col[i];
  }
}

// The smallest k such that H has no entry off the diagonal in rows [k, NV) (lower triangle).
template <int NV>
int dense_block_size(const Eigen::Matrix<double, NV, NV>& H) {
  int k = 0;
  for (int j = 0; j < NV; ++j) {
    const double* col = H.data() + j * NV;
    for (int i = NV - 1; i >= std::max(k, j + 1); --i) {
      if (col[i] != 0.0) {
        k = i + 1;
        break;
      }
    }
  }
  return k;
}

// out = L⁻¹n. L⁻¹n is zero above n's first nonzero entry, so the solve starts there: a bound's
// n is ±eⱼ, and the WBC's friction rows touch only the contact forces, the last 24 of 58
// variables (a 24-long solve instead of 58).
template <int NV, int NE, int NI, typename Out>
void solve_normal_into(const DenseQp<NV, NE, NI>& qp, ConstraintCode c, const DenseQpWorkspace<NV, NE, NI>& ws,
                       Out&& out) {
  using C = Codes<NV, NE, NI>;
  int first = 0;
  if (c >= 0 && C::is_bound(c)) {
    first = C::row(c) - NI;
    out.setZero();
    out(first) = C::upper(c) ? -1.0 : 1.0;
  } else {
    C::normal(qp, c, out);
    while (first < NV && out(first) == 0.0) ++first;
  }
  solve_lower(ws, out.data(), first);
}

template <int NV, int NE, int NI>
void solve_normal(const DenseQp<NV, NE, NI>& qp, ConstraintCode c, DenseQpWorkspace<NV, NE, NI>& ws) {
  solve_normal_into(qp, c, ws, ws.v);
}

// From ws.v: d = R⁻ᵀVᵀv, r = R⁻¹d (dual direction), y = v − V r (the part of v outside the
// span of V), z = L⁻ᵀy (primal direction). Returns ‖y‖² = nᵀz.
template <int NV, int NE, int NI>
double project(DenseQpWorkspace<NV, NE, NI>& ws) {
  const int q = ws.q;
  ws.y = ws.v;
  if (q > 0) {
    const auto V1 = ws.V.leftCols(q);
    const auto R1 = ws.R.topLeftCorner(q, q).template triangularView<Eigen::Upper>();
    auto d = ws.d.head(q);
    auto r = ws.r.head(q);
    auto delta = ws.column.head(q);
    d.noalias() = V1.transpose() * ws.v;
    R1.transpose().solveInPlace(d);
    r = d;
    R1.solveInPlace(r);
    ws.y.noalias() -= V1 * r;
    // The first pass solves with R from a Gram matrix: y carries an error of about
    // ε·κ(R)²·‖v‖. When that is not negligible next to ‖y‖, a second pass on what the first
    // left removes it ("twice is enough", as in Gram–Schmidt). κ(R) is estimated from its
    // diagonal (a lower bound, good enough to find the ill-conditioned sets).
    double r_min = std::abs(ws.R(0, 0)), r_max = r_min;
    for (int k = 1; k < q; ++k) {
      const double a = std::abs(ws.R(k, k));
      r_min = std::min(r_min, a);
      r_max = std::max(r_max, a);
    }
    const double kappa = r_max / r_min;
    const double error = kRoundoff * kappa * kappa * ws.v.norm();
    if (!(error <= kSecondPassTolerance * ws.y.norm())) {
      delta.noalias() = V1.transpose() * ws.y;
      R1.transpose().solveInPlace(delta);
      d += delta;
      R1.solveInPlace(delta);
      r += delta;
      ws.y.noalias() -= V1 * delta;
    }
  }
  ws.z = ws.y;
  solve_lower_transpose(ws, ws.z.data());
  return ws.y.squaredNorm();
}

// Appends the constraint whose L⁻¹n is in ws.v, after project() (d and ‖y‖ = y_norm > 0).
template <int NV, int NE, int NI>
void add_to_working_set(DenseQpWorkspace<NV, NE, NI>& ws, ConstraintCode code, double multiplier, double y_norm) {
  const int q = ws.q;
  ws.V.col(q) = ws.v;
  ws.R.col(q).head(q) = ws.d.head(q);
  ws.R(q, q) = y_norm;
  ws.R.col(q).tail(NV - q - 1).setZero();
  ws.u(q) = multiplier;
  ws.active[q] = code;
  if (code >= 0) ws.is_active[code] = 1;
  ws.q = q + 1;
}

// Removes working-set position pos: its column leaves V, and Givens rotations from the left
// restore R to triangular form (V = Q R still holds with a rotated Q, which is never stored).
template <int NV, int NE, int NI>
void drop_from_working_set(DenseQpWorkspace<NV, NE, NI>& ws, int pos) {
  if (ws.active[pos] >= 0) ws.is_active[ws.active[pos]] = 0;
  const int q = ws.q - 1;
  for (int j = pos; j < q; ++j) {
    ws.V.col(j) = ws.V.col(j + 1);
    ws.R.col(j).head(j + 2) = ws.R.col(j + 1).head(j + 2);
    ws.active[j] = ws.active[j + 1];
    ws.u(j) = ws.u(j + 1);
  }
  ws.R.col(q).setZero();
  for (int j = pos; j < q; ++j) {
    const double a = ws.R(j, j), b = ws.R(j + 1, j);
    const double h = std::hypot(a, b);
    if (h == 0.0) continue;
    const double c = a / h, s = b / h;
    for (int k = j; k < q; ++k) {
      const double rj = ws.R(j, k), rj1 = ws.R(j + 1, k);
      ws.R(j, k) = c * rj + s * rj1;
      ws.R(j + 1, k) = -s * rj + c * rj1;
    }
    ws.R(j + 1, j) = 0.0;
  }
  ws.q = q;
}

// x and u of the minimizer of the cost with the working set taken as equalities:
// RᵀR u = rhs + Vᵀ(L⁻¹g), x = L⁻ᵀ(V u − L⁻¹g); then one step of iterative refinement on the
// working-set residuals rhs − Nᵀx, from the problem data.
template <int NV, int NE, int NI>
void working_set_minimizer(const DenseQp<NV, NE, NI>& qp, DenseQpWorkspace<NV, NE, NI>& ws) {
  using C = Codes<NV, NE, NI>;
  const int q = ws.q;
  ws.x = -ws.gt;
  if (q == 0) {
    solve_lower_transpose(ws, ws.x.data());
    return;
  }
  const auto V1 = ws.V.leftCols(q);
  const auto R1 = ws.R.topLeftCorner(q, q).template triangularView<Eigen::Upper>();
  auto u = ws.u.head(q);
  auto delta = ws.r.head(q);
  for (int k = 0; k < q; ++k) ws.rhs(k) = C::bound(qp, ws.active[k]);
  u = ws.rhs.head(q);
  u.noalias() += V1.transpose() * ws.gt;
  R1.transpose().solveInPlace(u);
  R1.solveInPlace(u);
  ws.x.noalias() += V1 * u;
  solve_lower_transpose(ws, ws.x.data());
  for (int k = 0; k < q; ++k) delta(k) = ws.rhs(k) - C::dot(qp, ws.active[k], ws.x);
  R1.transpose().solveInPlace(delta);
  R1.solveInPlace(delta);
  u += delta;
  ws.column.noalias() = V1 * delta;
  solve_lower_transpose(ws, ws.column.data());
  ws.x += ws.column;
}

// Imposes the m constraints codes[0, m) as the working set in one block: V = L⁻¹N by a
// triangular solve, R by the Cholesky of the Gram matrix VᵀV. Returns false (working set left
// empty) if the Cholesky says some are nearly dependent.
template <int NV, int NE, int NI>
bool impose_block(const DenseQp<NV, NE, NI>& qp, DenseQpWorkspace<NV, NE, NI>& ws, const ConstraintCode* codes, int m) {
  ws.q = 0;
  if (m == 0) return true;
  // V = L⁻¹N with L = [L₁₁ 0; 0 D] (dense_size): one blocked triangular solve with L₁₁ over
  // the leading rows of the columns that reach them, a scaling of the rest. The working set
  // is ordered so that those columns come first: the equalities, then the guess's rows that
  // reach into the dense block, then the rest (on the WBC: the friction rows and the force
  // bounds, whose L⁻¹n is n scaled). A dense problem keeps its order and one solve over all
  // of L. (Column by column from each normal's first nonzero, as the additions do, measured
  // slower on dense problems: 25 → 34 µs.)
  using C = Codes<NV, NE, NI>;
  const int kd = ws.dense_size;
  std::array<ConstraintCode, NV> ordered{};
  std::array<ConstraintCode, NV> parked{};
  int lead = 0, rest = 0;
  for (int k = 0; k < m; ++k) {  // leading columns into V in order, the rest parked in R
    auto n = ws.R.col(rest);
    C::normal(qp, codes[k], n);
    if (codes[k] < 0 || (n.head(kd).array() != 0.0).any()) {
      ws.V.col(lead) = n;
      ordered[lead++] = codes[k];
    } else {
      parked[rest++] = codes[k];
    }
  }
  for (int r = 0; r < rest; ++r) {
    ws.V.col(lead + r) = ws.R.col(r);
    ordered[lead + r] = parked[r];
  }
  const auto V1 = ws.V.leftCols(m);
  if (kd > 0 && lead > 0) {
    ws.L.topLeftCorner(kd, kd).template triangularView<Eigen::Lower>().solveInPlace(ws.V.topLeftCorner(kd, lead));
  }
  if (kd < NV) ws.V.block(kd, 0, NV - kd, m).array().colwise() *= ws.inv_diag.tail(NV - kd).array();
  // Gram matrix and its Cholesky factor in the lower triangle (Eigen's blocked Cholesky runs
  // column-major there), then R = Lᵀ.
  auto G = ws.R.topLeftCorner(m, m);
  G.template triangularView<Eigen::Lower>().setZero();
  G.template selfadjointView<Eigen::Lower>().rankUpdate(V1.transpose());
  ws.gram_diagonal.head(m) = G.diagonal();
  if (Eigen::internal::llt_inplace<double, Eigen::Lower>::blocked(G) >= 0) return false;
  for (int k = 0; k < m; ++k) {
    if (!(G(k, k) * G(k, k) > kBlockPivotTolerance * ws.gram_diagonal(k))) return false;
  }
  for (int j = 0; j < m; ++j) {
    for (int i = j + 1; i < m; ++i) {
      G(j, i) = G(i, j);
      G(i, j) = 0.0;
    }
  }
  for (int k = 0; k < m; ++k) {
    ws.active[k] = ordered[k];
    if (ordered[k] >= 0) ws.is_active[ordered[k]] = 1;
  }
  ws.q = m;
  return true;
}

// No NaN (infinities allowed: disabled sides). x ≠ x only for NaN.
template <typename M>
bool has_nan(const M& m) {
  return m.size() != 0 && (m.array() != m.array()).any();
}

template <int NV, int NE, int NI>
void write_solution(const DenseQp<NV, NE, NI>&, DenseQpWorkspace<NV, NE, NI>& ws,
                    DenseQpSolution<NV, NE, NI>& sol, QpStatus status, int iterations) {
  using C = Codes<NV, NE, NI>;
  sol.status = status;
  sol.iterations = iterations;
  sol.x = ws.x;
  sol.y_eq.setZero();
  sol.z_ineq.setZero();
  sol.z_bound.setZero();
  sol.working_set_size = 0;
  for (int k = 0; k < ws.q; ++k) {
    const ConstraintCode c = ws.active[k];
    if (c < 0) {
      sol.y_eq(-1 - c) = -ws.u(k);  // GI: Hx + g = Σ u n
      continue;
    }
    const double z = C::upper(c) ? ws.u(k) : -ws.u(k);
    if (C::is_bound(c)) {
      sol.z_bound(C::row(c) - NI) = z;
    } else {
      sol.z_ineq(C::row(c)) = z;
    }
    sol.working_set[sol.working_set_size++] = c;
  }
}

}  // namespace dense_detail

// Solves qp. With settings.warm_start, sol must hold the previous result (its working set is
// read before being overwritten). Returns sol.status. Allocation-free.
template <int NV, int NE, int NI>
QpStatus solve_dense_qp(const DenseQp<NV, NE, NI>& qp, const DenseQpSettings& settings,
                        DenseQpWorkspace<NV, NE, NI>& ws, DenseQpSolution<NV, NE, NI>& sol) {
  using namespace dense_detail;
  using Cd = Codes<NV, NE, NI>;
  using Workspace = DenseQpWorkspace<NV, NE, NI>;
  constexpr double kInf = kInfinity;
  const double dep_tol2 = settings.dependency_tolerance * settings.dependency_tolerance;
  int iterations = 0;

  // The block to impose first: every equality, then the warm-start guess (copied before
  // anything touches sol), as far as it is valid.
  std::array<ConstraintCode, NV> block{};
  int block_size = 0;
  for (int i = 0; i < NE; ++i) block[block_size++] = -1 - i;
  int guess_size = 0;
  if (settings.warm_start) {
    ws.is_active.fill(0);
    const int n = std::clamp(sol.working_set_size, 0, NV);
    for (int k = 0; k < n && block_size < NV && guess_size < settings.max_iterations; ++k) {
      const ConstraintCode c = sol.working_set[k];
      if (c < 0 || c >= Workspace::kNumCodes || ws.is_active[c]) continue;
      if (!std::isfinite(Cd::bound(qp, c))) continue;
      ws.is_active[c] = 1;
      block[block_size++] = c;
      ++guess_size;
    }
  }

  ws.q = 0;
  ws.num_eq_active = 0;
  ws.counters = DenseQpCounters{};
  ws.is_active.fill(0);
  ws.x.setZero();
  ws.u.setZero();

  // Bad data never reaches the arithmetic: NaN would poison every later tick via warm start.
  if (!all_finite(qp.H) || !all_finite(qp.g) || !all_finite(qp.A) || !all_finite(qp.b) ||
      !all_finite(qp.C) || has_nan(qp.c_lower) || has_nan(qp.c_upper) || has_nan(qp.x_lower) ||
      has_nan(qp.x_upper)) {
    write_solution(qp, ws, sol, QpStatus::kBadInput, 0);
    return sol.status;
  }
  if constexpr (NI > 0) {
    if ((qp.c_lower.array() > qp.c_upper.array()).any()) {
      write_solution(qp, ws, sol, QpStatus::kInfeasible, 0);
      return sol.status;
    }
  }
  if ((qp.x_lower.array() > qp.x_upper.array()).any()) {
    write_solution(qp, ws, sol, QpStatus::kInfeasible, 0);
    return sol.status;
  }

  // In place (no Eigen::LLT: its l1 norm is a strided pass over H for a condition estimate
  // that is never used), only H's dense leading block (dense_size); the rest of L is √diag(H).
  const int kd = dense_block_size(qp.H);
  ws.dense_size = kd;
  ws.L = qp.H;
  bool convex = true;
  if (kd > 0) {
    auto L11 = ws.L.topLeftCorner(kd, kd);
    convex = Eigen::internal::llt_inplace<double, Eigen::Lower>::unblocked(L11) < 0;
  }
  for (int i = kd; i < NV && convex; ++i) {
    convex = qp.H(i, i) > 0.0;
    ws.L(i, i) = std::sqrt(qp.H(i, i));
  }
  if (!convex) {
    write_solution(qp, ws, sol, QpStatus::kNotConvex, 0);
    return sol.status;
  }
  for (int i = 0; i < NV; ++i) {  // down Lt's columns: its writes stay sequential
    ws.inv_diag(i) = 1.0 / ws.L(i, i);
    if (i < kd) {
      for (int j = 0; j < i; ++j) ws.Lt(j, i) = ws.L(i, j);
    }
  }
  ws.gt = qp.g;
  solve_lower(ws, ws.gt.data());
  ws.bound_weight = qp.H.diagonal().cwiseSqrt();  // H is positive definite here: H_jj > 0
  if constexpr (NI > 0) {
    // Row norms, plain and in the metric diag(H)⁻¹, in one pass down C's columns (a row of
    // the column-major C is strided).
    ws.cx.setZero();  // scratch: Σⱼ C_ij²
    ws.row_weight.setZero();  // scratch: Σⱼ C_ij² / H_jj
    for (int j = 0; j < NV; ++j) {
      const double inv_h = 1.0 / qp.H(j, j);
      ws.cx.array() += qp.C.col(j).array().square();
      ws.row_weight.array() += inv_h * qp.C.col(j).array().square();
    }
    for (int i = 0; i < NI; ++i) {
      ws.inv_row_norm(i) = ws.cx(i) > 0.0 ? 1.0 / std::sqrt(ws.cx(i)) : 0.0;
      ws.row_weight(i) = ws.row_weight(i) > 0.0 ? 1.0 / std::sqrt(ws.row_weight(i)) : 0.0;
    }
  }
  // Multipliers beyond this (times their row norm) mean the dual is unbounded: infeasible.
  const double multiplier_limit =
      settings.infeasible_multiplier *
      std::max({1.0, qp.g.cwiseAbs().maxCoeff(), qp.H.diagonal().cwiseAbs().maxCoeff()});

  if (impose_block(qp, ws, block.data(), block_size)) {
    ws.num_eq_active = NE;
    iterations = guess_size;
    ws.counters.guess_imposed = guess_size;
    working_set_minimizer(qp, ws);
  } else {
    // Some of the block is (nearly) dependent: add one constraint at a time from the
    // unconstrained minimizer, each with a full step, testing dependency exactly.
    ws.q = 0;
    ws.is_active.fill(0);
    working_set_minimizer(qp, ws);
    // Equalities: always in the working set, in order. A dependent row is dropped if it is
    // consistent with the others (redundant), otherwise the problem is infeasible.
    for (int k = 0; k < block_size; ++k) {
      const ConstraintCode c = block[k];
      if (c >= 0 && iterations >= settings.max_iterations) break;
      solve_normal(qp, c, ws);
      const double zn = project(ws);
      const double residual = Cd::bound(qp, c) - Cd::dot(qp, c, ws.x);
      if (zn <= dep_tol2 * ws.v.squaredNorm()) {
        if (c >= 0) continue;  // a guess: skip it
        const int i = -1 - c;
        const double scale = 1.0 + std::abs(qp.b(i)) + qp.A.row(i).norm() * ws.x.norm();
        if (std::abs(residual) <= settings.primal_tolerance * scale) continue;  // redundant
        write_solution(qp, ws, sol, QpStatus::kInfeasible, 0);
        return sol.status;
      }
      const double t = residual / zn;
      ws.u.head(ws.q) -= t * ws.r.head(ws.q);
      add_to_working_set(ws, c, t, std::sqrt(zn));
      ws.x += t * ws.z;
      if (c < 0) {
        ws.num_eq_active = ws.q;
      } else {
        ++iterations;
        ++ws.counters.guess_imposed;
      }
    }
  }

  // Restore dual feasibility: drop every inequality with a negative multiplier, re-solve,
  // until none is negative (each round shrinks the working set, so this ends). One re-solve
  // per round instead of one per dropped constraint: after a jump in the reference most of
  // the guess can be wrong at once (measured on the WBC: 10 of 14 rows).
  while (iterations < settings.max_iterations) {
    int dropped = 0;
    for (int k = ws.q - 1; k >= ws.num_eq_active; --k) {  // from the end: cheaper re-triangulation
      if (ws.u(k) < 0.0) {
        drop_from_working_set(ws, k);
        ++dropped;
      }
    }
    if (dropped == 0) break;
    working_set_minimizer(qp, ws);
    iterations += dropped;
    ws.counters.guess_dropped += dropped;
    ++ws.counters.drop_rounds;
  }

  // Main GI loop: add the most violated inequality, dropping blocking ones on the way.
  for (;;) {
    if constexpr (NI > 0) ws.cx.noalias() = qp.C * ws.x;
    ConstraintCode p = -1;
    const double tol = settings.primal_tolerance;
    double worst = 0.0;
    for (int i = 0; i < NI; ++i) {
      const double lo = qp.c_lower(i) - ws.cx(i), hi = ws.cx(i) - qp.c_upper(i);
      const double w = ws.row_weight(i);
      if (lo * ws.inv_row_norm(i) > tol && lo * w > worst && !ws.is_active[2 * i]) { worst = lo * w; p = 2 * i; }
      if (hi * ws.inv_row_norm(i) > tol && hi * w > worst && !ws.is_active[2 * i + 1]) { worst = hi * w; p = 2 * i + 1; }
    }
    for (int j = 0; j < NV; ++j) {
      const double lo = qp.x_lower(j) - ws.x(j), hi = ws.x(j) - qp.x_upper(j);
      const double w = ws.bound_weight(j);
      const int c = 2 * (NI + j);
      if (lo > tol && lo * w > worst && !ws.is_active[c]) { worst = lo * w; p = c; }
      if (hi > tol && hi * w > worst && !ws.is_active[c + 1]) { worst = hi * w; p = c + 1; }
    }
    if (p < 0) {
      write_solution(qp, ws, sol, QpStatus::kSolved, iterations);
      return sol.status;
    }
    const double bnd = Cd::bound(qp, p);
    const double p_norm = Cd::row(p) < NI ? 1.0 / ws.inv_row_norm(Cd::row(p)) : 1.0;
    double slack = Cd::dot(qp, p, ws.x) - bnd;  // < 0: violated
    double u_plus = 0.0;
    solve_normal(qp, p, ws);  // L⁻¹n does not depend on the working set
    const double v_norm2 = ws.v.squaredNorm();
    for (;;) {
      if (iterations >= settings.max_iterations) {
        write_solution(qp, ws, sol, QpStatus::kMaxIterations, iterations);
        return sol.status;
      }
      const double zn = project(ws);
      // Dual step bound: the first working-set inequality whose multiplier reaches zero.
      double t1 = kInf;
      int blocking = -1;
      for (int k = ws.num_eq_active; k < ws.q; ++k) {
        if (ws.r(k) > 0.0) {
          const double ratio = ws.u(k) / ws.r(k);
          if (ratio < t1) { t1 = ratio; blocking = k; }
        }
      }
      const double t2 = zn > dep_tol2 * v_norm2 ? -slack / zn : kInf;
      if (t1 == kInf && t2 == kInf) {
        // p is a combination of working-set normals that cannot be relaxed: no x satisfies all.
        write_solution(qp, ws, sol, QpStatus::kInfeasible, iterations);
        return sol.status;
      }
      const double t = std::min(t1, t2);
      if (t2 < kInf) ws.x += t * ws.z;
      ws.u.head(ws.q) -= t * ws.r.head(ws.q);
      u_plus += t;
      ++iterations;
      if (u_plus * p_norm > multiplier_limit) {
        write_solution(qp, ws, sol, QpStatus::kInfeasible, iterations);
        return sol.status;
      }
      if (t2 <= t1) {
        add_to_working_set(ws, p, u_plus, std::sqrt(zn));
        ++ws.counters.additions;
        break;
      }
      drop_from_working_set(ws, blocking);
      ++ws.counters.blocking_drops;
      slack = Cd::dot(qp, p, ws.x) - bnd;
    }
  }
}

}  // namespace kuavo::qp
