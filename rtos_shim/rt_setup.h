// Start-up settings that make a Linux thread real-time: lock memory, pin to a CPU,
// SCHED_FIFO priority. Any of them may be refused (no CAP_SYS_NICE / CAP_IPC_LOCK,
// RLIMIT_MEMLOCK, a CPU that does not exist, a container without RT budget), so
// the result is an error value naming the call that failed and its errno; the
// caller decides whether to continue (tests and desktop runs do, the robot does not).
// Start-up only: none of this may run inside the loop.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace kuavo::rtos {

// Stable numbers: they appear in logs and are never reused.
enum class RtStep : std::uint8_t {
  kConfig = 0,       // the configuration itself is invalid (errno EINVAL)
  kLockMemory = 1,   // mlockall(MCL_CURRENT | MCL_FUTURE)
  kCpuAffinity = 2,  // pthread_setaffinity_np
  kSchedFifo = 3,    // pthread_setschedparam(SCHED_FIFO)
  kThreadCreate = 4, // creating the task's thread
  kCpuDmaLatency = 5, // open + write /dev/cpu_dma_latency (the PM QoS request)
};
inline constexpr std::size_t kNumRtSteps = 6;

// What the caller wants when a step is refused.
enum class RtFailurePolicy : std::uint8_t {
  kRequire = 0,     // do not run the task (robot)
  kBestEffort = 1,  // run anyway with whatever was granted (tests, desktop)
};

struct RtConfig {
  // SCHED_FIFO priority 1..99; 0 keeps the normal (SCHED_OTHER) policy.
  int fifo_priority = 0;
  // CPU to pin the thread to; -1 leaves the affinity alone.
  int cpu = -1;
  // mlockall(MCL_CURRENT | MCL_FUTURE): no page faults later. Process-wide.
  bool lock_memory = false;
  // The CPU idle states' exit latency bound [us], process-wide, for the life of the process
  // (/dev/cpu_dma_latency, the kernel's PM QoS request: held while the file stays open).
  // 0 keeps the CPUs out of every idle state that takes time to leave, as cyclictest does:
  // a deep C-state (each state's exit latency is in /sys/devices/system/cpu/cpu*/cpuidle/
  // state*/latency) or, in a VM, a halted vCPU the host must reschedule, is a wake-up late
  // by that much. -1 leaves it alone.
  int cpu_dma_latency_us = -1;
  // Stack touched once after setup so its pages are resident before the loop
  // (with lock_memory they then stay). 64 KiB covers the loop bodies we run.
  std::size_t stack_prefault_bytes = 64 * 1024;
  RtFailurePolicy on_failure = RtFailurePolicy::kRequire;
};

// Outcome of the setup: errno per step, 0 where the step succeeded or was not requested.
struct RtStatus {
  std::array<int, kNumRtSteps> errno_by_step{};

  [[nodiscard]] bool ok() const noexcept;
  [[nodiscard]] bool failed(RtStep step) const noexcept {
    return errno_by_step[static_cast<std::size_t>(step)] != 0;
  }
  void set_failed(RtStep step, int errno_value) noexcept {
    errno_by_step[static_cast<std::size_t>(step)] = errno_value;
  }
  // e.g. "pthread_setschedparam(SCHED_FIFO, 80) failed: Operation not permitted (errno 1)".
  // One line per failed step; "ok" when none. Allocates: start-up / reporting only.
  [[nodiscard]] std::string describe() const;
};

// Name of the system call behind a step, for messages.
[[nodiscard]] const char* rt_step_call_name(RtStep step) noexcept;

// Applies `config` to the calling thread (memory locking is process-wide).
// With kRequire it stops at the first refused step; with kBestEffort it tries
// every step. Start-up only.
[[nodiscard]] RtStatus apply_realtime_to_this_thread(const RtConfig& config) noexcept;

}  // namespace kuavo::rtos
