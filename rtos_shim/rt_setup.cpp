#include "rtos_shim/rt_setup.h"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <mutex>

namespace kuavo::rtos {
namespace {

// Largest stack prefault we honour; bigger requests are clamped (the array
// below lives on the stack being prefaulted).
constexpr std::size_t kMaxStackPrefaultBytes = 512 * 1024;
constexpr std::size_t kPageBytes = 4096;

[[gnu::noinline]] void prefault_stack(std::size_t bytes) noexcept {
  volatile unsigned char buffer[kMaxStackPrefaultBytes];
  const std::size_t n = bytes < kMaxStackPrefaultBytes ? bytes : kMaxStackPrefaultBytes;
  // The stack grows down: touch from the end nearest the caller's frame downwards,
  // so the pages the loop body will use next are the ones made resident.
  for (std::size_t i = 0; i < n; i += kPageBytes) buffer[kMaxStackPrefaultBytes - 1 - i] = 0;
  // Tell the compiler the buffer is used, so the writes (the point) are kept.
  asm volatile("" : : "r"(buffer) : "memory");
}

// The PM QoS request's file: open for the life of the process once a task asked (closing it
// would drop the request). A later request writes its value on the same file. Two tasks may
// start at once: the mutex (start-up only) keeps it one file.
int g_cpu_dma_latency_fd = -1;
std::mutex g_cpu_dma_latency_mutex;

// 0 or the errno of the failed call.
int request_cpu_dma_latency(int latency_us) noexcept {
  const std::lock_guard<std::mutex> lock(g_cpu_dma_latency_mutex);
  if (g_cpu_dma_latency_fd < 0) {
    g_cpu_dma_latency_fd = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
    if (g_cpu_dma_latency_fd < 0) return errno;
  }
  const std::int32_t value = latency_us;
  const ssize_t n = ::write(g_cpu_dma_latency_fd, &value, sizeof value);
  if (n == static_cast<ssize_t>(sizeof value)) return 0;
  return n < 0 ? errno : EIO;
}

}  // namespace

bool RtStatus::ok() const noexcept {
  for (const int e : errno_by_step) {
    if (e != 0) return false;
  }
  return true;
}

const char* rt_step_call_name(RtStep step) noexcept {
  switch (step) {
    case RtStep::kConfig: return "RtConfig validation";
    case RtStep::kLockMemory: return "mlockall(MCL_CURRENT|MCL_FUTURE)";
    case RtStep::kCpuAffinity: return "pthread_setaffinity_np";
    case RtStep::kSchedFifo: return "pthread_setschedparam(SCHED_FIFO)";
    case RtStep::kThreadCreate: return "thread creation";
    case RtStep::kCpuDmaLatency: return "write(/dev/cpu_dma_latency)";
  }
  return "unknown step";
}

std::string RtStatus::describe() const {
  std::string text;
  for (std::size_t i = 0; i < kNumRtSteps; ++i) {
    const int e = errno_by_step[i];
    if (e == 0) continue;
    if (!text.empty()) text += '\n';
    char buffer[128];
    // GNU strerror_r returns the message pointer (possibly not buffer); thread-safe unlike strerror.
    const char* message = strerror_r(e, buffer, sizeof(buffer));
    text += rt_step_call_name(static_cast<RtStep>(i));
    text += " failed: ";
    text += message;
    text += " (errno ";
    text += std::to_string(e);
    text += ')';
  }
  return text.empty() ? std::string("ok") : text;
}

RtStatus apply_realtime_to_this_thread(const RtConfig& config) noexcept {
  RtStatus status;
  const bool require = config.on_failure == RtFailurePolicy::kRequire;

  if (config.fifo_priority != 0) {
    const int lo = sched_get_priority_min(SCHED_FIFO);
    const int hi = sched_get_priority_max(SCHED_FIFO);
    if (config.fifo_priority < lo || config.fifo_priority > hi) {
      status.set_failed(RtStep::kConfig, EINVAL);
      return status;  // a wrong number is a bug, not a missing privilege: never continue
    }
  }
  if (config.cpu < -1 || config.cpu >= CPU_SETSIZE || config.cpu_dma_latency_us < -1) {
    status.set_failed(RtStep::kConfig, EINVAL);
    return status;
  }

  // Lock first so the stack prefault below stays resident.
  if (config.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    status.set_failed(RtStep::kLockMemory, errno);
    if (require) return status;
  }

  if (config.cpu_dma_latency_us >= 0) {
    const int e = request_cpu_dma_latency(config.cpu_dma_latency_us);
    if (e != 0) {
      status.set_failed(RtStep::kCpuDmaLatency, e);
      if (require) return status;
    }
  }

  if (config.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(config.cpu, &set);
    // pthread_* return the error number rather than setting errno.
    const int e = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (e != 0) {
      status.set_failed(RtStep::kCpuAffinity, e);
      if (require) return status;
    }
  }

  if (config.fifo_priority != 0) {
    sched_param param{};
    param.sched_priority = config.fifo_priority;
    const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (e != 0) {
      status.set_failed(RtStep::kSchedFifo, e);
      if (require) return status;
    }
  }

  prefault_stack(config.stack_prefault_bytes);
  return status;
}

}  // namespace kuavo::rtos
