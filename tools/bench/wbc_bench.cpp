// One whole-body-control tick (dynamics terms + QP build + solve + output) on one core.
// Run pinned: taskset -c 1 build/bench/wbc_bench --benchmark_repetitions=1
// Reports the mean per tick (Google Benchmark) and, as counters, p50 / p99 / max over the
// measured ticks, timed one by one with the monotonic clock.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <vector>

#include "controllers/wbc/wbc.h"

namespace {

using namespace kuavo;

struct Fixture {
  model::Model robot;
  wbc::WbcConfig cfg;
  wbc::WbcWorkspace ws;
  std::array<dynamics::ConfigVector, 16> q;
  std::array<dynamics::VelocityVector, 16> v;
  std::array<wbc::WbcReference, 16> ref;
  hal::CommandFrame command;
  Fixture() {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
    wbc::wbc_init(robot, cfg, ws);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 16; ++i) {
      q[i] = dynamics::neutral_configuration(robot);
      for (int leg : {model::kLeftLegFirst, model::kRightLegFirst}) {
        q[i][7 + leg + 2] = -0.35;
        q[i][7 + leg + 3] = 0.7;
        q[i][7 + leg + 4] = -0.35;
      }
      q[i][2] -= 0.05;
      wbc::wbc_reference_hold_state(robot, ws, q[i], 0, ref[i]);
      if (i % 2 == 1) {  // single support, alternating feet: the walking case
        for (int c = 0; c < 4; ++c) ref[i].in_contact[(i % 4 == 1 ? 0 : 4) + c] = false;
      }
      for (int j = 0; j < model::kNumJoints; ++j) q[i][7 + j] += 0.01 * u(rng);
      for (int k = 0; k < model::kNv; ++k) v[i][k] = 0.1 * u(rng);
    }
  }
};

Fixture& fixture() {
  static Fixture f;  // static storage, as in the firmware
  return f;
}

void report_percentiles(benchmark::State& state, std::vector<double>& us) {
  std::sort(us.begin(), us.end());
  state.counters["p50_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[us.size() * 99 / 100];
  state.counters["max_us"] = us.back();
}

void BM_WbcTick(benchmark::State& state, bool single_support_only) {
  Fixture& f = fixture();
  std::vector<double> us;
  us.reserve(1 << 20);
  int i = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(wbc::wbc_step_rt(f.robot, f.cfg, f.ws, f.q[i], f.v[i], f.ref[i], 0, f.command));
    const auto t1 = std::chrono::steady_clock::now();
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    i = single_support_only ? (i + 2) % 16 : (i + 1) % 16;
    if (single_support_only && i % 2 == 0) i = (i + 1) % 16;
  }
  report_percentiles(state, us);
}

void BM_WbcTickMixed(benchmark::State& state) { BM_WbcTick(state, false); }
void BM_WbcTickSingleSupport(benchmark::State& state) { BM_WbcTick(state, true); }

// The parts: rigid-body terms alone (what the tick spends before the QP).
void BM_DynamicsTerms(benchmark::State& state) {
  Fixture& f = fixture();
  static dynamics::FrameJacobian jac;
  int i = 0;
  for (auto _ : state) {
    dynamics::compute_all_terms(f.robot, f.ws.data, f.q[i], f.v[i]);
    dynamics::bias_accelerations(f.robot, f.ws.data);
    for (int c = 0; c < model::kNumContactPoints; ++c) dynamics::frame_jacobian(f.robot, f.ws.data, c, jac);
    benchmark::DoNotOptimize(jac(0, 0));
    i = (i + 1) % 16;
  }
}

// The QP alone, on the problem of the last tick: cold, and warm from its own solution.
void BM_QpSolve(benchmark::State& state) {
  Fixture& f = fixture();
  const bool warm = state.range(0) != 0;
  const int i = static_cast<int>(state.range(1));
  wbc::wbc_step_rt(f.robot, f.cfg, f.ws, f.q[i], f.v[i], f.ref[i], 0, f.command);
  static wbc::QpSolution solution;
  qp::DenseQpSettings settings = f.ws.qp_settings;
  settings.warm_start = warm;
  long iterations = 0, solves = 0;
  for (auto _ : state) {
    solution = f.ws.solution;
    benchmark::DoNotOptimize(qp::solve_dense_qp(f.ws.qp, settings, f.ws.qp_workspace, solution));
    iterations += solution.iterations;
    ++solves;
  }
  state.counters["iterations"] = static_cast<double>(iterations) / static_cast<double>(solves);
  state.counters["working_set"] = solution.working_set_size;
}
BENCHMARK(BM_QpSolve)->ArgsProduct({{0, 1}, {0, 1}})->ArgNames({"warm", "single_support"})->Unit(benchmark::kMicrosecond);

BENCHMARK(BM_WbcTickMixed)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_WbcTickSingleSupport)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_DynamicsTerms)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
