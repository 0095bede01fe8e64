// Dense convex QP with compile-time sizes (the WBC and the retargeting IK):
//
//   minimize    ½ xᵀ H x + gᵀ x
//   subject to  A x = b                       (NE rows)
//               c_lower ≤ C x ≤ c_upper       (NI rows; ±kInfinity disables a side)
//               x_lower ≤ x ≤ x_upper         (±kInfinity disables a side)
//
// Sign convention of the multipliers (the same as OSQP): at a solution
//   H x + g + Aᵀ y_eq + Cᵀ z_ineq + z_bound = 0,
// with z ≥ 0 on a row at its upper bound, z ≤ 0 at its lower bound and z = 0 if inactive.
//
// All storage is fixed-size: a DenseQp is ~NV²+NI·NV doubles (55 KB at NV = 82), the
// workspace about twice that. Keep them in static storage, not on a real-time stack.
// The solver is in dense_qp_solver.h.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>

#include "controllers/qp/qp_status.h"

namespace kuavo::qp {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

template <int NV, int NE, int NI>
struct DenseQp {
  static_assert(NV > 0 && NE >= 0 && NI >= 0, "sizes");
  static_assert(NE <= NV, "more equalities than variables can only be redundant or infeasible");
  using Vector = Eigen::Matrix<double, NV, 1>;

  Eigen::Matrix<double, NV, NV> H = Eigen::Matrix<double, NV, NV>::Identity();  // lower triangle read
  Vector g = Vector::Zero();
  Eigen::Matrix<double, NE, NV> A = Eigen::Matrix<double, NE, NV>::Zero();
  Eigen::Matrix<double, NE, 1> b = Eigen::Matrix<double, NE, 1>::Zero();
  Eigen::Matrix<double, NI, NV> C = Eigen::Matrix<double, NI, NV>::Zero();
  Eigen::Matrix<double, NI, 1> c_lower = Eigen::Matrix<double, NI, 1>::Constant(-kInfinity);
  Eigen::Matrix<double, NI, 1> c_upper = Eigen::Matrix<double, NI, 1>::Constant(kInfinity);
  Vector x_lower = Vector::Constant(-kInfinity);
  Vector x_upper = Vector::Constant(kInfinity);
};

struct DenseQpSettings {
  // Cap on working-set changes (each adds or drops one inequality, O(NV²) flops), so the
  // worst-case time is bounded. On hitting it the status is kMaxIterations and x is the
  // minimizer of the cost subject to the equalities and the current working set taken as
  // equalities: it satisfies those exactly but may violate other inequalities.
  int max_iterations = 200;
  // A row counts as satisfied when its violation, divided by its row norm (distance in x
  // units), is below this. 1e-9 is ~1e4 ulp of a unit-scale WBC variable.
  double primal_tolerance = 1e-9;
  // A new constraint normal whose component outside the span of the working set is below
  // this fraction of its length (in the H⁻¹ metric) counts as linearly dependent.
  double dependency_tolerance = 1e-10;
  // The dual of an infeasible QP is unbounded. A multiplier whose size (times its row norm)
  // passes this multiple of the data scale max(1, ‖g‖∞, max|Hᵢⱼ|) ends the solve with
  // kInfeasible: in a nearly dependent working set roundoff would otherwise let GI take
  // ever larger steps until the iteration cap. A feasible problem needs multipliers of the
  // order of its gradient (times the conditioning of the active rows), far below this.
  double infeasible_multiplier = 1e12;
  // Start from the working set stored in the solution passed in (the previous tick's).
  bool warm_start = false;
};

// Working-set entry code for inequalities: 2·row + side, side 0 = lower, 1 = upper; rows
// [0, NI) are C's rows, rows [NI, NI + NV) the variable bounds.
using ConstraintCode = std::int32_t;

template <int NV, int NE, int NI>
struct DenseQpSolution {
  Eigen::Matrix<double, NV, 1> x = Eigen::Matrix<double, NV, 1>::Zero();
  Eigen::Matrix<double, NE, 1> y_eq = Eigen::Matrix<double, NE, 1>::Zero();
  Eigen::Matrix<double, NI, 1> z_ineq = Eigen::Matrix<double, NI, 1>::Zero();
  Eigen::Matrix<double, NV, 1> z_bound = Eigen::Matrix<double, NV, 1>::Zero();
  QpStatus status = QpStatus::kBadInput;
  int iterations = 0;  // working-set changes, warm-start additions included
  // Active inequalities at return; the warm start of the next solve.
  std::array<ConstraintCode, NV> working_set{};
  int working_set_size = 0;
};

// What the last solve spent its working-set changes on (solution.iterations is their sum):
// for benchmarks and diagnostics, written by the solver, never read by it.
struct DenseQpCounters {
  int guess_imposed = 0;  // warm-start rows imposed at the start
  int guess_dropped = 0;  // of those, dropped for a negative multiplier before the GI loop
  int drop_rounds = 0;    // re-solves those drops took
  int additions = 0;      // GI: constraints added
  int blocking_drops = 0; // GI: working-set members dropped on the way to an addition
};

template <int NV, int NE, int NI>
struct DenseQpWorkspace {
  using Vector = Eigen::Matrix<double, NV, 1>;
  using Square = Eigen::Matrix<double, NV, NV>;
  static constexpr int kNumCodes = 2 * (NI + NV);

  Square L = Square::Zero();  // H = L Lᵀ in the lower triangle (the strict upper holds H's)
  // Lᵀ in the upper triangle: the solves with Lᵀ then run down columns (axpy form) too.
  Square Lt = Square::Zero();
  Vector inv_diag = Vector::Zero();   // 1 / L(i, i)
  // H's rows [dense_size, NV) have no entry off the diagonal (the WBC's contact forces carry a
  // diagonal weight only), so L is [L₁₁ 0; 0 D] with L₁₁ dense_size × dense_size: only that
  // block is factored and the triangular solves scale the rest. Lt holds stale values
  // outside the block (nothing reads them); L outside it is H's zeros and diagonal √H_ii.
  int dense_size = NV;
  // Range-space Goldfarb–Idnani factors of the working set (normals N, q of them):
  // columns [0, q) of V are L⁻¹N, and R (upper triangular, q×q) is the triangle of the QR
  // factorization V = Q R, i.e. RᵀR = NᵀH⁻¹N. Q itself is never formed.
  Square V = Square::Zero();
  Square R = Square::Zero();
  Vector v = Vector::Zero();          // L⁻¹n for the constraint being added
  Vector d = Vector::Zero();          // Qᵀv = R⁻ᵀVᵀv (first q entries)
  Vector y = Vector::Zero();          // v minus its projection on the span of V: ‖y‖² = nᵀz
  Vector z = Vector::Zero();          // primal step direction L⁻ᵀy
  Vector r = Vector::Zero();          // dual step direction R⁻¹d (working set)
  Vector u = Vector::Zero();          // multipliers of the working set, GI sign (≥ 0 for inequalities)
  Vector x = Vector::Zero();
  Vector gt = Vector::Zero();         // L⁻¹g
  Vector column = Vector::Zero();     // scratch
  Vector rhs = Vector::Zero();        // working-set bounds (right-hand sides)
  Vector gram_diagonal = Vector::Zero();
  Eigen::Matrix<double, NI, 1> cx = Eigen::Matrix<double, NI, 1>::Zero();
  Eigen::Matrix<double, NI, 1> inv_row_norm = Eigen::Matrix<double, NI, 1>::Zero();
  // Selection weights (see the GI loop): 1/‖D^-½ n‖ per row, √H_jj per bound, D = diag(H).
  Eigen::Matrix<double, NI, 1> row_weight = Eigen::Matrix<double, NI, 1>::Zero();
  Vector bound_weight = Vector::Zero();
  std::array<ConstraintCode, NV> active{};  // equalities as -1 - i, first
  std::array<std::uint8_t, kNumCodes> is_active{};
  int q = 0;
  int num_eq_active = 0;
  DenseQpCounters counters;
};

}  // namespace kuavo::qp
