// SocketCAN layer: open failure on this kernel, frame I/O over socketpairs
// (same datagram-per-frame semantics as CAN_RAW), non-blocking behaviour,
// timestamps, error frames, and no heap in the I/O path.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include <vector>

#include "drivers/can/can_port.h"
#include "drivers/can/can_socket.h"
#include "tests/support/alloc_trap.h"

namespace kuavo::drivers {
namespace {

struct Pair {
  int fd[2]{-1, -1};
  explicit Pair(int type = SOCK_SEQPACKET) { EXPECT_EQ(socketpair(AF_UNIX, type, 0, fd), 0); }
  ~Pair() {
    for (int f : fd)
      if (f >= 0) close(f);
  }
};

can_frame make_frame(canid_t id, std::uint8_t len, std::uint8_t seed) {
  can_frame f{};
  f.can_id = id;
  f.len = len;
  for (int i = 0; i < len; ++i) f.data[i] = static_cast<std::uint8_t>(seed + i);
  return f;
}

bool kernel_has_can() {
  const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd >= 0) close(fd);
  return fd >= 0;
}

TEST(CanSocket, OpenFailsWithClearMessageWithoutKernelCan) {
  if (kernel_has_can()) GTEST_SKIP() << "this kernel has AF_CAN; the failure path is not reachable";
  CanPort port;
  std::string message;
  const DriverError e = open_can_socket("can0", CanSocketOptions{}, port, message);
  EXPECT_EQ(e, DriverError::kNoCanSupport);
  EXPECT_EQ(port.fd, -1);
  EXPECT_NE(message.find("can0"), std::string::npos) << message;
  EXPECT_NE(message.find("socket(AF_CAN)"), std::string::npos) << message;
  EXPECT_NE(message.find(std::strerror(EAFNOSUPPORT)), std::string::npos) << message;
  EXPECT_NE(message.find("kernel without CAN support"), std::string::npos) << message;
}

TEST(CanSocket, RejectsBadInterfaceNameBeforeTouchingTheKernel) {
  CanPort port;
  std::string message;
  EXPECT_EQ(open_can_socket("", CanSocketOptions{}, port, message), DriverError::kBadConfig);
  EXPECT_EQ(open_can_socket("a_name_longer_than_ifnamsiz", CanSocketOptions{}, port, message),
            DriverError::kBadConfig);
  EXPECT_NE(message.find("longer than 15"), std::string::npos) << message;
}

TEST(CanPort, ClassicFrameRoundTripOverSeqpacket) {
  Pair p;
  CanPort tx = attach_can_port(p.fd[0], false), rx = attach_can_port(p.fd[1], false);
  const can_frame sent = make_frame(0x123, 8, 0xA0);
  ASSERT_EQ(send_rt(tx, sent), DriverError::kOk);
  RxFrame got;
  ASSERT_EQ(receive_rt(rx, got), DriverError::kOk);
  EXPECT_FALSE(got.is_fd);
  can_frame classic;
  ASSERT_TRUE(as_classic(got, classic));
  EXPECT_EQ(classic.can_id, 0x123u);
  EXPECT_EQ(classic.len, 8);
  EXPECT_EQ(std::memcmp(classic.data, sent.data, 8), 0);
  EXPECT_EQ(tx.stats.tx_frames, 1u);
  EXPECT_EQ(rx.stats.rx_frames, 1u);
}

TEST(CanPort, EmptyReadReturnsImmediately) {
  Pair p;
  CanPort rx = attach_can_port(p.fd[1], false);
  RxFrame got;
  EXPECT_EQ(receive_rt(rx, got), DriverError::kRxEmpty);
  EXPECT_EQ(rx.stats.io_errors, 0u);
}

TEST(CanPort, KernelReceiveTimestamp) {
  Pair p;
  ASSERT_TRUE(enable_rx_timestamps(p.fd[1]));
  CanPort tx = attach_can_port(p.fd[0], false), rx = attach_can_port(p.fd[1], false);
  timespec before;
  clock_gettime(CLOCK_REALTIME, &before);
  ASSERT_EQ(send_rt(tx, make_frame(0x10, 2, 1)), DriverError::kOk);
  RxFrame got;
  ASSERT_EQ(receive_rt(rx, got), DriverError::kOk);
  const hal::TimeNs before_ns = before.tv_sec * 1'000'000'000LL + before.tv_nsec;
  EXPECT_GE(got.rx_realtime_ns, before_ns);
  EXPECT_LT(got.rx_realtime_ns - before_ns, 1'000'000'000LL);
}

TEST(CanPort, FullQueueDropsAndCountsWithoutBlocking) {
  Pair p(SOCK_DGRAM);
  const int small = 4096;
  ASSERT_EQ(setsockopt(p.fd[0], SOL_SOCKET, SO_SNDBUF, &small, sizeof(small)), 0);
  CanPort tx = attach_can_port(p.fd[0], false), rx = attach_can_port(p.fd[1], false);
  DriverError e = DriverError::kOk;
  int sent = 0;
  for (int i = 0; i < 100000 && e == DriverError::kOk; ++i) {
    e = send_rt(tx, make_frame(0x20, 8, static_cast<std::uint8_t>(i)));
    if (e == DriverError::kOk) ++sent;
  }
  ASSERT_EQ(e, DriverError::kTxQueueFull) << to_string(e);
  EXPECT_EQ(tx.stats.tx_dropped, 1u);
  EXPECT_EQ(tx.stats.tx_frames, static_cast<std::uint64_t>(sent));
  // Draining the peer frees the queue: the next cycle's frame goes out.
  RxFrame got;
  int drained = 0;
  while (receive_rt(rx, got) == DriverError::kOk) ++drained;
  EXPECT_EQ(drained, sent);
  EXPECT_EQ(send_rt(tx, make_frame(0x20, 8, 0)), DriverError::kOk);
}

TEST(CanPort, SendErrnoClassification) {
  EXPECT_EQ(classify_send_errno(ENOBUFS), DriverError::kTxQueueFull);
  EXPECT_EQ(classify_send_errno(EAGAIN), DriverError::kTxQueueFull);
  EXPECT_EQ(classify_send_errno(EPIPE), DriverError::kPeerClosed);
  EXPECT_EQ(classify_send_errno(EIO), DriverError::kIoError);
}

TEST(CanPort, ErrorFramesUpdateHealthAndBusOffBlocksSending) {
  Pair p;
  CanPort dev = attach_can_port(p.fd[0], false), host = attach_can_port(p.fd[1], false);
  can_frame passive{};
  passive.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  passive.len = CAN_ERR_DLC;
  passive.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  ASSERT_EQ(send_rt(dev, passive), DriverError::kOk);
  RxFrame got;
  EXPECT_EQ(receive_rt(host, got), DriverError::kErrorFrame);
  EXPECT_TRUE(host.health.error_passive);
  EXPECT_FALSE(host.health.bus_off);
  EXPECT_EQ(host.stats.rx_frames, 0u);  // error frames are not data

  can_frame busoff{};
  busoff.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  busoff.len = CAN_ERR_DLC;
  ASSERT_EQ(send_rt(dev, busoff), DriverError::kOk);
  EXPECT_EQ(receive_rt(host, got), DriverError::kErrorFrame);
  EXPECT_TRUE(host.health.bus_off);
  EXPECT_EQ(send_rt(host, make_frame(0x1, 1, 0)), DriverError::kBusOff);

  can_frame restarted{};
  restarted.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
  restarted.len = CAN_ERR_DLC;
  ASSERT_EQ(send_rt(dev, restarted), DriverError::kOk);
  EXPECT_EQ(receive_rt(host, got), DriverError::kErrorFrame);
  EXPECT_EQ(host.health.restarts, 1u);
  EXPECT_TRUE(host.health.bus_off);  // latched until the firmware clears it
  clear_bus_off(host.health);
  EXPECT_EQ(send_rt(host, make_frame(0x1, 1, 0)), DriverError::kOk);
}

TEST(CanPort, WrongSizedDatagramIsRejected) {
  Pair p;
  CanPort rx = attach_can_port(p.fd[1], false);
  const char junk[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(send(p.fd[0], junk, sizeof(junk), 0), 5);
  RxFrame got;
  EXPECT_EQ(receive_rt(rx, got), DriverError::kBadDatagram);
  EXPECT_EQ(rx.stats.rx_bad, 1u);
}

TEST(CanPort, FdFramesOnlyOnFdPorts) {
  Pair p;
  CanPort classic = attach_can_port(p.fd[0], false);
  canfd_frame fd{};
  fd.can_id = 0x55;
  fd.len = 64;
  fd.flags = CANFD_BRS;
  for (int i = 0; i < 64; ++i) fd.data[i] = static_cast<std::uint8_t>(i * 3);
  EXPECT_EQ(send_fd_rt(classic, fd), DriverError::kFdNotEnabled);
  CanPort tx = attach_can_port(p.fd[0], true), rx = attach_can_port(p.fd[1], true);
  ASSERT_EQ(send_fd_rt(tx, fd), DriverError::kOk);
  RxFrame got;
  ASSERT_EQ(receive_rt(rx, got), DriverError::kOk);
  EXPECT_TRUE(got.is_fd);
  EXPECT_EQ(got.frame.len, 64);
  EXPECT_EQ(std::memcmp(got.frame.data, fd.data, 64), 0);
  can_frame c;
  EXPECT_FALSE(as_classic(got, c));
}

TEST(CanPort, ClosedPeerIsReportedNotFatal) {
  Pair p;
  CanPort port = attach_can_port(p.fd[1], false);
  close(p.fd[0]);
  p.fd[0] = -1;
  RxFrame got;
  EXPECT_EQ(receive_rt(port, got), DriverError::kPeerClosed);
  EXPECT_EQ(send_rt(port, make_frame(0x1, 1, 0)), DriverError::kPeerClosed);  // no SIGPIPE
}

// The batched calls against the single-frame ones as the oracle: the same
// datagrams (data, error, FD, bad-sized, end-of-stream) read both ways give the
// same results, frames, counters and bus health.
TEST(CanPortBatch, ReceiveMatchesSingleFrameReads) {
  Pair a, b;
  auto feed = [](int fd) {
    for (int i = 0; i < 2 * kMaxBatchFrames + 3; ++i) {  // spans three batches
      const can_frame f = make_frame(0x100 + i, static_cast<std::uint8_t>(i % 9), static_cast<std::uint8_t>(i));
      ASSERT_EQ(send(fd, &f, CAN_MTU, 0), CAN_MTU);
      if (i == 5) {
        can_frame busoff{};
        busoff.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
        busoff.len = CAN_ERR_DLC;
        ASSERT_EQ(send(fd, &busoff, CAN_MTU, 0), CAN_MTU);
      }
      if (i == 17) {
        const char junk[5] = {1, 2, 3, 4, 5};
        ASSERT_EQ(send(fd, junk, sizeof(junk), 0), 5);
      }
      if (i == 20) {
        canfd_frame fd_frame{};
        fd_frame.can_id = 0x55;
        fd_frame.len = 48;
        for (int k = 0; k < 48; ++k) fd_frame.data[k] = static_cast<std::uint8_t>(k + i);
        ASSERT_EQ(send(fd, &fd_frame, CANFD_MTU, 0), CANFD_MTU);
      }
    }
  };
  feed(a.fd[0]);
  feed(b.fd[0]);
  close(a.fd[0]), close(b.fd[0]);
  a.fd[0] = b.fd[0] = -1;
  ASSERT_TRUE(enable_rx_timestamps(b.fd[1]));
  CanPort single = attach_can_port(a.fd[1], true), batched = attach_can_port(b.fd[1], true);

  std::vector<DriverError> want_e;
  std::vector<RxFrame> want_f;
  for (;;) {
    RxFrame f;
    const DriverError e = receive_rt(single, f);
    want_e.push_back(e), want_f.push_back(f);
    if (e == DriverError::kPeerClosed || e == DriverError::kRxEmpty) break;
  }
  ASSERT_EQ(want_e.back(), DriverError::kPeerClosed);
  ASSERT_EQ(want_e.size(), 2u * kMaxBatchFrames + 3 + 4);  // frames, bus-off, junk, FD, end

  std::vector<DriverError> got_e;
  std::vector<RxFrame> got_f;
  std::vector<int> call_sizes;
  for (int calls = 0; calls < 10; ++calls) {
    RxFrame f[kMaxBatchFrames];
    DriverError e[kMaxBatchFrames];
    const int n = receive_batch_rt(batched, f, e);
    call_sizes.push_back(n);
    for (int k = 0; k < n; ++k) got_e.push_back(e[k]), got_f.push_back(f[k]);
    if (n == 0 || e[n - 1] == DriverError::kPeerClosed) break;
  }
  EXPECT_EQ(call_sizes, (std::vector<int>{kMaxBatchFrames, kMaxBatchFrames, 7}));
  ASSERT_EQ(got_e, want_e);
  for (std::size_t i = 0; i + 1 < want_f.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(got_f[i].is_fd, want_f[i].is_fd);
    EXPECT_EQ(got_f[i].frame.can_id, want_f[i].frame.can_id);
    EXPECT_EQ(got_f[i].frame.len, want_f[i].frame.len);
    EXPECT_EQ(std::memcmp(got_f[i].frame.data, want_f[i].frame.data, want_f[i].frame.len), 0);
    if (want_e[i] != DriverError::kBadDatagram) {
      EXPECT_GT(got_f[i].rx_realtime_ns, 0);  // each datagram its own stamp
    }
  }
  EXPECT_EQ(batched.stats.rx_frames, single.stats.rx_frames);
  EXPECT_EQ(batched.stats.rx_bad, 1u);
  EXPECT_EQ(single.stats.rx_bad, 1u);
  EXPECT_TRUE(batched.health.bus_off);
  EXPECT_EQ(batched.health.bus_off, single.health.bus_off);
}

TEST(CanPortBatch, EmptyQueueReadsNothing) {
  Pair p;
  CanPort rx = attach_can_port(p.fd[1], false);
  RxFrame f[4];
  DriverError e[4];
  EXPECT_EQ(receive_batch_rt(rx, f, e), 0);
  EXPECT_EQ(rx.stats.io_errors, 0u);
}

// Sending: frames leave in order; a full queue drops (and counts) exactly the
// frames single sends would have dropped, and the rest of the batch is still tried.
TEST(CanPortBatch, SendKeepsOrderAndDropsWhatSingleSendsWouldDrop) {
  auto fill_to_full = [](int fd, int& queued) {
    const int small = 4096;
    ASSERT_EQ(setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &small, sizeof(small)), 0);
    queued = 0;
    const can_frame f = make_frame(0x1, 8, 0);
    while (send(fd, &f, CAN_MTU, MSG_DONTWAIT) == CAN_MTU) ++queued;
  };
  std::vector<can_frame> frames;
  for (int i = 0; i < 2 * kMaxBatchFrames + 5; ++i) frames.push_back(make_frame(0x200 + i, 8, static_cast<std::uint8_t>(i)));

  // In order, all of them, when there is room.
  {
    Pair p;
    CanPort tx = attach_can_port(p.fd[0], false), rx = attach_can_port(p.fd[1], false);
    std::vector<DriverError> e(frames.size(), DriverError::kIoError);
    send_batch_rt(tx, frames, e);
    EXPECT_EQ(e, std::vector<DriverError>(frames.size(), DriverError::kOk));
    EXPECT_EQ(tx.stats.tx_frames, frames.size());
    for (const can_frame& want : frames) {
      RxFrame got;
      ASSERT_EQ(receive_rt(rx, got), DriverError::kOk);
      EXPECT_EQ(got.frame.can_id, want.can_id);
      EXPECT_EQ(std::memcmp(got.frame.data, want.data, 8), 0);
    }
  }
  // A full queue: both ways agree frame by frame (DGRAM, whose queue a small
  // SO_SNDBUF bounds, as the FullQueue test above).
  Pair a(SOCK_DGRAM), b(SOCK_DGRAM);
  int queued_a = 0, queued_b = 0;
  fill_to_full(a.fd[0], queued_a);
  fill_to_full(b.fd[0], queued_b);
  ASSERT_EQ(queued_a, queued_b);
  CanPort single = attach_can_port(a.fd[0], false), batched = attach_can_port(b.fd[0], false);
  std::vector<DriverError> want, got(frames.size(), DriverError::kOk);
  for (const can_frame& f : frames) want.push_back(send_rt(single, f));
  send_batch_rt(batched, frames, got);
  EXPECT_EQ(got, want);
  EXPECT_EQ(got.front(), DriverError::kTxQueueFull);
  EXPECT_EQ(batched.stats.tx_dropped, frames.size());
  EXPECT_EQ(batched.stats.tx_dropped, single.stats.tx_dropped);
  EXPECT_EQ(batched.stats.io_errors, 0u);
  // Room for a few: the batch sends as many as single sends do, then drops the rest.
  for (int fd : {a.fd[1], b.fd[1]}) {
    can_frame sink;
    for (int k = 0; k < 3; ++k) ASSERT_EQ(recv(fd, &sink, sizeof(sink), MSG_DONTWAIT), CAN_MTU);
  }
  want.clear();
  for (const can_frame& f : frames) want.push_back(send_rt(single, f));
  send_batch_rt(batched, frames, got);
  EXPECT_EQ(got, want);
  EXPECT_EQ(got.front(), DriverError::kOk);
  EXPECT_EQ(got.back(), DriverError::kTxQueueFull);
  EXPECT_EQ(batched.stats.tx_frames, single.stats.tx_frames);
  EXPECT_EQ(batched.stats.tx_dropped, single.stats.tx_dropped);
}

TEST(CanPortBatch, SendCountsSplitSentDroppedAndFailed) {
  const DriverError results[] = {DriverError::kOk, DriverError::kTxQueueFull, DriverError::kBusOff,
                                 DriverError::kOk, DriverError::kPeerClosed, DriverError::kIoError};
  SendCounts counts;
  counts.sent = 1;  // adds to what is there
  count_sends(results, counts);
  EXPECT_EQ(counts.sent, 3);
  EXPECT_EQ(counts.dropped, 1);
  EXPECT_EQ(counts.failed, 3);
}

TEST(CanPortBatch, BusOffAndClosedPeerRefuseEveryFrame) {
  Pair p;
  CanPort port = attach_can_port(p.fd[1], false);
  const std::vector<can_frame> frames(3, make_frame(0x1, 1, 0));
  std::vector<DriverError> e(3, DriverError::kOk);
  port.health.bus_off = true;
  send_batch_rt(port, frames, e);
  EXPECT_EQ(e, std::vector<DriverError>(3, DriverError::kBusOff));
  EXPECT_EQ(port.stats.tx_frames + port.stats.tx_dropped + port.stats.io_errors, 0u);  // never reached the socket
  clear_bus_off(port.health);
  close(p.fd[0]);
  p.fd[0] = -1;
  send_batch_rt(port, frames, e);  // no SIGPIPE
  EXPECT_EQ(e, std::vector<DriverError>(3, DriverError::kPeerClosed));
  RxFrame f[4];
  DriverError r[4];
  EXPECT_EQ(receive_batch_rt(port, f, r), 1);  // one end-of-stream, not four
  EXPECT_EQ(r[0], DriverError::kPeerClosed);
}

TEST(CanPort, FrameIoDoesNotAllocate) {
  Pair p;
  ASSERT_TRUE(enable_rx_timestamps(p.fd[1]));
  CanPort tx = attach_can_port(p.fd[0], false), rx = attach_can_port(p.fd[1], false);
  RxFrame got;
  const can_frame f = make_frame(0x7, 8, 9);
  test::AllocTrap trap;
  for (int i = 0; i < 100; ++i) {
    (void)send_rt(tx, f);
    (void)receive_rt(rx, got);
  }
  (void)receive_rt(rx, got);
  const can_frame batch[3] = {f, f, f};
  DriverError results[kMaxBatchFrames];
  RxFrame rx_batch[kMaxBatchFrames];
  for (int i = 0; i < 100; ++i) {
    send_batch_rt(tx, batch, std::span<DriverError>(results, 3));
    (void)receive_batch_rt(rx, rx_batch, results);
  }
  EXPECT_EQ(trap.count(), 0u) << "first allocation " << trap.first_size_bytes() << " bytes";
}

}  // namespace
}  // namespace kuavo::drivers
