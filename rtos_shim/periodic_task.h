// A periodic real-time task on its own thread (Linux): the thread is created at
// start-up, applies RtConfig (mlockall, CPU affinity, SCHED_FIFO) to itself, and
// then runs run_periodic_loop_rt() with the caller's body. The body type is a
// template parameter, so the loop calls it directly: no std::function, no heap.
//
//   ControlStep step{...};                       // lives longer than the task
//   PeriodicTask task;
//   RtStatus s = task.start({.period_ns = 2'000'000, .rt = {.fifo_priority = 80, .cpu = 3,
//                            .lock_memory = true, .on_failure = RtFailurePolicy::kBestEffort}},
//                           step);
//   if (!s.ok()) log(s.describe());              // running anyway: best effort
//   ...
//   task.request_stop(); task.join();
//
// start() returns once the thread has finished its real-time setup, with the
// setup's status. Under kRequire a refused step means the loop never runs.
#pragma once

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <system_error>
#include <thread>

#include "rtos_shim/periodic_loop.h"
#include "rtos_shim/rt_setup.h"

namespace kuavo::rtos {

struct PeriodicConfig {
  TimeNs period_ns = 2'000'000;  // 500 Hz control rate
  std::uint64_t max_cycles = 0;  // 0: until request_stop()
  RtConfig rt{};
};

class PeriodicTask {
 public:
  PeriodicTask() = default;
  ~PeriodicTask() {
    request_stop();
    join();
  }
  PeriodicTask(const PeriodicTask&) = delete;
  PeriodicTask& operator=(const PeriodicTask&) = delete;

  // Starts the thread; `body` must outlive the task. Start-up only (allocates
  // the thread). Returns the real-time setup status; kConfig with EBUSY if
  // already started, EINVAL for period_ns <= 0.
  template <class Body>
  [[nodiscard]] RtStatus start(const PeriodicConfig& config, Body& body);

  // Asks the loop to end after its current cycle. Safe from any thread.
  void request_stop() noexcept { stop_.store(true, std::memory_order_relaxed); }

  // Waits for the thread to end (after max_cycles or request_stop()).
  void join() {
    if (thread_.joinable()) thread_.join();
  }

  // True once the loop has ended (or never ran).
  [[nodiscard]] bool finished() const noexcept { return finished_.load(std::memory_order_acquire); }

  [[nodiscard]] PeriodicPerfSnapshot perf() const noexcept { return perf_.snapshot(); }

 private:
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> setup_done_{false};
  std::atomic<bool> finished_{true};
  RtStatus setup_status_{};  // written by the thread before setup_done_ (release)
  PeriodicPerf perf_;
};

template <class Body>
RtStatus PeriodicTask::start(const PeriodicConfig& config, Body& body) {
  RtStatus status;
  if (thread_.joinable() || config.period_ns <= 0) {
    status.set_failed(RtStep::kConfig, thread_.joinable() ? EBUSY : EINVAL);
    return status;
  }
  stop_.store(false, std::memory_order_relaxed);
  setup_done_.store(false, std::memory_order_relaxed);
  finished_.store(false, std::memory_order_relaxed);
  perf_.reset();

  // A refused step only stops the task under kRequire; a bad config always does.
  const auto may_run = [&config](const RtStatus& s) {
    return s.ok() || (config.rt.on_failure == RtFailurePolicy::kBestEffort &&
                      !s.failed(RtStep::kConfig));
  };
  try {
    thread_ = std::thread([this, config, &body, may_run] {
      setup_status_ = apply_realtime_to_this_thread(config.rt);
      const bool run = may_run(setup_status_);
      setup_done_.store(true, std::memory_order_release);
      setup_done_.notify_one();
      if (run) run_periodic_loop_rt(config.period_ns, config.max_cycles, stop_, perf_, body);
      finished_.store(true, std::memory_order_release);
    });
  } catch (const std::system_error& e) {
    status.set_failed(RtStep::kThreadCreate, e.code().value());
    finished_.store(true, std::memory_order_release);
    return status;
  }
  setup_done_.wait(false, std::memory_order_acquire);
  status = setup_status_;
  if (!may_run(status)) thread_.join();
  return status;
}

}  // namespace kuavo::rtos
