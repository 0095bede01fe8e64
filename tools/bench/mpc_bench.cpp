// One centroidal-MPC real-time iteration (mpc_step_rt) per horizon, on one core.
// Run pinned: taskset -c 1 build-mpc/bench/mpc_bench
// Counters: p50 / p99 / max of the whole call, timed one by one with the monotonic clock, and
// the p50 of its three phases: linearization + QP build, the Riccati solve (+ step), the plan
// written for the WBC. The state alternates between standing still and a 0.1 m/s sideways
// CoM disturbance; the stamps advance one stage per call (warm start shifted by one, as at 50 Hz).
// BM_MpcStepStepping: the same at 1.2 s while stepping in place (swing-foot rows in the QP).
// BM_MpcStepSteppingIdle: the same with the core idle for 18 ms before each call, the planning
// task's duty cycle at 50 Hz (kuavo_fw --timing): what the call costs once its working set has
// left the caches.
// BM_RecoveryStepRewrite*: the recovery step's window rewrite with a step under way or held,
// which runs before the MPC in the same planning call; BM_EarlyTouchdownTrigger: the call
// that lands a swing early.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>
#include <vector>

#include "controllers/mpc/mpc.h"
#include "controllers/planner/recovery_step.h"
#include "controllers/standing/standing_controller.h"
#include "tools/bench/bench_stats.h"

namespace {

using namespace kuavo;
using Clock = std::chrono::steady_clock;

struct Fixture {
  model::Model robot;
  dynamics::Data data;
  mpc::MpcConfig cfg;
  mpc::MpcWorkspace ws;
  planner::PlanWindow window;
  mpc::MpcPlan plan;
  dynamics::ConfigVector q0;
  Fixture() {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
    q0 = dynamics::neutral_configuration(robot);
    q0.tail<model::kNumJoints>() = control::centred_standing_pose(robot, data, 0.78);
    control::place_on_ground(robot, data, q0);
  }
  // Standing, or stepping in place (double support 0.3 s, one foot swinging 0.4 s, 50 mm apex).
  void set_window(hal::TimeNs t0_ns, bool stepping) {
    window.count = planner::kMaxWindowKnots;
    window.dt_s = cfg.dt_s;
    planner::ContactFlags all{};
    all.fill(true);
    planner::plan_knot_from_state(robot, data, q0, dynamics::VelocityVector::Zero(), all, t0_ns, window.knots[0]);
    for (int k = 1; k < window.count; ++k) {
      window.knots[k] = window.knots[0];
      window.knots[k].stamp_ns = t0_ns + static_cast<hal::TimeNs>(k) * 20'000'000;
    }
    if (!stepping) return;
    for (int k = 0; k < window.count; ++k) {
      planner::PlanKnot& knot = window.knots[k];
      const double t = static_cast<double>(knot.stamp_ns) * 1e-9;
      const int cycle = static_cast<int>(t / 0.7);
      const double in_cycle = t - cycle * 0.7;
      if (in_cycle < 0.3) continue;
      const double s = (in_cycle - 0.3) / 0.4;
      const int first = cycle % 2 == 0 ? 0 : 4;
      for (int c = first; c < first + 4; ++c) {
        knot.in_contact[c] = false;
        knot.point_position_m[3 * c + 2] += 0.05 * std::sin(M_PI * s);
        knot.point_velocity_m_s[3 * c + 2] = 0.05 * M_PI / 0.4 * std::cos(M_PI * s);
      }
    }
  }
};

Fixture& fixture() {
  static auto f = std::make_unique<Fixture>();  // ~15 MB: static storage, as in the firmware
  return *f;
}

using kuavo::bench::percentile;

// tail_stride 0: the default grid (mpc.h: a coarse tail after 0.4 s); else that stride (1 = uniform).
void BM_MpcStep(benchmark::State& state, bool stepping, int idle_ms = 0, int tail_stride = 0) {
  Fixture& f = fixture();
  f.cfg = {};
  f.cfg.horizon_s = static_cast<double>(state.range(0)) / 1000.0;
  if (tail_stride > 0) {
    f.cfg.fine_horizon_s = 0.4;
    f.cfg.tail_stride = tail_stride;
  }
  mpc::mpc_init(f.robot, f.cfg, f.ws);
  dynamics::VelocityVector v[2] = {dynamics::VelocityVector::Zero(), dynamics::VelocityVector::Zero()};
  v[1][1] = 0.1;
  std::vector<double> total, build, solve, write;
  for (auto* vec : {&total, &build, &solve, &write}) vec->reserve(1 << 16);
  hal::TimeNs t = 0;
  int i = 0, failures = 0;
  double stages = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    if (idle_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(idle_ms));
    f.set_window(t, stepping);  // the planner's part
    state.ResumeTiming();
    const auto t0 = Clock::now();
    mpc::MpcStatus s = mpc::mpc_build_qp_rt(f.robot, f.cfg, f.ws, f.q0, v[i], f.window);
    const auto t1 = Clock::now();
    if (s == mpc::MpcStatus::kOk) s = mpc::mpc_solve_qp_rt(f.ws);
    const auto t2 = Clock::now();
    mpc::mpc_write_plan_rt(f.robot, f.cfg, f.ws, f.window, s, f.plan);
    const auto t3 = Clock::now();
    failures += s == mpc::MpcStatus::kOk ? 0 : 1;
    stages += f.ws.horizon;  // the tail's grid follows the contact switches
    benchmark::DoNotOptimize(f.plan.cost);
    auto us = [](auto a, auto b) { return std::chrono::duration<double, std::micro>(b - a).count(); };
    total.push_back(us(t0, t3));
    build.push_back(us(t0, t1));
    solve.push_back(us(t1, t2));
    write.push_back(us(t2, t3));
    t += 20'000'000;
    i ^= 1;
  }
  state.counters["stages_mean"] = total.empty() ? 0.0 : stages / static_cast<double>(total.size());
  state.counters["p50_us"] = percentile(total, 50);
  state.counters["p99_us"] = percentile(total, 99);
  state.counters["max_us"] = percentile(total, 100);
  state.counters["linearize_p50_us"] = percentile(build, 50);
  state.counters["solve_p50_us"] = percentile(solve, 50);
  state.counters["plan_p50_us"] = percentile(write, 50);
  state.counters["failures"] = failures;
}
void BM_MpcStepStanding(benchmark::State& state) { BM_MpcStep(state, false); }
void BM_MpcStepStepping(benchmark::State& state) { BM_MpcStep(state, true); }
void BM_MpcStepSteppingIdle(benchmark::State& state) { BM_MpcStep(state, true, 18); }
void BM_MpcStepSteppingUniform(benchmark::State& state) { BM_MpcStep(state, true, 0, 1); }
void BM_MpcStepSteppingUniformIdle(benchmark::State& state) { BM_MpcStep(state, true, 18, 1); }
BENCHMARK(BM_MpcStepStepping)->Arg(1200)->ArgName("horizon_ms")->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_MpcStepSteppingIdle)->Arg(1200)->ArgName("horizon_ms")->Unit(benchmark::kMillisecond)->MinTime(0.5);
BENCHMARK(BM_MpcStepSteppingUniform)->Arg(1200)->ArgName("horizon_ms")->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_MpcStepSteppingUniformIdle)->Arg(1200)->ArgName("horizon_ms")->Unit(benchmark::kMillisecond)->MinTime(0.5);
BENCHMARK(BM_MpcStepStanding)->Arg(600)->Arg(800)->Arg(1000)->Arg(1200)->Arg(1400)->ArgName("horizon_ms")
    ->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

namespace {

// The parts of one stage's linearization.
void BM_CentroidalEvaluate(benchmark::State& state) {
  Fixture& f = fixture();
  static mpc::CentroidalPoint point;
  static mpc::StateVector x;
  static mpc::InputVector u = mpc::InputVector::Zero();
  mpc::state_from_configuration(f.robot, f.data, f.q0, dynamics::VelocityVector::Zero(), x);
  for (int c = 0; c < 8; ++c) u[3 * c + 2] = 67.0;
  for (auto _ : state) {
    mpc::centroidal_evaluate(f.robot, x, u, mpc::HeadVector::Zero(), point);
    benchmark::DoNotOptimize(point.fx(0, 0));
  }
}
BENCHMARK(BM_CentroidalEvaluate)->Unit(benchmark::kMicrosecond);

void BM_ReferenceState(benchmark::State& state) {
  Fixture& f = fixture();
  static mpc::StateVector x;
  for (auto _ : state) {
    mpc::state_from_configuration(f.robot, f.data, f.q0, dynamics::VelocityVector::Zero(), x);
    benchmark::DoNotOptimize(x[0]);
  }
}
BENCHMARK(BM_ReferenceState)->Unit(benchmark::kMicrosecond);

// The recovery step's rewrite of a 1.2 s window (61 knots) while a step is under way and
// held (planner/recovery_step.h): consecutive calls one stage apart, as at 50 Hz (the knots
// met again come from the previous call), and `cold` (its cache emptied before each call:
// every knot's legs re-solved, as on the call that takes the step). The step is triggered
// on a standing motion by a backward CoM velocity that puts ξ 4 cm behind the heels; the
// 3 s that follow are replayed, then the step is taken again.
void BM_RecoveryStepRewrite(benchmark::State& state, bool cold) {
  Fixture& f = fixture();
  static auto motion = std::make_unique<planner::MotionPlan>();
  static auto rs = std::make_unique<planner::RecoveryStepState>();
  static auto measured = std::make_unique<planner::PlanKnot>();
  static planner::PlanWindow window;
  motion->rate_hz = 100.0;
  motion->frame_count = 600;
  for (int i = 0; i < motion->frame_count; ++i) motion->q[i] = f.q0, motion->foot_contact[i] = {true, true};
  planner::RecoveryStepConfig cfg;
  cfg.settle_s = 0.0;
  dynamics::VelocityVector push = dynamics::VelocityVector::Zero();
  push[0] = -0.56;  // ξ = c + ċ/ω 0.16 m behind the CoM: 4 cm behind the heels
  const auto stamp = [](int stage) -> hal::TimeNs { return 1'000'000'000 + stage * 20'000'000LL; };
  const auto call = [&](int stage, const dynamics::VelocityVector& v) {
    const hal::TimeNs t_ns = stamp(stage);
    planner::motion_plan_window_rt(f.robot, f.data, *motion, t_ns, 0.02, 61, window);
    planner::plan_knot_measured(f.robot, f.data, f.q0, v, t_ns, *measured);
    planner::recovery_step_rt(f.robot, cfg, *rs, *motion, *measured, window);
  };
  std::vector<double> us;
  int stage = 150;
  for (auto _ : state) {
    if (stage == 150) {  // take the step again
      planner::recovery_step_reset(*rs);
      call(0, push);
      call(1, push);
      if (rs->steps != 1) {
        state.SkipWithError("no recovery step triggered");
        return;
      }
      stage = 2;
    }
    if (cold) rs->cache_count = 0;
    planner::motion_plan_window_rt(f.robot, f.data, *motion, stamp(stage), 0.02, 61, window);
    const auto t0 = Clock::now();
    // The measured state's kinematics are timed with it (stack_plan_rt computes them once per call).
    planner::plan_knot_measured(f.robot, f.data, f.q0, dynamics::VelocityVector::Zero(), stamp(stage), *measured);
    planner::recovery_step_rt(f.robot, cfg, *rs, *motion, *measured, window);
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    ++stage;
  }
  state.counters["p50_us"] = percentile(us, 50);
  state.counters["p99_us"] = percentile(us, 99);
}
void BM_RecoveryStepRewriteConsecutive(benchmark::State& state) { BM_RecoveryStepRewrite(state, false); }
void BM_RecoveryStepRewriteCold(benchmark::State& state) { BM_RecoveryStepRewrite(state, true); }
BENCHMARK(BM_RecoveryStepRewriteConsecutive)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RecoveryStepRewriteCold)->Unit(benchmark::kMicrosecond);

// The planner call that lands a swing early (recovery_step.h, early touchdown): the motion
// swings the left foot over [1.0, 1.8) s holding its own ξ over the right sole's centre (its
// knots' CoM velocity: its touchdown holds it), the robot on its right foot moves left at
// 0.56 m/s (ξ at the left sole's outer edge); the second call at 1.1 s triggers and rewrites
// the window (every knot from then on carries the landing). Timed: that call, from a reset.
void BM_EarlyTouchdownTrigger(benchmark::State& state) {
  Fixture& f = fixture();
  static auto motion = std::make_unique<planner::MotionPlan>();
  static auto rs = std::make_unique<planner::RecoveryStepState>();
  static auto measured = std::make_unique<planner::PlanKnot>();
  static planner::PlanWindow window;
  motion->rate_hz = 100.0;
  motion->frame_count = 600;
  for (int i = 0; i < motion->frame_count; ++i) {
    motion->q[i] = f.q0, motion->foot_contact[i] = {!(i >= 100 && i < 180), true};
  }
  planner::RecoveryStepConfig cfg;
  cfg.settle_s = 0.0;
  dynamics::VelocityVector push = dynamics::VelocityVector::Zero();
  push[1] = 0.56;
  // Timed as the step's rewrite above: the measured knot and the rewrite, not the window's sampling.
  const auto call = [&](hal::TimeNs t_ns, std::vector<double>* us) {
    planner::motion_plan_window_rt(f.robot, f.data, *motion, t_ns, 0.02, 61, window);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // the right sole's
    for (int i = 0; i < planner::kCornersPerFoot; ++i) {
      centre += window.knots[0].point_position_m.segment<3>(3 * (planner::kRightFoot * planner::kCornersPerFoot + i)) /
                planner::kCornersPerFoot;
    }
    for (int k = 0; k < window.count; ++k) {
      planner::PlanKnot& knot = window.knots[k];
      const double omega = std::sqrt(model::kGravity_m_s2 / (knot.com_position_m.z() - centre.z()));
      knot.com_velocity_m_s.head<2>() = (centre.head<2>() - knot.com_position_m.head<2>()) * omega;
    }
    const auto t0 = Clock::now();
    planner::plan_knot_measured(f.robot, f.data, f.q0, push, t_ns, *measured);
    planner::recovery_step_rt(f.robot, cfg, *rs, *motion, *measured, window);
    if (us != nullptr) us->push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
  };
  std::vector<double> us;
  for (auto _ : state) {
    planner::recovery_step_reset(*rs);
    call(1'080'000'000, nullptr);
    call(1'100'000'000, &us);
    if (rs->early_touchdowns != 1) {
      state.SkipWithError("no early touchdown triggered");
      return;
    }
  }
  state.counters["p50_us"] = percentile(us, 50);
  state.counters["p99_us"] = percentile(us, 99);
}
BENCHMARK(BM_EarlyTouchdownTrigger)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
