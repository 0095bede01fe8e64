// One 500 Hz control tick of the online stack — estimator + reference interpolation + WBC
// QP + PD/feed-forward output (stack_control_tick_rt) — while stepping in place, on one
// core. Run pinned: taskset -c 1 build/bench/stack_bench
// Ticks are timed one by one with rtos_shim's monotonic clock; p50 / p99 / max are
// reported as counters (the goal: ≤ 100 µs max). The 50 Hz planner (kinematic
// here; the MPC has its own benchmark, mpc_bench) runs between ticks, untimed.
//
// Two motions: stepping in place (kinematic planner) and the built-in dance (MPC planner,
// plans switched at once, and blended over 20 ms: StackConfig::plan_blend_s).
// Each motion's ticks are replayed identically several times (stack_start restarts the
// same state), so every tick index has several timings of the same computation:
//   max_us          the worst single tick: computation + whatever the platform added
//                   (interrupts, a VM's steal time, cache pollution by other processes)
//   intrinsic_max_us the worst over tick indices of the fastest of its repetitions: the
//                   computation's own worst case with the random platform delays removed
//   qp_iter_at_max  the WBC QP iterations of the intrinsically slowest tick
// KUAVO_BENCH_FLUSH=1 evicts the caches (writes 32 MB) before every tick, untimed: every tick
// then starts as the ones after the planner do here (the MPC's 15 MB workspace runs on the
// same core between ticks, untimed, and leaves the control data in L3 or memory).
// KUAVO_BENCH_RT=1 runs the timed thread SCHED_FIFO 80 with mlockall (as the firmware
// does; needs root / CAP_SYS_NICE), "rt" = 1 when that was granted.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/planner/balance_filter.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/stack/online_stack.h"
#include "controllers/standing/standing_controller.h"
#include "rtos_shim/clock.h"
#include "rtos_shim/rt_setup.h"
#include "sim/ideal_sensors.h"
#include "tools/mocap/motion_plan_io.h"

namespace {

using namespace kuavo;

// A motion with its sensor frames precomputed (the robot exactly on the motion, ideal
// sensors), the stack started on it.
struct Fixture {
  model::Model robot;
  stack::StackConfig cfg;
  std::unique_ptr<planner::MotionPlan> plan = std::make_unique<planner::MotionPlan>();
  std::unique_ptr<stack::ControlWorkspace> control = std::make_unique<stack::ControlWorkspace>();
  std::unique_ptr<stack::PlannerWorkspace> planner_ws = std::make_unique<stack::PlannerWorkspace>();
  planner::ReferencePlan pending;
  dynamics::Data data;
  std::vector<hal::SensorFrame> frames;
  hal::CommandFrame command;
  bool ok = false, made = false;

  // The step-in-place gait (4 steps, 8 s) with the kinematic planner.
  static Fixture& steps() {
    static Fixture s;
    if (!s.made) {
      s.made = true;
      s.load_robot();
      dynamics::ConfigVector q0 = dynamics::neutral_configuration(s.robot);
      q0.tail<model::kNumJoints>() = control::centred_standing_pose(s.robot, s.data, 0.78);
      control::place_on_ground(s.robot, s.data, q0);
      planner::StepInPlaceConfig gait;
      gait.steps = 4;
      s.ok = planner::make_step_in_place(s.robot, q0, gait, *s.plan) == nullptr;
      s.start(4000);
    }
    return s;
  }
  // The built-in dance (retargeted, balance-filtered, 31 s) with the MPC planner, as the
  // main job runs it.
  static Fixture& dance(double plan_blend_s) {
    static Fixture blended, switched;
    Fixture& s = plan_blend_s > 0.0 ? blended : switched;
    if (!s.made) {
      s.made = true;
      s.load_robot();
      std::string error;
      auto filter = std::make_unique<planner::BalanceFilterWorkspace>();
      planner::BalanceFilterReport report;
      s.ok = mocap::built_in_dance_plan(s.robot, *s.plan, error) &&
             planner::balance_filter(s.robot, planner::BalanceFilterConfig{}, *s.plan, *filter, report) == nullptr;
      s.cfg.planner = stack::PlannerKind::kMpc;
      s.cfg.plan_blend_s = plan_blend_s;
      if (s.ok) s.start(static_cast<int>(planner::motion_plan_duration_s(*s.plan) / 0.002));
    }
    return s;
  }

 private:
  void load_robot() { model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot); }
  void start(int ticks) {
    frames.resize(ticks);
    planner::PlanKnot knot;
    for (int i = 0; i < ticks; ++i) sim::ideal_sensor_frame_on_plan(robot, data, *plan, i * 2'000'000LL, knot, frames[i]);
    stack::stack_start(robot, cfg, *control, *planner_ws, *plan, frames[0], 0);
  }
};

// Times every control tick of `passes` identical replays of the fixture's motion; the
// planner runs every 10th tick, untimed.
void time_ticks(benchmark::State& state, Fixture& f) {
  if (!f.ok) {
    state.SkipWithError("fixture");
    return;
  }
  bool rt = false;
  if (const char* e = std::getenv("KUAVO_BENCH_RT"); e != nullptr && e[0] == '1') {
    rtos::RtConfig c;
    c.fifo_priority = 80;
    c.lock_memory = true;
    c.on_failure = rtos::RtFailurePolicy::kBestEffort;
    rt = rtos::apply_realtime_to_this_thread(c).ok();
  }
  const bool flush = std::getenv("KUAVO_BENCH_FLUSH") != nullptr;
  std::vector<double> flush_buffer(flush ? (32u << 20) / sizeof(double) : 0, 0.0);
  const int n = static_cast<int>(f.frames.size());
  std::vector<double> us;
  us.reserve(1 << 20);
  std::vector<double> fastest(n, std::numeric_limits<double>::infinity());
  std::vector<int> qp_iterations(n, 0);
  // The replay must be the same computation: the first pass's torques, compared bitwise.
  std::vector<double> first_torque(n, 0.0);
  int i = 0, pass = 0, replay_mismatches = 0, first_mismatch = -1;
  for (auto _ : state) {
    const hal::TimeNs now = i * 2'000'000LL;
    if (i % 10 == 0) {
      state.PauseTiming();
      stack::stack_plan_rt(f.robot, f.cfg, *f.planner_ws, *f.plan, f.control->estimate.q, f.control->estimate.v, now, f.pending);
      stack::stack_apply_plan_rt(*f.control, f.pending);
      state.ResumeTiming();
    }
    if (flush) {
      state.PauseTiming();
      for (std::size_t k = 0; k < flush_buffer.size(); k += 8) flush_buffer[k] += 1.0;
      benchmark::DoNotOptimize(flush_buffer.data());
      state.ResumeTiming();
    }
    const rtos::TimeNs t0 = rtos::now_ns();
    benchmark::DoNotOptimize(
        stack::stack_control_tick_rt(f.robot, f.cfg, *f.control, f.frames[i], now, stack::StateOverride{}, f.command));
    const double t_us = static_cast<double>(rtos::now_ns() - t0) * 1e-3;
    us.push_back(t_us);
    fastest[i] = std::min(fastest[i], t_us);
    qp_iterations[i] = f.control->wbc.diagnostics.qp_iterations;
    double torque_sum = 0.0;
    for (const auto& j : f.command.joints) torque_sum += j.torque_ff_Nm;
    if (pass == 0) first_torque[i] = torque_sum;
    else if (torque_sum != first_torque[i]) {
      ++replay_mismatches;
      if (first_mismatch < 0) first_mismatch = i;
    }
    if (++i == n) {  // start the motion over: the same ticks again
      i = 0;
      ++pass;
      state.PauseTiming();
      stack::stack_start(f.robot, f.cfg, *f.control, *f.planner_ws, *f.plan, f.frames[0], 0);
      state.ResumeTiming();
    }
  }
  std::sort(us.begin(), us.end());
  state.counters["p50_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[us.size() * 99 / 100];
  state.counters["max_us"] = us.back();
  const auto worst = std::max_element(fastest.begin(), fastest.end());
  state.counters["intrinsic_max_us"] = *worst;
  state.counters["qp_iter_at_max"] = qp_iterations[worst - fastest.begin()];
  state.counters["qp_iter_max"] = *std::max_element(qp_iterations.begin(), qp_iterations.end());
  state.counters["rt"] = rt ? 1.0 : 0.0;
  state.counters["replay_mismatch"] = replay_mismatches;
  int over = 0;
  for (double t : fastest) over += t > 100.0 ? 1 : 0;
  state.counters["intrinsic_over_100us"] = over;
  if (std::getenv("KUAVO_BENCH_WORST")) {
    std::vector<int> order(n);
    for (int k = 0; k < n; ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return fastest[a] > fastest[b]; });
    for (int k = 0; k < std::min(n, 25); ++k) {
      std::fprintf(stderr, "tick %5d t=%6.3f s  %6.1f us  %2d QP iterations\n", order[k], order[k] * 0.002,
                   fastest[order[k]], qp_iterations[order[k]]);
    }
  }
  state.counters["first_mismatch_tick"] = first_mismatch;
}

// The WBC QPs of a motion's hardest ticks, captured with the working set each was warm
// started from, so the solver alone can be timed on them: many repetitions of the same
// solve, the fastest kept (the QP's intrinsic time), far steadier than whole-tick timings.
struct HardQp {
  wbc::Qp qp;
  wbc::QpSolution previous;  // the warm start (the tick before's solution)
  int tick = 0, warm_iterations = 0;
};

// Replays the motion once and keeps the QPs that took at least min_iterations iterations.
std::vector<std::unique_ptr<HardQp>> capture_hard_qps(Fixture& f, int min_iterations) {
  std::vector<std::unique_ptr<HardQp>> out;
  if (!f.ok) return out;
  stack::stack_start(f.robot, f.cfg, *f.control, *f.planner_ws, *f.plan, f.frames[0], 0);
  auto previous = std::make_unique<wbc::QpSolution>();
  const int n = static_cast<int>(f.frames.size());
  for (int i = 0; i < n; ++i) {
    const hal::TimeNs now = i * 2'000'000LL;
    if (i % 10 == 0) {
      stack::stack_plan_rt(f.robot, f.cfg, *f.planner_ws, *f.plan, f.control->estimate.q, f.control->estimate.v, now, f.pending);
      stack::stack_apply_plan_rt(*f.control, f.pending);
    }
    *previous = f.control->wbc.solution;
    stack::stack_control_tick_rt(f.robot, f.cfg, *f.control, f.frames[i], now, stack::StateOverride{}, f.command);
    const int iterations = f.control->wbc.diagnostics.qp_iterations;
    if (iterations >= min_iterations && previous->status == qp::QpStatus::kSolved) {
      auto h = std::make_unique<HardQp>();
      h->qp = f.control->wbc.qp;
      h->previous = *previous;
      h->tick = i;
      h->warm_iterations = iterations;
      out.push_back(std::move(h));
    }
  }
  stack::stack_start(f.robot, f.cfg, *f.control, *f.planner_ws, *f.plan, f.frames[0], 0);
  return out;
}

// Each captured QP solved `repeats` times warm (from its captured working set) or cold.
//   qp_max_us   the worst over the QPs of the fastest of the repetitions
//   qp_mean_us  the mean over the QPs of the fastest
void time_hard_qps(benchmark::State& state, const std::vector<std::unique_ptr<HardQp>>& qps, bool warm) {
  if (qps.empty()) {
    state.SkipWithError("no captured QPs");
    return;
  }
  static wbc::QpWorkspace ws;
  static wbc::QpSolution sol;
  qp::DenseQpSettings settings;
  settings.max_iterations = wbc::WbcConfig{}.qp_max_iterations;
  settings.warm_start = warm;
  std::vector<double> fastest(qps.size(), std::numeric_limits<double>::infinity());
  std::vector<int> iterations(qps.size(), 0), final_size(qps.size(), 0);
  std::vector<qp::DenseQpCounters> counters(qps.size());
  int failures = 0;
  for (auto _ : state) {
    for (std::size_t k = 0; k < qps.size(); ++k) {
      sol = qps[k]->previous;
      const rtos::TimeNs t0 = rtos::now_ns();
      benchmark::DoNotOptimize(qp::solve_dense_qp(qps[k]->qp, settings, ws, sol));
      fastest[k] = std::min(fastest[k], static_cast<double>(rtos::now_ns() - t0) * 1e-3);
      iterations[k] = sol.iterations;
      counters[k] = ws.counters;
      final_size[k] = sol.working_set_size;
      failures += sol.status == qp::QpStatus::kSolved ? 0 : 1;
    }
  }
  const auto worst = std::max_element(fastest.begin(), fastest.end());
  double sum = 0.0;
  for (double t : fastest) sum += t;
  state.counters["qps"] = static_cast<double>(qps.size());
  state.counters["qp_max_us"] = *worst;
  state.counters["qp_mean_us"] = sum / static_cast<double>(qps.size());
  state.counters["tick_at_max"] = qps[worst - fastest.begin()]->tick;
  state.counters["iter_at_max"] = iterations[worst - fastest.begin()];
  state.counters["iter_max"] = *std::max_element(iterations.begin(), iterations.end());
  state.counters["failures"] = failures;
  if (std::getenv("KUAVO_BENCH_WORST")) {
    std::vector<int> order(qps.size());
    for (std::size_t k = 0; k < qps.size(); ++k) order[k] = static_cast<int>(k);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return fastest[a] > fastest[b]; });
    for (int k = 0; k < std::min<int>(static_cast<int>(qps.size()), 10); ++k) {
      const int o = order[k];
      const qp::DenseQpCounters& c = counters[o];
      std::fprintf(stderr,
                   "%s tick %5d  %6.1f us  %2d iterations (%2d in the replay): guess %2d, dropped %2d in %d rounds, "
                   "%2d added, %2d blocking drops, %2d active at the end\n",
                   warm ? "warm" : "cold", qps[o]->tick, fastest[o], iterations[o], qps[o]->warm_iterations,
                   c.guess_imposed, c.guess_dropped, c.drop_rounds, c.additions, c.blocking_drops, final_size[o]);
    }
  }
}

}  // namespace

// Whole replays: 5 of the 8 s gait, 3 of the dance (the iteration counts need the
// motions' lengths, so the benchmarks are registered after the fixtures are made).
int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  Fixture& steps = Fixture::steps();
  Fixture& dance = Fixture::dance(0.0);
  Fixture& dance_blend = Fixture::dance(0.02);
  benchmark::RegisterBenchmark("BM_ControlTick_Steps", [&](benchmark::State& s) { time_ticks(s, steps); })
      ->Iterations(5 * static_cast<benchmark::IterationCount>(std::max<std::size_t>(1, steps.frames.size())))
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_ControlTick_DanceMpc", [&](benchmark::State& s) { time_ticks(s, dance); })
      ->Iterations(3 * static_cast<benchmark::IterationCount>(std::max<std::size_t>(1, dance.frames.size())))
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_ControlTick_DanceMpc_Blend20ms", [&](benchmark::State& s) { time_ticks(s, dance_blend); })
      ->Iterations(3 * static_cast<benchmark::IterationCount>(std::max<std::size_t>(1, dance_blend.frames.size())))
      ->Unit(benchmark::kMicrosecond);
  // The dance's hardest QPs (≥ 15 iterations in the replay: the ticks after a new plan).
  static std::vector<std::unique_ptr<HardQp>> hard;
  bool captured = false;
  auto hard_qps = [&]() -> const std::vector<std::unique_ptr<HardQp>>& {
    if (!captured) {
      captured = true;
      hard = capture_hard_qps(dance, 15);
      // KUAVO_BENCH_DUMP_QPS=file writes them (raw HardQp records, this build's layout) for
      // offline profiling of the solver.
      if (const char* path = std::getenv("KUAVO_BENCH_DUMP_QPS")) {
        if (std::FILE* out = std::fopen(path, "wb")) {
          for (const auto& h : hard) std::fwrite(h.get(), sizeof(HardQp), 1, out);
          std::fclose(out);
        }
      }
    }
    return hard;
  };
  benchmark::RegisterBenchmark("BM_WbcQp_DanceHard_Warm", [&](benchmark::State& s) { time_hard_qps(s, hard_qps(), true); })
      ->Iterations(30)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_WbcQp_DanceHard_Cold", [&](benchmark::State& s) { time_hard_qps(s, hard_qps(), false); })
      ->Iterations(30)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
