// "Nice" axis ticks: steps of 1, 2 or 5 times a power of ten, as a reader would pick by hand.
#pragma once

#include <string>
#include <vector>

namespace kuavo::report {

struct AxisTicks {
  double step = 1.0;           // 1, 2 or 5 x 10^k
  std::vector<double> values;  // every multiple of step inside [lo, hi], ascending
};

// Ticks for the finite range lo < hi, with the step whose interval count is closest to
// target_intervals (at least 1).
AxisTicks nice_ticks(double lo, double hi, int target_intervals);

// The label of a tick value: as many decimals as the step needs, never "-0"; exponent form for
// very large or very small magnitudes.
std::string format_tick(double value, double step);

}  // namespace kuavo::report
