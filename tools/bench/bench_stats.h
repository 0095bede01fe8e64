// Order statistics of per-call timings for the benchmark programs' counters.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace kuavo::bench {

// The p-th percentile (0…100) of v, by rank ⌊n·p/100⌋ (p = 0: the minimum, 100: the maximum);
// sorts v in place.
inline double percentile(std::vector<double>& v, int p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, v.size() * static_cast<std::size_t>(p) / 100)];
}

}  // namespace kuavo::bench
