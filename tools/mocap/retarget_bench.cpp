// Geometric retargeting throughput: frames per second of Retargeter::step on one core
// (goal ≥ 2000 frames/s; GMR reports 35–70). Input: the built-in default dance at 100 Hz
// with its automatic contact schedule, so stance pinning and ground rows are exercised.
// Run: build/bench/retarget_bench  (items_per_second = frames/s).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "tools/mocap/contacts.h"
#include "tools/mocap/default_dance.h"
#include "tools/mocap/retarget.h"

namespace {

using namespace kuavo;

struct Setup {
  model::Model robot;
  mocap::HumanTargets targets;
  std::vector<mocap::FootPins> pins;
  Setup() {
    model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, robot);
    const mocap::Bvh bvh = mocap::default_dance_bvh();
    mocap::SkeletonMap map;
    std::string error;
    if (!mocap::map_skeleton(bvh, map, error) || !mocap::make_targets(bvh, map, robot, {}, targets, error))
      std::fprintf(stderr, "retarget_bench: %s\n", error.c_str());
    pins = mocap::plan_foot_pins(targets, mocap::detect_contacts(targets, robot), robot, targets.rate_hz);
  }
};

const Setup& setup() {
  static const Setup s;
  return s;
}

void BM_RetargetFrame(benchmark::State& state) {
  const Setup& s = setup();
  mocap::RetargetOptions options;
  options.iterations = static_cast<int>(state.range(0));
  mocap::Retargeter solver(s.robot, options, s.targets.rate_hz);
  std::size_t i = 0;
  for (auto _ : state) {
    if (i == s.targets.frames.size()) {
      i = 0;
      solver.reset();
    }
    benchmark::DoNotOptimize(solver.step(s.targets.frames[i], s.targets.present, s.pins[i]));
    ++i;
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_RetargetFrame)->Arg(3)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
