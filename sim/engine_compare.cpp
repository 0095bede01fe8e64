#include "sim/engine_compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace kuavo::sim {
namespace {

std::string outcome(const RunSummary& r) {
  char buf[96];
  if (!r.ok) return "the simulation failed (" + r.error + ")";
  if (r.fell) {
    std::snprintf(buf, sizeof buf, "fell at %.2f s", r.fell_at_s);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "stayed up to the end (%.2f s)", r.sim_time_s);
  return buf;
}

void compare_tracking(const char* what, double simbody_rad, double mujoco_rad, EngineComparison& c) {
  const double hi = std::max(simbody_rad, mujoco_rad), lo = std::min(simbody_rad, mujoco_rad);
  if (hi <= kTrackingFloor_rad || hi <= kTrackingRatio * lo) return;
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s tracking RMS: simbody %.4f rad, mujoco %.4f rad (over %.1fx apart)", what, simbody_rad,
                mujoco_rad, kTrackingRatio);
  c.disagreements.emplace_back(buf);
}

// The summaries end with "}\n"; nested, they keep their lines.
std::string trimmed(std::string json) {
  while (!json.empty() && (json.back() == '\n' || json.back() == ' ')) json.pop_back();
  return json;
}

}  // namespace

EngineComparison compare_engines(const MotionSummary& simbody, const MotionSummary& mujoco) {
  EngineComparison c;
  const RunSummary &a = simbody.run, &b = mujoco.run;
  const bool same_outcome = a.ok == b.ok && a.fell == b.fell;
  if (!same_outcome || (a.fell && b.fell && std::abs(a.fell_at_s - b.fell_at_s) > kFallTimesApart_s)) {
    c.disagreements.push_back("simbody: " + outcome(a) + "; mujoco: " + outcome(b));
  }
  if (a.ok && b.ok) {
    compare_tracking("legs", simbody.tracking_rms_legs_rad, mujoco.tracking_rms_legs_rad, c);
    compare_tracking("arms", simbody.tracking_rms_arms_rad, mujoco.tracking_rms_arms_rad, c);
    if (std::abs(simbody.steps - mujoco.steps) >= kLiftOffsApart) {
      char buf[120];
      std::snprintf(buf, sizeof buf, "lift-offs: simbody %d, mujoco %d", simbody.steps, mujoco.steps);
      c.disagreements.emplace_back(buf);
    }
  }
  c.agree = c.disagreements.empty();
  return c;
}

std::string engine_comparison_json(const EngineComparison& c, const std::string& simbody_json,
                                   const std::string& mujoco_json) {
  std::string json = "{\n  \"engine\": \"both\",\n  \"agree\": ";
  json += c.agree ? "true" : "false";
  json += ",\n  \"disagreements\": [";
  for (std::size_t i = 0; i < c.disagreements.size(); ++i) {
    json += (i == 0 ? "\n    \"" : ",\n    \"") + c.disagreements[i] + "\"";
  }
  json += c.disagreements.empty() ? "],\n" : "\n  ],\n";
  json += "  \"simbody\": " + trimmed(simbody_json) + ",\n  \"mujoco\": " + trimmed(mujoco_json) + "\n}\n";
  return json;
}

}  // namespace kuavo::sim
