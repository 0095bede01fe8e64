// Small dense QP with box constraints only:
//   minimize ½ xᵀ H x − gᵀ x   subject to   lo ≤ x ≤ hi   (±infinity allowed)
// for symmetric positive definite H. Primal active-set method: start from the feasible
// point closest to 0, solve the equality-constrained problem on the free variables by
// Cholesky (fixed size: fixed variables get an identity row), step to the first bound that
// blocks, release a bound whose multiplier has the wrong sign. Finite: each step either
// adds a bound or strictly lowers the objective. No allocation (fixed-size Eigen).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>

namespace kuavo::mocap {

template <int N>
struct BoxQpResult {
  bool converged = false;
  int iterations = 0;
  std::array<std::int8_t, N> bound{};  // -1 at lower, +1 at upper, 0 free
};

template <int N>
BoxQpResult<N> solve_box_qp(const Eigen::Matrix<double, N, N>& h, const Eigen::Matrix<double, N, 1>& g,
                            const Eigen::Matrix<double, N, 1>& lo, const Eigen::Matrix<double, N, 1>& hi,
                            Eigen::Matrix<double, N, 1>& x, int max_iterations = 4 * N) {
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  BoxQpResult<N> r;
  for (int i = 0; i < N; ++i) {
    x[i] = std::fmin(std::fmax(0.0, lo[i]), hi[i]);
    r.bound[i] = x[i] == lo[i] && lo[i] > -INFINITY ? -1 : (x[i] == hi[i] && hi[i] < INFINITY ? 1 : 0);
    if (lo[i] == hi[i]) r.bound[i] = -1;
  }
  constexpr double kMultiplierTol = 1e-12;
  Mat m;
  Vec rhs, y;
  Eigen::LLT<Mat> llt;
  for (r.iterations = 0; r.iterations < max_iterations; ++r.iterations) {
    // Equality-constrained subproblem: free rows of H, fixed variables pinned.
    m = h;
    rhs = g;
    for (int i = 0; i < N; ++i) {
      if (r.bound[i] == 0) continue;
      rhs.noalias() -= h.col(i) * x[i];
    }
    for (int i = 0; i < N; ++i) {
      if (r.bound[i] == 0) continue;
      m.row(i).setZero();
      m.col(i).setZero();
      m(i, i) = 1.0;
      rhs[i] = x[i];
    }
    llt.compute(m);
    y = llt.solve(rhs);
    // Largest step toward y that stays feasible.
    double alpha = 1.0;
    int blocking = -1;
    for (int i = 0; i < N; ++i) {
      if (r.bound[i] != 0) continue;
      const double d = y[i] - x[i];
      if (y[i] < lo[i] && d < 0.0) {
        const double a = (lo[i] - x[i]) / d;
        if (a < alpha) alpha = a, blocking = i;
      } else if (y[i] > hi[i] && d > 0.0) {
        const double a = (hi[i] - x[i]) / d;
        if (a < alpha) alpha = a, blocking = i;
      }
    }
    if (blocking >= 0) {
      x += std::fmax(alpha, 0.0) * (y - x);
      const bool lower = y[blocking] < lo[blocking];
      x[blocking] = lower ? lo[blocking] : hi[blocking];
      r.bound[blocking] = lower ? -1 : 1;
      continue;
    }
    x = y;
    // Multipliers of the fixed variables: the gradient H x − g must push into the bound.
    const Vec grad = h * x - g;
    int release = -1;
    double worst = kMultiplierTol;
    for (int i = 0; i < N; ++i) {
      if (r.bound[i] == 0 || lo[i] == hi[i]) continue;
      const double wrong = r.bound[i] < 0 ? -grad[i] : grad[i];  // > 0: leaving the bound lowers the cost
      if (wrong > worst) worst = wrong, release = i;
    }
    if (release < 0) {
      r.converged = true;
      ++r.iterations;
      return r;
    }
    r.bound[release] = 0;
  }
  return r;
}

}  // namespace kuavo::mocap
