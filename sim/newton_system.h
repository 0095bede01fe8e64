// CVODE's Newton linear system (I − γJ)·x = b for the plant, solved through its
// structure instead of as one dense 75×75 matrix.
//
// y = [q (35); u (34); z (6)]: Simbody's positions and speeds, then the contact-
// impulse quadratures. Their Jacobian has the shape
//   J = [Jqq Jqu 0; Juq Juu 0; Jzq Jzu 0]
// with Jqu = N(q) (q̇ = N·u) and Jqq zero except the quaternion's ½Ω(ω) block,
// which is O(|ω|) and dropped (CVODE's modified Newton needs only an approximate
// matrix; the corrector still converges to the same tolerance). Eliminating q and z
// leaves a 34×34 system in the speeds:
//   (I − γJuu − γ²·Juq·Jqu)·x_u = b_u + γ·Juq·b_q,
//   x_q = b_q + γ·Jqu·x_u,   x_z = b_z + γ·(Jzq·x_q + Jzu·x_u).
// Against the dense path this removes the 75×75 copy, scale-add and LU at every
// linear-solver setup (half of a carpet run).
//
// J itself is by forward differences of the right-hand side, column by column
// over q and u, with CVODE's own increments (cvLsDenseDQJac); the z columns are
// zero and skipped.
#pragma once

#include <cvode/cvode.h>
#include <sundials/sundials_linearsolver.h>

#include <Eigen/Core>
#include <Eigen/LU>

#include "controllers/model/model_tables.h"

namespace kuavo::sim {

class NewtonSystem {
 public:
  static constexpr int kNq = model::kNq;
  static constexpr int kNu = model::kNv;
  static constexpr int kNz = 6;
  static constexpr int kN = kNq + kNu + kNz;

  // A SUNDIALS "direct" linear solver whose setup/solve use this object.
  SUNLinearSolver make_linear_solver(SUNContext ctx);

  // The body of a CVLsLinSysFn: re-evaluates J by differences unless jok, keeps γ.
  // f/user: the right-hand side CVODE integrates and its user data. Returns f's
  // failure code when a difference evaluation fails (recoverable if positive).
  int update(void* cvode, CVRhsFn f, void* user, sunrealtype t, N_Vector y, N_Vector fy, bool jok, bool* jcur,
             sunrealtype gamma, N_Vector tmp1, N_Vector tmp2);

  long jacobian_evaluations() const { return jacobian_evaluations_; }

 private:
  static int setup(SUNLinearSolver s, SUNMatrix);
  static int solve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, sunrealtype);
  static int free(SUNLinearSolver s);

  Eigen::Matrix<double, kNq, kNu> jqu_ = Eigen::Matrix<double, kNq, kNu>::Zero();
  Eigen::Matrix<double, kNu, kNq> juq_ = Eigen::Matrix<double, kNu, kNq>::Zero();
  Eigen::Matrix<double, kNu, kNu> juu_ = Eigen::Matrix<double, kNu, kNu>::Zero();
  Eigen::Matrix<double, kNz, kNq> jzq_ = Eigen::Matrix<double, kNz, kNq>::Zero();
  Eigen::Matrix<double, kNz, kNu> jzu_ = Eigen::Matrix<double, kNz, kNu>::Zero();
  Eigen::Matrix<double, kNu, kNu> juq_jqu_ = Eigen::Matrix<double, kNu, kNu>::Zero();  // Juq·N, once per J
  double gamma_ = 0.0;
  Eigen::Matrix<double, kNu, kNu> schur_ = Eigen::Matrix<double, kNu, kNu>::Zero();
  Eigen::PartialPivLU<Eigen::Matrix<double, kNu, kNu>> lu_;
  long jacobian_evaluations_ = 0;
};

}  // namespace kuavo::sim
