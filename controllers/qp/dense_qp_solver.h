// Dense QP solver: the Goldfarb–Idnani dual active-set method (Math. Prog. 27, 1983), in
// the factored form of QuadProg, with a warm start from the previous working set.
//
// Why this method: the WBC and IK Hessians are strictly convex by construction (task weights
// plus regularization), which is exactly GI's requirement; it needs no feasible starting point
// (the WBC has none at hand); every iterate is dual feasible, so after the cap one still has the
// minimizer over a subset of the constraints; and each working-set change costs O(NV²) with no
// refactorization. Adding a constraint uses one Householder reflection (4·NV·(NV−q) flops)
// instead of QuadProg's chain of Givens rotations; dropping one restores R with Givens.
//
// Warm start: the previous working set is first imposed as equalities, then members with a
// negative multiplier are dropped one at a time. The result is a valid GI starting point (the
// minimizer over a working set, dual feasible), so correctness never depends on the guess; a
// good guess only removes the add/drop iterations.
//
// Real-time: no allocation, no exceptions; cost ≤ one Cholesky + inverse (≈ NV³) plus
// (NE + max_iterations) · O(NV²).
#pragma once

#include <Eigen/Householder>
#include <algorithm>
#include <cmath>

#include "controllers/qp/dense_qp.h"

namespace kuavo::qp {
namespace dense_detail {

// Constraint code helpers: the inequality is written GI-style as nᵀx ≥ bound.
template <int NV, int NE, int NI>
struct Codes {
  static int row(ConstraintCode c) { return c >> 1; }
  static bool upper(ConstraintCode c) { return (c & 1) != 0; }
  static bool is_bound(ConstraintCode c) { return row(c) >= NI; }

  static double bound(const DenseQp<NV, NE, NI>& qp, ConstraintCode c) {
    const int i = row(c);
    if (i < NI) return upper(c) ? -qp.c_upper(i) : qp.c_lower(i);
    return upper(c) ? -qp.x_upper(i - NI) : qp.x_lower(i - NI);
  }
  // nᵀv
  template <typename V>
  static double dot(const DenseQp<NV, NE, NI>& qp, ConstraintCode c, const V& v) {
    const int i = row(c);
    const double s = upper(c) ? -1.0 : 1.0;
    if constexpr (NI > 0) {
      if (i < NI) return s * qp.C.row(i).dot(v);
    }
    return s * v(i - NI);
  }
  // ws.d = Jᵀ n
  static void project(const DenseQp<NV, NE, NI>& qp, ConstraintCode c, DenseQpWorkspace<NV, NE, NI>& ws) {
    const int i = row(c);
    if constexpr (NI > 0) {
      if (i < NI) {
        ws.d.noalias() = ws.J.transpose() * qp.C.row(i).transpose();
      } else {
        ws.d = ws.J.row(i - NI).transpose();
      }
    } else {
      ws.d = ws.J.row(i - NI).transpose();  // n is a unit vector: a row of J
    }
    if (upper(c)) ws.d = -ws.d;
  }
};

// From ws.d: z = J₂ d₂ (primal direction), r = R⁻¹ d₁ (dual direction). Returns ‖d₂‖² = nᵀz.
template <int NV, int NE, int NI>
double step_directions(DenseQpWorkspace<NV, NE, NI>& ws) {
  const int q = ws.q, m = NV - q;
  if (m > 0) {
    ws.z.noalias() = ws.J.rightCols(m) * ws.d.tail(m);
  } else {
    ws.z.setZero();
  }
  if (q > 0) {
    ws.r.head(q) = ws.d.head(q);
    ws.R.topLeftCorner(q, q).template triangularView<Eigen::Upper>().solveInPlace(ws.r.head(q));
  }
  return m > 0 ? ws.d.tail(m).squaredNorm() : 0.0;
}

// As step_directions but without z, for a constraint that will be added with a full step:
// then z = β·(new column q of J) after the reflection (J₂ d₂ = J₂H·H d₂ = J₂H·β e₁), which
// saves one pass over J. Returns ‖d₂‖².
template <int NV, int NE, int NI>
double dual_direction(DenseQpWorkspace<NV, NE, NI>& ws) {
  const int q = ws.q, m = NV - q;
  if (q > 0) {
    ws.r.head(q) = ws.d.head(q);
    ws.R.topLeftCorner(q, q).template triangularView<Eigen::Upper>().solveInPlace(ws.r.head(q));
  }
  return m > 0 ? ws.d.tail(m).squaredNorm() : 0.0;
}

// Appends the constraint whose Jᵀn is in ws.d (its component outside the span must be nonzero).
template <int NV, int NE, int NI>
void add_to_working_set(DenseQpWorkspace<NV, NE, NI>& ws, ConstraintCode code, double multiplier) {
  const int q = ws.q, m = NV - q;
  double tau = 0.0, beta = 0.0;
  auto tail = ws.d.tail(m);
  auto essential = ws.householder.head(m - 1);
  tail.makeHouseholder(essential, tau, beta);
  ws.J.rightCols(m).applyHouseholderOnTheRight(essential, tau, ws.column.data());
  ws.R.col(q).head(q) = ws.d.head(q);
  ws.R(q, q) = beta;
  ws.beta = beta;
  ws.u(q) = multiplier;
  ws.active[q] = code;
  if (code >= 0) ws.is_active[code] = 1;
  ws.q = q + 1;
}

// Removes working-set position pos and restores R to triangular form with Givens rotations,
// applied to the same columns of J so that L⁻¹N = Q R still holds.
template <int NV, int NE, int NI>
void drop_from_working_set(DenseQpWorkspace<NV, NE, NI>& ws, int pos) {
  if (ws.active[pos] >= 0) ws.is_active[ws.active[pos]] = 0;
  const int q = ws.q - 1;
  for (int j = pos; j < q; ++j) {
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
    ws.column = c * ws.J.col(j) + s * ws.J.col(j + 1);
    ws.J.col(j + 1) = -s * ws.J.col(j) + c * ws.J.col(j + 1);
    ws.J.col(j) = ws.column;
  }
  ws.q = q;
}

template <typename M>
bool all_finite(const M& m) {
  return m.size() == 0 || m.allFinite();
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
  constexpr double kInf = kInfinity;
  const double dep_tol2 = settings.dependency_tolerance * settings.dependency_tolerance;
  int iterations = 0;

  // Copy the warm-start guess before anything touches sol.
  std::array<ConstraintCode, NV> guess{};
  int guess_size = 0;
  if (settings.warm_start) {
    guess_size = std::clamp(sol.working_set_size, 0, NV);
    std::copy_n(sol.working_set.begin(), guess_size, guess.begin());
  }

  ws.q = 0;
  ws.num_eq_active = 0;
  ws.is_active.fill(0);
  ws.x.setZero();
  ws.u.setZero();

  // Bad data never reaches the arithmetic: NaN would poison every later tick via warm start.
  if (!all_finite(qp.H) || !all_finite(qp.g) || !all_finite(qp.A) || !all_finite(qp.b) ||
      !all_finite(qp.C) || qp.c_lower.hasNaN() || qp.c_upper.hasNaN() || qp.x_lower.hasNaN() ||
      qp.x_upper.hasNaN()) {
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

  ws.llt.compute(qp.H);
  if (ws.llt.info() != Eigen::Success) {
    write_solution(qp, ws, sol, QpStatus::kNotConvex, 0);
    return sol.status;
  }
  // J = L⁻ᵀ, row by row: row j of J is L⁻¹e_j, nonzero from j on, so each is a triangular
  // solve of size NV − j (NV³/3 flops in all, a third of a solve against the identity).
  ws.J.setZero();
  for (int j = 0; j < NV; ++j) {
    const int m = NV - j;
    ws.column.head(m).setZero();
    ws.column(0) = 1.0;
    ws.llt.matrixLLT().bottomRightCorner(m, m).template triangularView<Eigen::Lower>().solveInPlace(ws.column.head(m));
    ws.J.row(j).tail(m) = ws.column.head(m).transpose();
  }
  ws.R.setZero();
  ws.x = -qp.g;
  ws.llt.solveInPlace(ws.x);  // unconstrained minimizer
  if constexpr (NI > 0) {
    for (int i = 0; i < NI; ++i) {
      const double n = qp.C.row(i).norm();
      ws.inv_row_norm(i) = n > 0.0 ? 1.0 / n : 0.0;
    }
  }

  // Equalities: always in the working set, in order. A dependent row is dropped if it is
  // consistent with the others (redundant), otherwise the problem is infeasible.
  if constexpr (NE > 0) for (int i = 0; i < NE; ++i) {
    ws.d.noalias() = ws.J.transpose() * qp.A.row(i).transpose();
    const double zn = dual_direction(ws);
    const double residual = qp.b(i) - qp.A.row(i).dot(ws.x);
    if (zn <= dep_tol2 * ws.d.squaredNorm()) {
      const double scale = 1.0 + std::abs(qp.b(i)) + qp.A.row(i).norm() * ws.x.norm();
      if (std::abs(residual) <= settings.primal_tolerance * scale) continue;  // redundant
      write_solution(qp, ws, sol, QpStatus::kInfeasible, 0);
      return sol.status;
    }
    const double t = residual / zn;
    ws.u.head(ws.q) -= t * ws.r.head(ws.q);
    add_to_working_set(ws, -1 - i, t);
    ws.x += (t * ws.beta) * ws.J.col(ws.q - 1);
  }
  ws.num_eq_active = ws.q;

  // Warm start: impose the guess, then restore dual feasibility by dropping negative multipliers.
  for (int k = 0; k < guess_size && iterations < settings.max_iterations; ++k) {
    const ConstraintCode c = guess[k];
    if (c < 0 || c >= DenseQpWorkspace<NV, NE, NI>::kNumCodes || ws.is_active[c] || ws.q >= NV) continue;
    const double bnd = Cd::bound(qp, c);
    if (!std::isfinite(bnd)) continue;
    Cd::project(qp, c, ws);
    const double zn = dual_direction(ws);
    if (zn <= dep_tol2 * ws.d.squaredNorm()) continue;
    const double t = -(Cd::dot(qp, c, ws.x) - bnd) / zn;
    ws.u.head(ws.q) -= t * ws.r.head(ws.q);
    add_to_working_set(ws, c, t);
    ws.x += (t * ws.beta) * ws.J.col(ws.q - 1);
    ++iterations;
  }
  while (iterations < settings.max_iterations) {
    int worst = -1;
    double worst_u = 0.0;
    for (int k = ws.num_eq_active; k < ws.q; ++k) {
      if (ws.u(k) < worst_u) {
        worst_u = ws.u(k);
        worst = k;
      }
    }
    if (worst < 0) break;
    const ConstraintCode c = ws.active[worst];
    drop_from_working_set(ws, worst);
    Cd::project(qp, c, ws);
    step_directions(ws);
    const double t = -worst_u;  // moves this multiplier to zero
    ws.x += t * ws.z;
    ws.u.head(ws.q) -= t * ws.r.head(ws.q);
    ++iterations;
  }

  // Main GI loop: add the most violated inequality, dropping blocking ones on the way.
  for (;;) {
    if constexpr (NI > 0) ws.cx.noalias() = qp.C * ws.x;
    ConstraintCode p = -1;
    double worst = settings.primal_tolerance;
    for (int i = 0; i < NI; ++i) {
      const double lo = (qp.c_lower(i) - ws.cx(i)) * ws.inv_row_norm(i);
      const double hi = (ws.cx(i) - qp.c_upper(i)) * ws.inv_row_norm(i);
      if (lo > worst && !ws.is_active[2 * i]) { worst = lo; p = 2 * i; }
      if (hi > worst && !ws.is_active[2 * i + 1]) { worst = hi; p = 2 * i + 1; }
    }
    for (int j = 0; j < NV; ++j) {
      const double lo = qp.x_lower(j) - ws.x(j), hi = ws.x(j) - qp.x_upper(j);
      const int c = 2 * (NI + j);
      if (lo > worst && !ws.is_active[c]) { worst = lo; p = c; }
      if (hi > worst && !ws.is_active[c + 1]) { worst = hi; p = c + 1; }
    }
    if (p < 0) {
      write_solution(qp, ws, sol, QpStatus::kSolved, iterations);
      return sol.status;
    }
    const double bnd = Cd::bound(qp, p);
    double slack = Cd::dot(qp, p, ws.x) - bnd;  // < 0: violated
    double u_plus = 0.0;
    for (;;) {
      if (iterations >= settings.max_iterations) {
        write_solution(qp, ws, sol, QpStatus::kMaxIterations, iterations);
        return sol.status;
      }
      Cd::project(qp, p, ws);
      const double zn = step_directions(ws);
      // Dual step bound: the first working-set inequality whose multiplier reaches zero.
      double t1 = kInf;
      int blocking = -1;
      for (int k = ws.num_eq_active; k < ws.q; ++k) {
        if (ws.r(k) > 0.0) {
          const double ratio = ws.u(k) / ws.r(k);
          if (ratio < t1) { t1 = ratio; blocking = k; }
        }
      }
      const double t2 = zn > dep_tol2 * ws.d.squaredNorm() ? -slack / zn : kInf;
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
      if (t2 <= t1) {
        add_to_working_set(ws, p, u_plus);
        break;
      }
      drop_from_working_set(ws, blocking);
      slack = Cd::dot(qp, p, ws.x) - bnd;
    }
  }
}

}  // namespace kuavo::qp
