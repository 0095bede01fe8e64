// One run of a real program under a time and an address-space limit, its output captured:
// what the end-to-end fuzz harness judges (crash, hang, exit code, output).
#pragma once

#include <string>
#include <vector>

namespace kuavo::fuzz {

struct RunLimits {
  double timeout_s = 20.0;       // then SIGKILL: a hang
  long memory_bytes = 512L << 20;  // RLIMIT_AS: exhaustion must become exit 1, never a crash; 0: none
};

struct RunResult {
  enum class End { kExited, kSignal, kTimeout, kNotStarted } end = End::kNotStarted;
  int code = -1;  // exit code, or the signal
  std::string out, err;
};

// Runs argv[0] (a path) with argv in `workdir` (its cwd; stdin /dev/null, no core files).
RunResult run_limited(const std::vector<std::string>& argv, const std::string& workdir, const RunLimits& limits);

// "" if the run ended as a program must (exit 0, 1 or 2), otherwise what happened:
// "crash: signal 11 (Segmentation fault)", "hang: killed after 20 s", "exit 134".
std::string judge_end(const RunResult& r, const RunLimits& limits);

}  // namespace kuavo::fuzz
