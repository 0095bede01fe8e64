#include "tools/report/decimate.h"

#include <algorithm>
#include <cmath>

namespace kuavo::report {

void decimate_min_max(std::span<const double> px, std::span<const double> py, std::vector<std::size_t>* keep) {
  keep->clear();
  const std::size_t n = std::min(px.size(), py.size());
  std::size_t begin = 0;
  while (begin < n) {
    const double column = std::floor(px[begin]);
    std::size_t end = begin + 1;
    std::size_t lowest = begin, highest = begin;
    while (end < n && std::floor(px[end]) == column) {
      if (py[end] < py[lowest]) lowest = end;
      if (py[end] > py[highest]) highest = end;
      ++end;
    }
    std::size_t picks[4] = {begin, lowest, highest, end - 1};
    std::sort(picks, picks + 4);
    for (std::size_t i = 0; i < 4; ++i) {
      if (i == 0 || picks[i] != picks[i - 1]) keep->push_back(picks[i]);
    }
    begin = end;
  }
}

}  // namespace kuavo::report
