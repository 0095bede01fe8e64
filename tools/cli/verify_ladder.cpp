#include "tools/cli/verify_ladder.h"

#include <algorithm>
#include <cmath>

namespace kuavo::cli {
namespace {

// A fall's range over which this many earlier ranges lie holds both feet down (the ladder's
// third rung).
constexpr int kHoldAfter = 2;

// How many of the first `count` ranges overlap [a, b).
int ranges_over(const std::vector<std::pair<int, int>>& ranges, std::size_t count, int a, int b) {
  int n = 0;
  for (std::size_t i = 0; i < count; ++i) n += a < ranges[i].second && ranges[i].first < b;
  return n;
}

}  // namespace

bool verification_range(double fell_at_s, int lead_frames, int dance_frames, double rate_hz, const VerifyLadder& ladder,
                        std::vector<std::pair<int, int>>& scaled, VerifyRange& out) {
  const int fall = static_cast<int>(std::lround(fell_at_s * rate_hz)) - lead_frames;  // dance clock
  const int a = std::max(0, fall - static_cast<int>(std::lround(ladder.before_s * rate_hz)));
  const int b = std::min(dance_frames, fall + static_cast<int>(std::lround(ladder.after_s * rate_hz)));
  if (b <= a) return false;
  // A fall where an earlier round already scaled the gestures: what is left of them there
  // goes (their 1 s average stays: the steps, the travel, the turns), and the dance takes
  // calm steps (RepairConfig::calm_*). Scaling by the same gain again (0.25, 0.125) left
  // cmu_05_20 falling at the same 9.5 s three rounds running. A third fall there: both feet
  // stay down over the range (the upper body's 1 s average goes on); with that, cmu_05_07
  // and cmu_05_20 danced floor and carpet (seed 1), where without it carpet still fell at
  // 8.1 and 9.4 s after 12 rounds.
  const int before = ranges_over(scaled, scaled.size(), a, b);
  scaled.emplace_back(a, b);
  const bool again = before > 0;
  out = {a, b, again ? 0.0 : ladder.gain, again, before >= kHoldAfter};
  return true;
}

bool gives_up_pushed_run(double push_start_s, double fell_at_s, int lead_frames, int dance_frames, double rate_hz,
                         const VerifyLadder& ladder, const std::vector<std::pair<int, int>>& scaled) {
  // The model errors alone (the push still to come), or a push long before: the ladder as for any fall.
  if (!(push_start_s < fell_at_s && push_start_s >= fell_at_s - ladder.before_s)) return false;
  std::vector<std::pair<int, int>> trial = scaled;
  VerifyRange next;
  return verification_range(fell_at_s, lead_frames, dance_frames, rate_hz, ladder, trial, next) && next.hold;
}

bool gives_up_held_run(double fell_at_s, int lead_frames, int dance_frames, double rate_hz, const VerifyLadder& ladder,
                       const std::vector<std::pair<int, int>>& scaled) {
  std::vector<std::pair<int, int>> trial;
  VerifyRange range;
  if (!verification_range(fell_at_s, lead_frames, dance_frames, rate_hz, ladder, trial, range)) return false;
  // Replay the ladder over the earlier ranges, in order: the i-th held the feet down if
  // kHoldAfter before it overlapped it, as verification_range decided then.
  for (std::size_t i = 0; i < scaled.size(); ++i) {
    const auto& [a, b] = scaled[i];
    if (ranges_over(scaled, i, a, b) >= kHoldAfter && range.a < b && a < range.b) return true;
  }
  return false;
}

}  // namespace kuavo::cli
