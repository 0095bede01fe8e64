#include "drivers/can/can_port.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <sys/socket.h>
#include <sys/uio.h>

namespace kuavo::drivers {

CanPort attach_can_port(int fd, bool fd_frames) {
  CanPort port;
  port.fd = fd;
  port.fd_frames = fd_frames;
  return port;
}

bool enable_rx_timestamps(int fd) {
  const int on = 1;
  return setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on)) == 0;
}

DriverError classify_send_errno(int err) {
  switch (err) {
    case ENOBUFS:  // CAN_RAW: the netdev TX queue is full (never blocks)
    case EAGAIN:   // socketpair / socket send buffer full
      return DriverError::kTxQueueFull;
    case EPIPE:
    case ECONNRESET:
      return DriverError::kPeerClosed;
    default:
      return DriverError::kIoError;
  }
}

namespace {

DriverError send_bytes_rt(CanPort& port, const void* bytes, std::size_t size) {
  // MSG_NOSIGNAL: a closed socketpair peer must not kill the process with SIGPIPE.
  const ssize_t n = ::send(port.fd, bytes, size, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n == static_cast<ssize_t>(size)) {
    ++port.stats.tx_frames;
    return DriverError::kOk;
  }
  const DriverError e = n < 0 ? classify_send_errno(errno) : DriverError::kIoError;
  if (e == DriverError::kTxQueueFull) {
    ++port.stats.tx_dropped;
  } else {
    ++port.stats.io_errors;
  }
  return e;
}

}  // namespace

DriverError send_rt(CanPort& port, const can_frame& frame) {
  if (port.health.bus_off) return DriverError::kBusOff;
  return send_bytes_rt(port, &frame, CAN_MTU);
}

DriverError send_fd_rt(CanPort& port, const canfd_frame& frame) {
  if (!port.fd_frames) return DriverError::kFdNotEnabled;
  if (port.health.bus_off) return DriverError::kBusOff;
  return send_bytes_rt(port, &frame, CANFD_MTU);
}

namespace {

// What receive_rt reports for a datagram of n bytes the kernel put in out.frame
// with the ancillary data in msg.
DriverError decode_datagram_rt(CanPort& port, RxFrame& out, ssize_t n, const msghdr& msg) {
  if (n == 0) return DriverError::kPeerClosed;  // SEQPACKET end-of-stream
  if (n == CAN_MTU) {
    out.is_fd = false;
    out.frame.len = out.frame.len > CAN_MAX_DLEN ? CAN_MAX_DLEN : out.frame.len;
  } else if (n == CANFD_MTU) {
    out.is_fd = true;
    out.frame.len = out.frame.len > CANFD_MAX_DLEN ? CANFD_MAX_DLEN : out.frame.len;
  } else {
    ++port.stats.rx_bad;
    return DriverError::kBadDatagram;
  }

  out.rx_realtime_ns = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(const_cast<msghdr*>(&msg), c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts;
      std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
      out.rx_realtime_ns = static_cast<hal::TimeNs>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
    }
  }

  if (out.frame.can_id & CAN_ERR_FLAG) {
    can_frame classic{};
    classic.can_id = out.frame.can_id;
    classic.len = out.frame.len > CAN_MAX_DLEN ? CAN_MAX_DLEN : out.frame.len;
    std::memcpy(classic.data, out.frame.data, CAN_MAX_DLEN);
    apply_error_frame_rt(classic, port.health);
    return DriverError::kErrorFrame;
  }
  ++port.stats.rx_frames;
  return DriverError::kOk;
}

// Room for one timestamp control message per datagram.
constexpr std::size_t kControlBytes = CMSG_SPACE(sizeof(timespec));

}  // namespace

DriverError receive_rt(CanPort& port, RxFrame& out) {
  iovec iov{&out.frame, sizeof(out.frame)};
  alignas(cmsghdr) unsigned char control[kControlBytes];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof(control);

  const ssize_t n = ::recvmsg(port.fd, &msg, MSG_DONTWAIT);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK) return DriverError::kRxEmpty;
    ++port.stats.io_errors;
    return DriverError::kIoError;
  }
  return decode_datagram_rt(port, out, n, msg);
}

void send_batch_rt(CanPort& port, std::span<const can_frame> frames, std::span<DriverError> results) {
  const int n = static_cast<int>(std::min(frames.size(), results.size()));
  if (port.health.bus_off) {
    for (int i = 0; i < n; ++i) results[i] = DriverError::kBusOff;
    return;
  }
  iovec iov[kMaxBatchFrames];
  mmsghdr msgs[kMaxBatchFrames];
  int i = 0;
  while (i < n) {
    const int chunk = std::min(n - i, kMaxBatchFrames);
    for (int k = 0; k < chunk; ++k) {
      iov[k] = iovec{const_cast<can_frame*>(&frames[i + k]), CAN_MTU};
      msgs[k] = mmsghdr{};
      msgs[k].msg_hdr.msg_iov = &iov[k];
      msgs[k].msg_hdr.msg_iovlen = 1;
    }
    // MSG_NOSIGNAL: a closed socketpair peer must not kill the process with SIGPIPE.
    const int sent = ::sendmmsg(port.fd, msgs, static_cast<unsigned>(chunk), MSG_DONTWAIT | MSG_NOSIGNAL);
    if (sent > 0) {
      for (int k = 0; k < sent; ++k) {
        if (msgs[k].msg_len == CAN_MTU) {
          ++port.stats.tx_frames;
          results[i + k] = DriverError::kOk;
        } else {
          ++port.stats.io_errors;
          results[i + k] = DriverError::kIoError;
        }
      }
      i += sent;
      continue;
    }
    // Frame i was refused (a later frame's error would have been reported as a
    // partial count and surfaces here on the next call).
    const DriverError e = sent < 0 ? classify_send_errno(errno) : DriverError::kIoError;
    if (e == DriverError::kTxQueueFull) {
      ++port.stats.tx_dropped;
    } else {
      ++port.stats.io_errors;
    }
    results[i++] = e;
  }
}

void count_sends(std::span<const DriverError> results, SendCounts& counts) {
  for (const DriverError e : results) {
    if (e == DriverError::kOk) {
      ++counts.sent;
    } else if (e == DriverError::kTxQueueFull) {
      ++counts.dropped;
    } else {
      ++counts.failed;
    }
  }
}

int receive_batch_rt(CanPort& port, std::span<RxFrame> out, std::span<DriverError> results) {
  const int want = static_cast<int>(std::min({out.size(), results.size(), static_cast<std::size_t>(kMaxBatchFrames)}));
  if (want <= 0) return 0;
  iovec iov[kMaxBatchFrames];
  alignas(cmsghdr) unsigned char control[kMaxBatchFrames][kControlBytes];
  mmsghdr msgs[kMaxBatchFrames];
  for (int k = 0; k < want; ++k) {
    iov[k] = iovec{&out[k].frame, sizeof(out[k].frame)};
    msgs[k] = mmsghdr{};
    msgs[k].msg_hdr.msg_iov = &iov[k];
    msgs[k].msg_hdr.msg_iovlen = 1;
    msgs[k].msg_hdr.msg_control = control[k];
    msgs[k].msg_hdr.msg_controllen = kControlBytes;
  }
  const int got = ::recvmmsg(port.fd, msgs, static_cast<unsigned>(want), MSG_DONTWAIT, nullptr);
  if (got < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK) return 0;
    ++port.stats.io_errors;
    results[0] = DriverError::kIoError;
    return 1;
  }
  for (int k = 0; k < got; ++k) {
    results[k] = decode_datagram_rt(port, out[k], static_cast<ssize_t>(msgs[k].msg_len), msgs[k].msg_hdr);
    if (results[k] == DriverError::kPeerClosed) return k + 1;  // end-of-stream repeats; one is enough
  }
  return got;
}

bool as_classic(const RxFrame& rx, can_frame& out) {
  if (rx.is_fd && rx.frame.len > CAN_MAX_DLEN) return false;
  out = can_frame{};
  out.can_id = rx.frame.can_id;
  out.len = rx.frame.len;
  std::memcpy(out.data, rx.frame.data, CAN_MAX_DLEN);
  return true;
}

}  // namespace kuavo::drivers
