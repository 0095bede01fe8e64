// rtos_shim costs: SPSC ring push+pop, latest-value publish+read of a 32 KiB
// payload (the size class of an MPC solution), and the periodic task's wake-up
// latency at 500 Hz (how late the control loop starts after its deadline).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>

#include "rtos_shim/latest_value.h"
#include "rtos_shim/periodic_task.h"
#include "rtos_shim/spsc_ring.h"

namespace {

using kuavo::rtos::TimeNs;

struct LogRecord {  // 32 bytes, like a small log record
  std::uint64_t stamp_ns;
  std::uint32_t code;
  std::uint32_t arg;
  double value[2];
};

kuavo::rtos::SpscRing<LogRecord, 1024> g_ring;

void BM_SpscRingPushPop(benchmark::State& state) {
  LogRecord in{1, 2, 3, {4.0, 5.0}};
  LogRecord out{};
  for (auto _ : state) {
    ++in.stamp_ns;
    benchmark::DoNotOptimize(g_ring.try_push_rt(in));
    benchmark::DoNotOptimize(g_ring.try_pop_rt(out));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SpscRingPushPop);

struct Solution32K {
  std::uint64_t words[4096];
};
static_assert(sizeof(Solution32K) == 32 * 1024);
kuavo::rtos::LatestValue<Solution32K> g_latest;
Solution32K g_solution;

// Copy-in publish (32 KiB memcpy) + reader update + one read: the per-plan cost.
void BM_LatestValuePublishRead32K(benchmark::State& state) {
  std::uint64_t seq = 0;
  for (auto _ : state) {
    g_solution.words[0] = ++seq;
    g_latest.publish_rt(g_solution);
    benchmark::DoNotOptimize(g_latest.update_rt());
    benchmark::DoNotOptimize(g_latest.front_rt().words[0]);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(sizeof(Solution32K)));
}
BENCHMARK(BM_LatestValuePublishRead32K);

// In-place publish (the writer fills back_rt() directly): the handover alone.
void BM_LatestValueHandoverOnly(benchmark::State& state) {
  std::uint64_t seq = 0;
  for (auto _ : state) {
    g_latest.back_rt().words[0] = ++seq;
    g_latest.publish_rt();
    benchmark::DoNotOptimize(g_latest.update_rt());
    benchmark::DoNotOptimize(g_latest.front_rt().words[0]);
  }
}
BENCHMARK(BM_LatestValueHandoverOnly);

constexpr int kJitterCycles = 2000;
constexpr TimeNs kControlPeriodNs = 2'000'000;  // 500 Hz

struct WakeRecorder {
  std::array<TimeNs, kJitterCycles> latency_ns{};
  int n = 0;
  void operator()(const kuavo::rtos::CycleInfo& info) noexcept {
    if (n < kJitterCycles) latency_ns[n++] = info.wake_ns - info.deadline_ns;
  }
};
WakeRecorder g_recorder;

// 2000 cycles at 500 Hz (4 s) on a PeriodicTask with SCHED_FIFO 80 and mlockall,
// best effort: without privileges it still runs, and rt_ok says so.
void BM_PeriodicWakeLatency500Hz(benchmark::State& state) {
  for (auto _ : state) {
    g_recorder.n = 0;
    kuavo::rtos::PeriodicConfig config;
    config.period_ns = kControlPeriodNs;
    config.max_cycles = kJitterCycles;
    config.rt.fifo_priority = 80;
    config.rt.lock_memory = true;
    config.rt.on_failure = kuavo::rtos::RtFailurePolicy::kBestEffort;
    kuavo::rtos::PeriodicTask task;
    const kuavo::rtos::RtStatus status = task.start(config, g_recorder);
    if (!status.ok()) std::fprintf(stderr, "real-time setup: %s\n", status.describe().c_str());
    task.join();
    const kuavo::rtos::PeriodicPerfSnapshot perf = task.perf();

    std::array<TimeNs, kJitterCycles> sorted = g_recorder.latency_ns;
    const int n = g_recorder.n;
    std::sort(sorted.begin(), sorted.begin() + n);
    const auto us = [](TimeNs ns) { return static_cast<double>(ns) * 1e-3; };
    state.counters["p50_us"] = us(sorted[n / 2]);
    state.counters["p99_us"] = us(sorted[(n * 99) / 100]);
    state.counters["max_us"] = us(sorted[n - 1]);
    state.counters["cycles"] = static_cast<double>(perf.cycles);
    state.counters["overruns"] = static_cast<double>(perf.overruns);
    state.counters["rt_ok"] = status.ok() ? 1.0 : 0.0;
  }
}
BENCHMARK(BM_PeriodicWakeLatency500Hz)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
