// Non-blocking frame I/O on an already-open descriptor. Opening lives in
// can_socket.h; keeping the two apart lets tests and the bus emulator carry the
// same frames over a socketpair(AF_UNIX, SOCK_SEQPACKET) - one datagram per
// frame, exactly as a CAN_RAW socket delivers them.
//
// Every function here is real-time safe: no heap, no blocking (MSG_DONTWAIT),
// no printing. Counters are plain integers owned by the single bus thread.
#pragma once

#include <cstdint>
#include <span>
#include <linux/can.h>

#include "controllers/hal/types.h"
#include "drivers/can/bus_health.h"
#include "drivers/driver_error.h"

namespace kuavo::drivers {

struct CanPortStats {
  std::uint64_t tx_frames = 0;
  std::uint64_t tx_dropped = 0;   // ENOBUFS/EAGAIN: the queue was full, frame not sent
  std::uint64_t rx_frames = 0;    // data frames delivered to the caller
  std::uint64_t rx_bad = 0;       // datagrams of a size that is no CAN frame
  std::uint64_t io_errors = 0;
};

struct CanPort {
  int fd = -1;
  bool fd_frames = false;  // CAN_RAW_FD_FRAMES enabled on the socket
  CanPortStats stats{};
  BusHealth health{};
};

// A received frame. Classic frames are stored in the canfd_frame layout (the
// header and the first 8 data bytes coincide, see linux/can.h).
struct RxFrame {
  canfd_frame frame{};
  bool is_fd = false;
  // Kernel receive time (SO_TIMESTAMPNS, CLOCK_REALTIME), 0 if the socket gave
  // none. The firmware converts it to the monotonic base with the offset
  // rtos_shim measures each cycle; the drivers never read a clock themselves.
  hal::TimeNs rx_realtime_ns = 0;
};

// Wraps an open descriptor (CAN_RAW socket or one end of a socketpair).
CanPort attach_can_port(int fd, bool fd_frames);

// Asks the kernel to stamp received datagrams (works on CAN_RAW and AF_UNIX).
// Start-up only. Returns false with errno set on failure.
bool enable_rx_timestamps(int fd);

// Sends one classic frame. kTxQueueFull means the frame was dropped and
// counted; the caller resends the newest command next cycle, never waits.
DriverError send_rt(CanPort& port, const can_frame& frame);
DriverError send_fd_rt(CanPort& port, const canfd_frame& frame);

// Reads at most one datagram. kRxEmpty when nothing is queued. Error frames
// update port.health and return kErrorFrame (the frame is still copied out).
DriverError receive_rt(CanPort& port, RxFrame& out);

// A cycle's frames in one system call where the kernel takes them (sendmmsg /
// recvmmsg): each frame's result is exactly what send_rt / receive_rt would
// have returned for it, in order, at a fraction of the per-frame syscall cost
// (the bus cycle's largest share on the robot's NUC). Buffers: the caller's.
inline constexpr int kMaxBatchFrames = 16;

// Sends frames[i] for i < min(sizes), in order; results[i] as send_rt. A
// frame the kernel refuses is counted and skipped; the rest are still tried.
void send_batch_rt(CanPort& port, std::span<const can_frame> frames, std::span<DriverError> results);

// A batch's send results as the bus cycles report them: kOk sent, kTxQueueFull
// dropped, anything else (bus-off, closed peer, I/O error) failed.
struct SendCounts {
  int sent = 0, dropped = 0, failed = 0;
};
void count_sends(std::span<const DriverError> results, SendCounts& counts);

// Reads up to min(out.size(), results.size(), kMaxBatchFrames) datagrams;
// results[i] as receive_rt. Returns how many results it wrote: 0 when the
// queue is empty; a kPeerClosed or kIoError result is the last one written.
// Fewer than asked (and no kPeerClosed / kIoError) means the queue is empty.
int receive_batch_rt(CanPort& port, std::span<RxFrame> out, std::span<DriverError> results);

// Copies a received classic frame into `out`; false for an FD frame > 8 bytes.
bool as_classic(const RxFrame& rx, can_frame& out);

// Maps a send() errno to the driver error (exposed so the rule is testable).
DriverError classify_send_errno(int err);

}  // namespace kuavo::drivers
