#include "tools/cli/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rtos_shim/clock.h"

namespace kuavo::cli {
namespace {

// Redraw at most this often (a terminal line, not an animation).
constexpr std::int64_t kRedrawPeriod_ns = 200'000'000;
// Below this fraction done the estimate of the time left is noise: not shown.
constexpr double kEstimateFrom = 0.02;

}  // namespace

std::string format_duration(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  if (s >= 60) {
    std::snprintf(buf, sizeof buf, "%ld min %02ld s", s / 60, s % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%ld s", s);
  }
  return buf;
}

Progress::Progress(bool quiet) : shown_(!quiet && ::isatty(STDERR_FILENO) == 1) {
  start_ns_ = rtos::now_ns();
}

Progress::~Progress() { clear(); }

void Progress::update(double done, const std::string& what) {
  if (!shown_) return;
  const std::int64_t now = rtos::now_ns();
  const bool changed = what != what_;
  done_ = std::clamp(done, 0.0, total_);
  what_ = what;
  if (!changed && now - last_ns_ < kRedrawPeriod_ns) return;
  last_ns_ = now;
  const double fraction = total_ > 0.0 ? done_ / total_ : 0.0;
  const double elapsed_s = 1e-9 * static_cast<double>(now - start_ns_);
  std::string left;
  if (fraction >= kEstimateFrom && fraction < 1.0) left = "  ~" + format_duration(elapsed_s * (1.0 - fraction) / fraction) + " left";
  std::fprintf(stderr, "\r\033[K[%3.0f%%] %s%s", 100.0 * fraction, what_.c_str(), left.c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::clear() {
  if (!drawn_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  drawn_ = false;
}

}  // namespace kuavo::cli
