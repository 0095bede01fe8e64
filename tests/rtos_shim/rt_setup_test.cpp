#include "rtos_shim/rt_setup.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <thread>

namespace kuavo::rtos {
namespace {

// Each case runs on a scratch thread so the test runner's own thread keeps its settings.
RtStatus apply_on_scratch_thread(const RtConfig& config) {
  RtStatus status;
  std::thread t([&] { status = apply_realtime_to_this_thread(config); });
  t.join();
  return status;
}

TEST(RtosRtSetup, NothingRequestedIsOk) {
  const RtStatus s = apply_on_scratch_thread(RtConfig{});
  EXPECT_TRUE(s.ok());
  EXPECT_EQ(s.describe(), "ok");
}

TEST(RtosRtSetup, InvalidNumbersAreConfigErrorsEvenInBestEffort) {
  RtConfig c;
  c.on_failure = RtFailurePolicy::kBestEffort;
  c.fifo_priority = 100;  // SCHED_FIFO is 1..99
  RtStatus s = apply_on_scratch_thread(c);
  EXPECT_TRUE(s.failed(RtStep::kConfig));
  EXPECT_FALSE(s.failed(RtStep::kSchedFifo)) << "must not even try";
  c.fifo_priority = 0;
  c.cpu = -2;
  s = apply_on_scratch_thread(c);
  EXPECT_TRUE(s.failed(RtStep::kConfig));
  EXPECT_NE(s.describe().find("RtConfig validation failed"), std::string::npos) << s.describe();
}

TEST(RtosRtSetup, RequireStopsAtTheFirstRefusalBestEffortTriesAll) {
  RtConfig c;
  c.cpu = 1000;           // refused: no such CPU
  c.fifo_priority = 1;    // would be tried after affinity
  c.on_failure = RtFailurePolicy::kRequire;
  RtStatus s = apply_on_scratch_thread(c);
  EXPECT_TRUE(s.failed(RtStep::kCpuAffinity));
  EXPECT_FALSE(s.failed(RtStep::kSchedFifo)) << "kRequire stops at the first refusal";

  c.on_failure = RtFailurePolicy::kBestEffort;
  s = apply_on_scratch_thread(c);
  EXPECT_TRUE(s.failed(RtStep::kCpuAffinity));
  // SCHED_FIFO itself may or may not be granted here; what matters is that it was attempted,
  // which shows as either success or its own errno (never a skipped step with kRequire's logic).
  if (s.failed(RtStep::kSchedFifo)) {
    EXPECT_NE(s.describe().find("pthread_setschedparam(SCHED_FIFO)"), std::string::npos);
  }
}

// The idle-latency bound is the kernel's PM QoS request: /dev/cpu_dma_latency reads back the
// bound in force (the least of every open request; 2e9 us when there is none), which this
// process's request of 0 makes 0 for as long as the process lives. Without the device or the
// permission (not root) the step is refused by name, with its errno.
TEST(RtosRtSetup, CpuDmaLatencyRequestIsHeldByTheKernel) {
  RtConfig c;
  c.on_failure = RtFailurePolicy::kBestEffort;
  c.cpu_dma_latency_us = -2;
  EXPECT_TRUE(apply_on_scratch_thread(c).failed(RtStep::kConfig));
  c.cpu_dma_latency_us = 0;
  const RtStatus s = apply_on_scratch_thread(c);
  if (s.failed(RtStep::kCpuDmaLatency)) {
    EXPECT_NE(s.describe().find("write(/dev/cpu_dma_latency) failed"), std::string::npos) << s.describe();
    GTEST_SKIP() << "no PM QoS request here: " << s.describe();
  }
  EXPECT_TRUE(s.ok()) << s.describe();
  const int fd = ::open("/dev/cpu_dma_latency", O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  std::int32_t bound_us = -1;
  EXPECT_EQ(::read(fd, &bound_us, sizeof bound_us), static_cast<ssize_t>(sizeof bound_us));
  ::close(fd);
  EXPECT_EQ(bound_us, 0);
}

TEST(RtosRtSetup, DescribeNamesEveryFailedCallWithItsErrno) {
  RtStatus s;
  s.set_failed(RtStep::kLockMemory, ENOMEM);
  s.set_failed(RtStep::kSchedFifo, EPERM);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.describe(),
            "mlockall(MCL_CURRENT|MCL_FUTURE) failed: Cannot allocate memory (errno 12)\n"
            "pthread_setschedparam(SCHED_FIFO) failed: Operation not permitted (errno 1)");
}

}  // namespace
}  // namespace kuavo::rtos
