// QP solver benchmarks (run pinned: taskset -c 1 build/bench/qp_bench).
//   Dense WBC size: 82 vars, 32 equalities, 92 two-sided inequalities (+ bounds), and the
//   torque-eliminated 56 vars / 18 equalities / 60 inequalities; warm start = re-solve of the
//   previous tick's problem with a small change in g, from its working set. 58 / 6 / 60 is the
//   shape the WBC solves (random data here; wbc_bench times the real one). The solver caches
//   nothing between calls, so changing only g costs the same as a new H would.
//   OCP: N = 60, nx = 38, nu = 50 — one Riccati factorization + solve (what one RTI costs
//   per interior-point iteration), with and without 12 stage equalities, and a full
//   interior-point solve with 20 inequalities per stage.
// Every bench links kuavo_sim, whose PUBLIC -UNDEBUG (needed by Simbody's headers) would time
// Eigen with its range assertions on. The solvers are header-only and this file does not
// include Simbody, so measure them as the firmware builds them: without Eigen's assertions.
#ifndef EIGEN_NO_DEBUG
#define EIGEN_NO_DEBUG
#endif
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "controllers/qp/dense_qp_solver.h"
#include "controllers/qp/ocp_solver.h"
#include "tools/bench/bench_stats.h"

namespace {

using namespace kuavo::qp;

double gauss(std::mt19937_64& rng) { return std::normal_distribution<double>(0.0, 1.0)(rng); }
double unif(std::mt19937_64& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

template <typename M>
void fill(M& m, std::mt19937_64& rng, double scale = 1.0) {
  for (int j = 0; j < m.cols(); ++j)
    for (int i = 0; i < m.rows(); ++i) m(i, j) = scale * gauss(rng);
}

// WBC-like: well-conditioned weighted-task Hessian, a feasible point inside the constraints,
// a task pull that activates a moderate number of inequalities (as friction cones and limits do).
// margin scales the distance from the feasible point to each constraint: 1 gives a heavy
// case (~half the inequalities active), 4 a typical WBC tick (a handful active).
template <int NV, int NE, int NI>
void make_dense(DenseQp<NV, NE, NI>& qp, std::mt19937_64& rng, double margin) {
  Eigen::Matrix<double, NV + 10, NV> M;
  fill(M, rng);
  qp.H.noalias() = M.transpose() * M / double(NV);
  qp.H.diagonal().array() += 1e-2;
  fill(qp.g, rng, 3.0 / (margin * margin));  // the task pull, weaker in the typical case
  Eigen::Matrix<double, NV, 1> x0;
  fill(x0, rng);
  fill(qp.A, rng);
  if constexpr (NE > 0) qp.b.noalias() = qp.A * x0;
  fill(qp.C, rng);
  if constexpr (NI > 0) {
    for (int i = 0; i < NI; ++i) {
      const double cx = qp.C.row(i).dot(x0);
      qp.c_lower(i) = cx - margin * unif(rng, 0.5, 3.0);
      qp.c_upper(i) = cx + margin * unif(rng, 0.5, 3.0);
    }
  }
  for (int j = 0; j < NV; ++j) {
    qp.x_lower(j) = x0(j) - margin * unif(rng, 0.5, 3.0);
    qp.x_upper(j) = x0(j) + margin * unif(rng, 0.5, 3.0);
  }
}

template <int NV, int NE, int NI>
struct DenseBench {
  DenseQp<NV, NE, NI> qp;
  DenseQpWorkspace<NV, NE, NI> ws;
  DenseQpSolution<NV, NE, NI> sol;
  Eigen::Matrix<double, NV, 1> g0;
};

template <int NV, int NE, int NI>
void dense_solve(benchmark::State& state, bool warm, double margin) {
  static auto b = std::make_unique<DenseBench<NV, NE, NI>>();
  std::mt19937_64 rng(1);
  make_dense(b->qp, rng, margin);
  b->g0 = b->qp.g;
  DenseQpSettings settings;
  settings.warm_start = warm;
  solve_dense_qp(b->qp, DenseQpSettings{}, b->ws, b->sol);
  int tick = 0, iterations = 0, active = 0;
  for (auto _ : state) {
    // The next tick's task: a small, deterministic change of the linear term.
    b->qp.g = b->g0;
    b->qp.g(tick % NV) += 1e-2 * ((tick & 1) ? 1.0 : -1.0);
    ++tick;
    solve_dense_qp(b->qp, settings, b->ws, b->sol);
    iterations += b->sol.iterations;
    active += b->sol.working_set_size;
    benchmark::DoNotOptimize(b->sol.x.data());
  }
  if (b->sol.status != QpStatus::kSolved) state.SkipWithError(to_string(b->sol.status));
  state.counters["iterations"] = double(iterations) / double(tick);
  state.counters["active_ineq"] = double(active) / double(tick);
}

void BM_DenseWbc82_Typical_Warm(benchmark::State& s) { dense_solve<82, 32, 92>(s, true, 4.0); }
void BM_DenseWbc82_Typical_Cold(benchmark::State& s) { dense_solve<82, 32, 92>(s, false, 4.0); }
void BM_DenseWbc82_Heavy_Warm(benchmark::State& s) { dense_solve<82, 32, 92>(s, true, 1.0); }
void BM_DenseWbc82_Heavy_Cold(benchmark::State& s) { dense_solve<82, 32, 92>(s, false, 1.0); }
void BM_DenseWbc56_Typical_Warm(benchmark::State& s) { dense_solve<56, 18, 60>(s, true, 4.0); }
void BM_DenseWbc56_Typical_Cold(benchmark::State& s) { dense_solve<56, 18, 60>(s, false, 4.0); }
void BM_DenseWbc56_Heavy_Warm(benchmark::State& s) { dense_solve<56, 18, 60>(s, true, 1.0); }
void BM_DenseWbc58_Typical_Warm(benchmark::State& s) { dense_solve<58, 6, 60>(s, true, 4.0); }
void BM_DenseWbc58_Typical_Cold(benchmark::State& s) { dense_solve<58, 6, 60>(s, false, 4.0); }
void BM_DenseWbc58_Heavy_Warm(benchmark::State& s) { dense_solve<58, 6, 60>(s, true, 1.0); }
void BM_DenseIk34Bounds_Warm(benchmark::State& s) { dense_solve<34, 0, 0>(s, true, 1.0); }
BENCHMARK(BM_DenseWbc82_Typical_Warm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc82_Typical_Cold)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc82_Heavy_Warm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc82_Heavy_Cold)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc56_Typical_Warm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc56_Typical_Cold)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc56_Heavy_Warm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc58_Typical_Warm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc58_Typical_Cold)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseWbc58_Heavy_Warm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseIk34Bounds_Warm)->Unit(benchmark::kMicrosecond);

constexpr int kNx = 38, kNu = 50, kN = 60, kNc = 12, kNg = 20;
using MpcQp = OcpQp<kNx, kNu, kN, kNc, kNg>;

struct OcpBench {
  MpcQp qp;
  OcpWorkspace<kNx, kNu, kN, kNc, kNg> ws;
  OcpSolution<kNx, kNu, kN, kNc, kNg> sol;
};

void make_ocp(MpcQp& qp, std::mt19937_64& rng, bool equalities, bool inequalities) {
  Eigen::Matrix<double, kNx, 1> x;
  fill(x, rng);
  qp.x_initial = x;
  Eigen::Matrix<double, kNu, 1> u;
  for (int k = 0; k <= kN; ++k) {
    auto& s = qp.stages[k];
    Eigen::Matrix<double, kNx + kNu + 5, kNx + kNu> M;
    fill(M, rng);
    Eigen::Matrix<double, kNx + kNu, kNx + kNu> W;
    W.noalias() = M.transpose() * M / double(kNx + kNu);
    W.diagonal().array() += 0.05;
    s.Q = W.topLeftCorner<kNx, kNx>();
    s.S = W.bottomLeftCorner<kNu, kNx>();
    s.R = W.bottomRightCorner<kNu, kNu>();
    fill(s.q, rng);
    fill(s.r, rng);
    fill(s.A, rng, 0.1 / std::sqrt(double(kNx)));  // spectral radius ~1.1: stays bounded over 60 stages
    s.A.diagonal().array() += 0.9;
    fill(s.B, rng, 0.2);
    fill(s.b, rng, 0.1);
    fill(u, rng);
    s.num_eq = (equalities && k < kN && k % 2 == 0) ? kNc : 0;  // stance stages: no-slip rows
    fill(s.C, rng);
    fill(s.D, rng);
    s.e.noalias() = s.C * x;
    s.e.noalias() += s.D * u;
    s.num_ineq = inequalities ? kNg : 0;
    fill(s.Gx, rng);
    fill(s.Gu, rng);
    s.h.noalias() = s.Gx * x;
    if (k < kN) s.h.noalias() += s.Gu * u;
    for (int i = 0; i < kNg; ++i) s.h(i) += unif(rng, 0.1, 1.0);
    if (k < kN) {
      const Eigen::Matrix<double, kNx, 1> next = s.A * x + s.B * u + s.b;
      x = next;
    }
  }
}

// What each timed iteration runs: the matrix pass, the vector pass (with rollout), or both.
// kFused: riccati_factor_solve, the backward vector recursion inside the matrix pass (what the
// equality-only path of solve_ocp_qp and so the MPC run).
enum class RiccatiPart { kBoth, kFactor, kSolve, kFused };

void riccati_once(benchmark::State& state, bool equalities, RiccatiPart part = RiccatiPart::kBoth) {
  static auto b = std::make_unique<OcpBench>();
  std::mt19937_64 rng(2);
  make_ocp(b->qp, rng, equalities, false);
  copy_vectors(b->qp, b->ws.vec);
  if (riccati_factor(b->qp, b->ws.riccati) != QpStatus::kSolved) state.SkipWithError("factor");
  std::vector<double> fused_us;  // kFused: each solve timed alone (the distribution, see below)
  fused_us.reserve(1 << 16);
  for (auto _ : state) {
    if (part == RiccatiPart::kFused) {
      const auto t0 = std::chrono::steady_clock::now();
      if (riccati_factor_solve(b->qp, b->ws.riccati, b->ws.vec, b->sol) != QpStatus::kSolved) state.SkipWithError("factor");
      benchmark::DoNotOptimize(b->sol.u[0].data());
      if (fused_us.size() < fused_us.capacity()) {
        fused_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      }
      continue;
    }
    if (part != RiccatiPart::kSolve && riccati_factor(b->qp, b->ws.riccati) != QpStatus::kSolved) {
      state.SkipWithError("factor");
    }
    if (part != RiccatiPart::kFactor) riccati_solve(b->qp, b->ws.riccati, b->ws.vec, b->sol);
    benchmark::DoNotOptimize(b->sol.u[0].data());
    benchmark::DoNotOptimize(b->ws.riccati.stage[0].L.data());
  }
  if (!fused_us.empty()) {
    // At N = 60 the solve streams ~10 MB through the L3 this VM shares with other tenants: its
    // time spreads by tens of percent with their traffic (at N = 6, L2-resident, by ~3 %), so
    // the spread is reported beside the mean. min: the quiet-machine cost.
    state.counters["min_us"] = kuavo::bench::percentile(fused_us, 0);
    state.counters["p10_us"] = kuavo::bench::percentile(fused_us, 10);
    state.counters["p50_us"] = kuavo::bench::percentile(fused_us, 50);
    state.counters["p90_us"] = kuavo::bench::percentile(fused_us, 90);
  }
  int factored = 0;  // stages whose cost-to-go took the square-root path
  for (const auto& w : b->ws.riccati.stage) factored += w.p_factored ? 1 : 0;
  state.counters["p_factored"] = factored;
}

void BM_OcpRiccati_N60_nx38_nu50(benchmark::State& s) { riccati_once(s, false); }
void BM_OcpRiccati_N60_nx38_nu50_eq12(benchmark::State& s) { riccati_once(s, true); }
void BM_OcpRiccatiFused_N60_nx38_nu50(benchmark::State& s) { riccati_once(s, false, RiccatiPart::kFused); }
void BM_OcpRiccatiFused_N60_nx38_nu50_eq12(benchmark::State& s) { riccati_once(s, true, RiccatiPart::kFused); }
void BM_OcpRiccatiFactorOnly_N60_nx38_nu50(benchmark::State& s) { riccati_once(s, false, RiccatiPart::kFactor); }
void BM_OcpRiccatiSolveOnly_N60_nx38_nu50(benchmark::State& s) { riccati_once(s, false, RiccatiPart::kSolve); }
// Five repetitions each, reported as mean, median, stddev and min: this VM's phases move a
// repetition's mean by 10–20 %, and the min is the computation's own cost (BENCHMARKS.md).
double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }
#define KUAVO_OCP_BENCHMARK(f) \
  BENCHMARK(f)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ComputeStatistics("min", min_of)->DisplayAggregatesOnly(true)
KUAVO_OCP_BENCHMARK(BM_OcpRiccati_N60_nx38_nu50);
KUAVO_OCP_BENCHMARK(BM_OcpRiccati_N60_nx38_nu50_eq12);
KUAVO_OCP_BENCHMARK(BM_OcpRiccatiFused_N60_nx38_nu50);
KUAVO_OCP_BENCHMARK(BM_OcpRiccatiFused_N60_nx38_nu50_eq12);
KUAVO_OCP_BENCHMARK(BM_OcpRiccatiFactorOnly_N60_nx38_nu50);
KUAVO_OCP_BENCHMARK(BM_OcpRiccatiSolveOnly_N60_nx38_nu50);

void BM_OcpInteriorPoint_N60_eq12_ineq20(benchmark::State& state) {
  static auto b = std::make_unique<OcpBench>();
  std::mt19937_64 rng(3);
  make_ocp(b->qp, rng, true, true);
  int iterations = 0, solves = 0;
  for (auto _ : state) {
    solve_ocp_qp(b->qp, OcpSettings{}, b->ws, b->sol);
    iterations += b->sol.iterations;
    ++solves;
  }
  state.counters["iterations"] = double(iterations) / double(solves);
  state.counters["residual"] = b->sol.residual;
  state.counters["mu"] = b->sol.complementarity;
  state.counters["status"] = double(static_cast<int>(b->sol.status));
}
BENCHMARK(BM_OcpInteriorPoint_N60_eq12_ineq20)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
