// Result of every QP solve in controllers/qp. The numbers are stable (they go into logs and
// fault records): never renumber or reuse one; add new values at the end.
#pragma once

#include <cstdint>

namespace kuavo::qp {

enum class QpStatus : std::uint8_t {
  kSolved = 0,         // KKT conditions hold to the settings' tolerances
  kMaxIterations = 1,  // iteration cap hit; see each solver's header for what the iterate means
  kInfeasible = 2,     // constraints inconsistent (primal infeasible); iterate is not a solution
  kNotConvex = 3,      // a Hessian (or reduced Hessian) is not positive definite
  kBadInput = 4,       // non-finite data, lower > upper, or a size beyond capacity
  kRankDeficient = 5,  // stage equality constraints whose input matrix lacks full row rank (OCP)
  kNumericalError = 6, // factorization broke down from roundoff mid-solve; last iterate returned
};

inline const char* to_string(QpStatus s) {
  switch (s) {
    case QpStatus::kSolved: return "solved";
    case QpStatus::kMaxIterations: return "max_iterations";
    case QpStatus::kInfeasible: return "infeasible";
    case QpStatus::kNotConvex: return "not_convex";
    case QpStatus::kBadInput: return "bad_input";
    case QpStatus::kRankDeficient: return "rank_deficient";
    case QpStatus::kNumericalError: return "numerical_error";
  }
  return "unknown";
}

}  // namespace kuavo::qp
