#include "tools/report/axis_ticks.h"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace kuavo::report {
namespace {

// Rounding slack when deciding whether a multiple of the step lies inside the range, so a tick
// that lands on the range end by arithmetic (0.1 * 3 vs 0.3) is not lost.
constexpr double kTickEdgeTolerance_steps = 1e-9;
// Beyond these magnitudes fixed-point labels get long: switch to exponent form.
constexpr double kMaxFixedMagnitude = 1e6;
constexpr double kMinFixedStep = 1e-5;
// A bound on the tick count whatever the caller asks for (keeps a bad target from flooding).
constexpr int kMaxTicks = 200;

}  // namespace

AxisTicks nice_ticks(double lo, double hi, int target_intervals) {
  AxisTicks ticks;
  const double span = hi - lo;
  if (!(span > 0.0) || !std::isfinite(span)) return ticks;
  target_intervals = std::clamp(target_intervals, 1, kMaxTicks - 1);
  const double raw = span / target_intervals;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  // The nice step whose interval count is nearest the target; "nearest" in ratio terms, so the
  // thresholds are the geometric means between 1, 2, 5 and 10.
  const double mantissa = raw / magnitude;
  double nice = 10.0;
  if (mantissa < std::sqrt(2.0)) {
    nice = 1.0;
  } else if (mantissa < std::sqrt(10.0)) {
    nice = 2.0;
  } else if (mantissa < std::sqrt(50.0)) {
    nice = 5.0;
  }
  ticks.step = nice * magnitude;
  const double first = std::ceil(lo / ticks.step - kTickEdgeTolerance_steps);
  const double last = std::floor(hi / ticks.step + kTickEdgeTolerance_steps);
  for (double k = first; k <= last && static_cast<int>(ticks.values.size()) < kMaxTicks; k += 1.0) {
    const double v = k * ticks.step;  // k * step, not a running sum: no drift
    ticks.values.push_back(k == 0.0 ? 0.0 : v);
  }
  return ticks;
}

std::string format_tick(double value, double step) {
  if (std::abs(value) < step * kTickEdgeTolerance_steps) value = 0.0;  // never "-0"
  char buf[64];
  std::to_chars_result r{};
  if (std::abs(value) >= kMaxFixedMagnitude || step < kMinFixedStep) {
    // Enough significant digits to tell neighbouring ticks apart (1000000.5 vs 1000001).
    const int digits =
        static_cast<int>(std::floor(std::log10(std::max(std::abs(value), step))) - std::floor(std::log10(step))) + 1;
    r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, std::clamp(digits, 1, 17));
  } else {
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
    r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::fixed, decimals);
  }
  return std::string(buf, r.ptr);
}

}  // namespace kuavo::report
