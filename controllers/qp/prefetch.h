// Software prefetch of the next stage's data, sent in slices between the current stage's
// kernels (the Riccati matrix pass, riccati.h).
//
// Why: at the MPC's size each stage's data (~45 KB of factor storage, ~25 KB of QP matrices)
// is touched once per call, and after the planning task's 18 ms of idle it comes from beyond
// the caches (the VM's neighbours share the last level): the matrix pass then waits for memory
// line by line, ~1.1 ms of a 2.5 ms solve. The lines a stage will touch are known before it
// runs, so the stage before it asks for them a slice at a time while its FMAs run. A prefetch
// changes no value: every result is bit for bit what it was.
//
// A plan is a list of address ranges (whole cache lines) and a cursor; issue(n) sends the next
// n lines. Fixed capacity, no allocation; a range that does not fit is counted in dropped()
// and only not prefetched.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace kuavo::qp {

inline constexpr int kCacheLine = 64;

template <int kMaxRanges>
class PrefetchPlan {
 public:
  void clear() {
    count_ = range_ = next_ = lines_ = dropped_ = 0;
  }
  // The lines of [p, p + bytes), to be read or (write) written: those are fetched owned.
  // A range starting in or right after the previous one's lines (same kind) extends it.
  void add(const void* p, std::size_t bytes, bool write) {
    if (bytes == 0) return;
    const auto address = reinterpret_cast<std::uintptr_t>(p);
    const std::uintptr_t first = address & ~std::uintptr_t{kCacheLine - 1};
    const std::uintptr_t end = (address + bytes + kCacheLine - 1) & ~std::uintptr_t{kCacheLine - 1};
    if (count_ > 0) {
      Range& last = ranges_[count_ - 1];
      const std::uintptr_t last_end = last.first + static_cast<std::uintptr_t>(last.lines) * kCacheLine;
      if (last.write == write && first >= last.first && first <= last_end) {
        if (end > last_end) {
          const int more = static_cast<int>((end - last_end) / kCacheLine);
          last.lines += more;
          lines_ += more;
        }
        return;
      }
    }
    if (count_ == kMaxRanges) {
      ++dropped_;
      return;
    }
    ranges_[count_++] = {first, static_cast<int>((end - first) / kCacheLine), write};
    lines_ += ranges_[count_ - 1].lines;
  }
  // Rows [row0, row1) of column j of a column-major matrix (leading dimension ld).
  void add_column(const double* m, int ld, int j, int row0, int row1, bool write) {
    if (row1 > row0) add(m + j * ld + row0, static_cast<std::size_t>(row1 - row0) * sizeof(double), write);
  }
  int lines() const { return lines_; }
  int ranges() const { return count_; }
  int dropped() const { return dropped_; }
  // Whether the byte at p lies in the plan's lines (tests).
  bool covers(const void* p) const {
    const auto a = reinterpret_cast<std::uintptr_t>(p);
    for (int i = 0; i < count_; ++i) {
      if (a >= ranges_[i].first && a < ranges_[i].first + static_cast<std::uintptr_t>(ranges_[i].lines) * kCacheLine) return true;
    }
    return false;
  }
  // Sends the next n lines of the plan (fewer at its end).
  void issue(int n) {
    while (n > 0 && range_ < count_) {
      const Range& r = ranges_[range_];
      const int take = r.lines - next_ < n ? r.lines - next_ : n;
      const char* a = reinterpret_cast<const char*>(r.first) + static_cast<std::ptrdiff_t>(next_) * kCacheLine;
      if (r.write) {
        for (int i = 0; i < take; ++i, a += kCacheLine) __builtin_prefetch(a, 1, 3);
      } else {
        for (int i = 0; i < take; ++i, a += kCacheLine) __builtin_prefetch(a, 0, 3);
      }
      next_ += take;
      n -= take;
      if (next_ == r.lines) {
        ++range_;
        next_ = 0;
      }
    }
  }
  // Sends the rest of the plan.
  void finish() { issue(lines_); }

 private:
  struct Range {
    std::uintptr_t first = 0;
    int lines = 0;
    bool write = false;
  };
  std::array<Range, kMaxRanges> ranges_{};
  int count_ = 0;
  int range_ = 0;
  int next_ = 0;
  int lines_ = 0;
  int dropped_ = 0;
};

}  // namespace kuavo::qp
