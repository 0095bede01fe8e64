// Progress of a long command (kuavo demo, kuavo paper) on a terminal: one line rewritten in
// place on stderr, "[ 42%] dance_carpet: simulating  ~1 min 05 s left". Shown only when
// stderr is a terminal and --quiet was not given, so piped and CI output stays clean.
// The remaining time is the elapsed wall time scaled by the work left (work is counted in
// the caller's units, e.g. simulated seconds weighted by their cost).
#pragma once

#include <cstdint>
#include <string>

namespace kuavo::cli {

class Progress {
 public:
  explicit Progress(bool quiet);
  ~Progress();
  bool shown() const { return shown_; }
  void set_total(double work) { total_ = work; }
  // Work done so far (absolute) and what is running now.
  void update(double done, const std::string& what);
  // Clears the line (before the caller prints a result).
  void clear();

 private:
  bool shown_ = false;
  double total_ = 1.0, done_ = 0.0;
  std::int64_t start_ns_ = 0, last_ns_ = 0;
  std::string what_;
  bool drawn_ = false;
};

// "1 min 05 s", "12 s": for progress lines.
std::string format_duration(double seconds);

}  // namespace kuavo::cli
