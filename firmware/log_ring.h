// Firmware log: the real-time cycle pushes fixed-size records into a lock-free
// SPSC ring (rtos_shim) and never waits; a normal thread drains the ring and
// formats text. A full ring drops the record and counts it (the cycle must
// not block on a slow terminal or disk).
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <thread>

#include "controllers/hal/types.h"
#include "firmware/fault.h"
#include "firmware/mode_machine.h"
#include "rtos_shim/spsc_ring.h"

namespace kuavo::firmware {

enum class LogKind : std::uint8_t {
  kModeChange = 0,  // mode entered; fault = the latched fault (if any)
  kFault = 1,       // a fault latched; joint = offending joint or -1
  kStatus = 2,      // periodic: value = max tilt since last status [rad]
};

struct LogRecord {
  hal::TimeNs stamp_ns = 0;
  LogKind kind = LogKind::kStatus;
  Mode mode = Mode::kBoot;
  Fault fault = Fault::kNone;
  std::int16_t joint = -1;
  double value = 0.0;
};

// 1024 records: at most a few per cycle on transitions; the writer drains
// every 10 ms, so the ring absorbs seconds of a stalled writer.
using LogRing = rtos::SpscRing<LogRecord, 1024>;

struct LogSink {
  LogRing ring;
  std::atomic<std::uint64_t> dropped{0};
};

// Real-time side: push or count a drop.
inline void log_rt(LogSink& sink, const LogRecord& r) noexcept {
  if (!sink.ring.try_push_rt(r)) sink.dropped.fetch_add(1, std::memory_order_relaxed);
}

// One line of text for a record (non-real-time).
int format_log_record(const LogRecord& r, char* buf, int size);

// Non-real-time writer thread: drains `sink` into `out` until stopped, then
// drains what is left. Start-up/shut-down only.
class LogWriter {
 public:
  LogWriter() = default;
  ~LogWriter() { stop(); }
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  void start(LogSink& sink, std::FILE* out);
  void stop();
  // Drains the ring once on the caller's thread (tests, shut-down); returns records written.
  static int drain(LogSink& sink, std::FILE* out);

 private:
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

}  // namespace kuavo::firmware
