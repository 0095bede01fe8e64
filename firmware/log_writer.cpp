#include "firmware/log_ring.h"

#include "rtos_shim/clock.h"

namespace kuavo::firmware {

int format_log_record(const LogRecord& r, char* buf, int size) {
  const double t_s = static_cast<double>(r.stamp_ns) * 1e-9;
  switch (r.kind) {
    case LogKind::kModeChange:
      return std::snprintf(buf, size, "%.4f mode %s (fault %u: %s)\n", t_s, to_string(r.mode),
                           static_cast<unsigned>(r.fault), to_string(r.fault));
    case LogKind::kFault:
      return std::snprintf(buf, size, "%.4f FAULT %u: %s (joint %d) in %s\n", t_s, static_cast<unsigned>(r.fault),
                           to_string(r.fault), r.joint, to_string(r.mode));
    case LogKind::kStatus:
      return std::snprintf(buf, size, "%.4f status %s max tilt %.3f rad\n", t_s, to_string(r.mode), r.value);
  }
  return std::snprintf(buf, size, "%.4f unknown record\n", t_s);
}

int LogWriter::drain(LogSink& sink, std::FILE* out) {
  LogRecord r;
  int n = 0;
  char line[160];
  while (sink.ring.try_pop_rt(r)) {
    format_log_record(r, line, sizeof line);
    if (out != nullptr) std::fputs(line, out);
    ++n;
  }
  if (out != nullptr && n > 0) std::fflush(out);
  return n;
}

void LogWriter::start(LogSink& sink, std::FILE* out) {
  stop_.store(false);
  thread_ = std::thread([this, &sink, out] {
    while (!stop_.load(std::memory_order_relaxed)) {
      drain(sink, out);
      rtos::sleep_until_ns_rt(rtos::now_ns() + 10'000'000);  // 10 ms: not real-time, just frequent
    }
    drain(sink, out);
  });
}

void LogWriter::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

}  // namespace kuavo::firmware
