// Optimal-control-structured QP (the centroidal MPC's subproblem), compile-time capacities:
//
//   minimize   Σ_{k<T} ½xₖᵀQₖxₖ + uₖᵀSₖxₖ + ½uₖᵀRₖuₖ + qₖᵀxₖ + rₖᵀuₖ  +  ½x_TᵀQ_Tx_T + q_Tᵀx_T
//   subject to x₀ = x_initial
//              xₖ₊₁ = Aₖxₖ + Bₖuₖ + bₖ                 k < T
//              Cₖxₖ + Dₖuₖ = eₖ    (first num_eq rows)   k < T   (state-input equalities)
//              Gxₖxₖ + Guₖuₖ ≤ hₖ  (first num_ineq rows) k ≤ T   (Gu unused at k = T)
//
// T = horizon ≤ N. Q and R are read in full (keep them symmetric). Each Dₖ needs full row rank:
// pure state equalities are not supported (write them as penalties, as OCS2 does), and the
// terminal stage takes no equalities. NC/NG are per-stage row capacities; NC or NG may be 0.
//
// Multipliers (all with + sign in the Lagrangian  cost + Σ πₖ₊₁ᵀ(Aₖxₖ + Bₖuₖ + bₖ − xₖ₊₁)
// + π₀ᵀ(x_initial − x₀) + Σ νₖᵀ(Cₖxₖ + Dₖuₖ − eₖ) + Σ λₖᵀ(Gxₖxₖ + Guₖuₖ − hₖ)), λ ≥ 0.
//
// Sizes: one stage at NX = 38, NU = 50 is ~90 KB; keep an OcpQp in static storage.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "controllers/qp/qp_status.h"

namespace kuavo::qp {

template <int NX, int NU, int NC, int NG>
struct OcpStage {
  Eigen::Matrix<double, NX, NX> A = Eigen::Matrix<double, NX, NX>::Identity();
  Eigen::Matrix<double, NX, NU> B = Eigen::Matrix<double, NX, NU>::Zero();
  Eigen::Matrix<double, NX, 1> b = Eigen::Matrix<double, NX, 1>::Zero();

  Eigen::Matrix<double, NX, NX> Q = Eigen::Matrix<double, NX, NX>::Identity();
  Eigen::Matrix<double, NU, NX> S = Eigen::Matrix<double, NU, NX>::Zero();
  // true promises S = 0 (keep it so: the KKT residual still reads it), and the Riccati
  // recursion then does not read S: a stage without cross terms (the centroidal MPC's) spares
  // S's 15 KB of the ~82 KB fetched per stage and factorization (the x-u block is ZᵀZ alone).
  bool s_zero = false;
  // R is zero outside its leading r_dense × r_dense block and its diagonal (r_dense = NU: no
  // structure), and the Riccati recursion reads only those (and R's 4×4 diagonal blocks): the
  // MPC's R is its force block (friction and leg-torque barriers) and the joint velocities'
  // diagonal, ~2/3 of the lower triangle's cache lines not fetched.
  int r_dense = NU;
  Eigen::Matrix<double, NU, NU> R = Eigen::Matrix<double, NU, NU>::Identity();
  Eigen::Matrix<double, NX, 1> q = Eigen::Matrix<double, NX, 1>::Zero();
  Eigen::Matrix<double, NU, 1> r = Eigen::Matrix<double, NU, 1>::Zero();

  Eigen::Matrix<double, NC, NX> C = Eigen::Matrix<double, NC, NX>::Zero();
  Eigen::Matrix<double, NC, NU> D = Eigen::Matrix<double, NC, NU>::Zero();
  Eigen::Matrix<double, NC, 1> e = Eigen::Matrix<double, NC, 1>::Zero();
  int num_eq = 0;

  Eigen::Matrix<double, NG, NX> Gx = Eigen::Matrix<double, NG, NX>::Zero();
  Eigen::Matrix<double, NG, NU> Gu = Eigen::Matrix<double, NG, NU>::Zero();
  Eigen::Matrix<double, NG, 1> h = Eigen::Matrix<double, NG, 1>::Zero();
  int num_ineq = 0;
};

template <int NX, int NU, int N, int NC, int NG>
struct OcpQp {
  static_assert(NX > 0 && NU > 0 && N >= 0 && NC >= 0 && NG >= 0, "sizes");
  static_assert(NC <= NU, "stage equalities must be solvable for the inputs");
  using Stage = OcpStage<NX, NU, NC, NG>;
  std::array<Stage, N + 1> stages{};
  Eigen::Matrix<double, NX, 1> x_initial = Eigen::Matrix<double, NX, 1>::Zero();
  int horizon = N;  // T: stages 0 … T are used, T = 0 means only x₀ (nothing to decide)
  // Optional structure of the dynamics (used for NX ≤ 64): with ab_groups_declared, column j of
  // every stage's B (A) is zero outside the 4-row groups whose bits b_groups[j] (a_groups[j])
  // set (bit g: rows [4g, 4g + 4)), and the Riccati recursion does not read the rest. The
  // centroidal MPC's A is the identity but in 9 rows and its force columns of B are 6 rows
  // deep: about half of A's and B's cache lines (~12 KB a stage) are not fetched.
  bool ab_groups_declared = false;
  std::array<std::uint16_t, NU> b_groups{};
  std::array<std::uint16_t, NX> a_groups{};
};

struct OcpSettings {
  // Interior-point iterations, each one Riccati factorization and two solves; the cost of one
  // call is bounded by this. See ocp_solver.h for the result on hitting it.
  int max_iterations = 30;
  // Both relative to the data scale max(1, |q|, |r|, |b|, |e|, |h|, |x_initial|) (∞-norms):
  double residual_tolerance = 1e-9;          // equalities, inequalities, stationarity
  double complementarity_tolerance = 1e-10;  // mean sᵢλᵢ
  // A multiplier this large means no interior point exists: report kInfeasible.
  double infeasible_multiplier = 1e12;
  // Start from the slacks and multipliers left in the workspace by the previous solve.
  bool warm_start = false;
  // Problems without inequalities (one factorization and one solve): whether to compute the
  // KKT residual of the result, one more pass over all the data (~7 % of an MPC iteration at
  // 1.2 s). false: sol.residual = −1 (not computed); the result is checked finite either way
  // (kBadInput otherwise). The MPC's real-time iteration sets false: nothing in the loop reads
  // the residual, and its RTI QPs are checked against an independent KKT residual in the tests.
  bool lq_residual = true;
  // Problems without inequalities: whether to compute the costates πₖ (each stage's cost-to-go
  // factor read once more in the forward rollout). false (and lq_residual false): sol.costate
  // is not written. The MPC's real-time iteration sets false: it reads only x and u.
  bool lq_costate = true;
};

template <int NX, int NU, int N, int NC, int NG>
struct OcpSolution {
  std::array<Eigen::Matrix<double, NX, 1>, N + 1> x{};
  std::array<Eigen::Matrix<double, NU, 1>, N + 1> u{};        // u[T] unused
  std::array<Eigen::Matrix<double, NX, 1>, N + 1> costate{};  // πₖ
  std::array<Eigen::Matrix<double, NC, 1>, N + 1> nu{};       // stage equality multipliers
  std::array<Eigen::Matrix<double, NG, 1>, N + 1> lambda{};   // inequality multipliers ≥ 0
  QpStatus status = QpStatus::kBadInput;
  int iterations = 0;
  double residual = 0.0;         // max of the equality, inequality and stationarity residuals (absolute)
  double complementarity = 0.0;  // mean sᵢλᵢ
};

}  // namespace kuavo::qp
