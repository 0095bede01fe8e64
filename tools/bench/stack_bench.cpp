// One 500 Hz control tick of the online stack — estimator + reference interpolation + WBC
// QP + PD/feed-forward output (stack_control_tick_rt) — while stepping in place, on one
// core. Run pinned: taskset -c 1 build/bench/stack_bench
// Ticks are timed one by one with rtos_shim's monotonic clock; p50 / p99 / max are
// reported as counters (the goal: ≤ 100 µs max). The 50 Hz planner (kinematic
// here; the MPC has its own benchmark, mpc_bench) runs between ticks, untimed.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "controllers/dynamics/rigid_body.h"
#include "controllers/planner/step_in_place.h"
#include "controllers/stack/online_stack.h"
#include "controllers/standing/standing_controller.h"
#include "rtos_shim/clock.h"
#include "sim/ideal_sensors.h"

namespace {

using namespace kuavo;

struct Fixture {
  model::Model robot;
  stack::StackConfig cfg;
  std::unique_ptr<planner::MotionPlan> plan = std::make_unique<planner::MotionPlan>();
  std::unique_ptr<stack::ControlWorkspace> control = std::make_unique<stack::ControlWorkspace>();
  std::unique_ptr<stack::PlannerWorkspace> planner_ws = std::make_unique<stack::PlannerWorkspace>();
  planner::ReferencePlan pending;
  dynamics::Data data;
  static constexpr int kFrames = 4000;  // 8 s of the gait at 500 Hz, sensors precomputed
  std::vector<hal::SensorFrame> frames = std::vector<hal::SensorFrame>(kFrames);
  hal::CommandFrame command;
  Fixture() {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
    dynamics::ConfigVector q0 = dynamics::neutral_configuration(robot);
    q0.tail<model::kNumJoints>() = control::centred_standing_pose(robot, data, 0.78);
    control::place_on_ground(robot, data, q0);
    planner::StepInPlaceConfig gait;
    gait.steps = 4;
    planner::make_step_in_place(robot, q0, gait, *plan);
    planner::PlanKnot knot;
    for (int i = 0; i < kFrames; ++i) sim::ideal_sensor_frame_on_plan(robot, data, *plan, i * 2'000'000LL, knot, frames[i]);
    stack::stack_start(robot, cfg, *control, *planner_ws, *plan, frames[0], 0);
  }
};

void BM_ControlTick(benchmark::State& state) {
  static Fixture f;
  std::vector<double> us;
  us.reserve(1 << 20);
  int i = 0;
  for (auto _ : state) {
    const hal::TimeNs now = i * 2'000'000LL;
    if (i % 10 == 0) {
      state.PauseTiming();
      stack::stack_plan_rt(f.robot, f.cfg, *f.planner_ws, *f.plan, f.control->estimate.q, f.control->estimate.v, now, f.pending);
      stack::stack_apply_plan_rt(*f.control, f.pending);
      state.ResumeTiming();
    }
    const rtos::TimeNs t0 = rtos::now_ns();
    benchmark::DoNotOptimize(
        stack::stack_control_tick_rt(f.robot, f.cfg, *f.control, f.frames[i], now, stack::StateOverride{}, f.command));
    us.push_back(static_cast<double>(rtos::now_ns() - t0) * 1e-3);
    if (++i == Fixture::kFrames) {  // start the gait over
      i = 0;
      state.PauseTiming();
      stack::stack_start(f.robot, f.cfg, *f.control, *f.planner_ws, *f.plan, f.frames[0], 0);
      state.ResumeTiming();
    }
  }
  std::sort(us.begin(), us.end());
  state.counters["p50_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[us.size() * 99 / 100];
  state.counters["max_us"] = us.back();
}
BENCHMARK(BM_ControlTick)->Iterations(20000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
