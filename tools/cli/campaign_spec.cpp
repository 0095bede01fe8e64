#include "tools/cli/campaign_spec.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "controllers/estimator/estimator.h"
#include "sim/push_option.h"

namespace kuavo::cli {
namespace {

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double unit_from_bits(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

bool string_list(const nlohmann::json& j, const char* key, std::vector<std::string>& out, std::string& error) {
  if (!j.contains(key) || !j[key].is_array() || j[key].empty()) {
    error = std::string("\"") + key + "\" must be a non-empty list of strings";
    return false;
  }
  for (const auto& v : j[key]) {
    if (!v.is_string() || v.get<std::string>().empty()) {
      error = std::string("\"") + key + "\" must be a non-empty list of strings";
      return false;
    }
    out.push_back(v.get<std::string>());
  }
  return true;
}

bool number(const nlohmann::json& j, const char* key, double& out, std::string& error) {
  if (!j.contains(key)) return true;
  if (!j[key].is_number() || !std::isfinite(j[key].get<double>())) {
    error = std::string("\"") + key + "\" must be a finite number";
    return false;
  }
  out = j[key].get<double>();
  return true;
}

// A boolean key; absent: out untouched (Out: bool, or std::optional<bool> left unset).
template <class Out>
bool boolean(const nlohmann::json& j, const char* key, Out& out, std::string& error) {
  if (!j.contains(key)) return true;
  if (!j[key].is_boolean()) {
    error = std::string("\"") + key + "\" must be true or false";
    return false;
  }
  out = j[key].get<bool>();
  return true;
}

// An optional key in [lo, hi] (range: the bounds as the message says them); absent: out unset.
bool optional_number(const nlohmann::json& j, const char* key, double lo, double hi, const char* range,
                     std::optional<double>& out, std::string& error) {
  if (!j.contains(key)) return true;
  double value = 0.0;
  if (!number(j, key, value, error)) return false;
  if (!(value >= lo && value <= hi)) {
    error = std::string("\"") + key + "\" must be " + range;
    return false;
  }
  out = value;
  return true;
}

}  // namespace

bool parse_campaign_spec(const std::string& text, CampaignSpec& out, std::string& error) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    error = "the spec is not a JSON object";
    return false;
  }
  static const char* const kKeys[] = {"name", "motions", "grounds", "perturbations", "seeds",
                                      "first_seed", "planner", "liftoff_hold", "plan_anchor", "plan_anchor_home",
                                      "estimator_unloaded_foot_N", "planner_sole_inset_m", "recovery_fast_swing_s",
                                      "surface_sink_m", "lean_trim", "holdable_soles", "duration_s", "push"};
  for (const auto& [key, value] : j.items()) {
    bool known = false;
    for (const char* k : kKeys) known = known || key == k;
    if (!known) {
      error = "unknown key \"" + key + "\"";
      return false;
    }
  }
  CampaignSpec s;
  s.name = j.value("name", std::string("campaign"));
  if (!string_list(j, "motions", s.motions, error) || !string_list(j, "grounds", s.grounds, error) ||
      !string_list(j, "perturbations", s.perturbations, error)) {
    return false;
  }
  for (const std::string& g : s.grounds) {
    if (g != "floor" && g != "carpet") {
      error = "ground '" + g + "' must be floor or carpet";
      return false;
    }
  }
  if (!j.contains("seeds") || !j["seeds"].is_number_integer() || j["seeds"].get<long long>() < 1 ||
      j["seeds"].get<long long>() > 100000) {
    error = "\"seeds\" must be an integer in 1..100000";
    return false;
  }
  s.seeds = static_cast<int>(j["seeds"].get<long long>());
  if (j.contains("first_seed")) {
    if (!j["first_seed"].is_number_unsigned()) {
      error = "\"first_seed\" must be an unsigned integer";
      return false;
    }
    s.first_seed = j["first_seed"].get<std::uint64_t>();
  }
  s.planner = j.value("planner", std::string("mpc"));
  if (s.planner != "mpc" && s.planner != "kinematic") {
    error = "\"planner\" must be mpc or kinematic";
    return false;
  }
  if (!boolean(j, "liftoff_hold", s.liftoff_hold, error) || !boolean(j, "plan_anchor", s.plan_anchor, error) ||
      !boolean(j, "holdable_soles", s.holdable_soles, error)) {
    return false;
  }
  if (j.contains("lean_trim")) {
    const nlohmann::json& v = j["lean_trim"];
    if (v.is_boolean()) {
      s.lean_trim = v.get<bool>() ? "on" : "off";
    } else if (v.is_string() && (v == "off" || v == "opening" || v == "always")) {
      s.lean_trim = v.get<std::string>();
    } else {
      error = "\"lean_trim\" must be \"off\", \"opening\", \"always\", true or false";
      return false;
    }
  }
  if (!optional_number(j, "plan_anchor_home", 0.0, 0.5, "0..0.5", s.plan_anchor_home, error)) return false;
  if (!optional_number(j, "estimator_unloaded_foot_N", 0.0, 1000.0, "0..1000 N", s.estimator_unloaded_foot_N, error)) {
    return false;
  }
  if (!optional_number(j, "planner_sole_inset_m", 0.0, 0.04, "0..0.04 m", s.planner_sole_inset_m, error)) return false;
  if (!optional_number(j, "recovery_fast_swing_s", 0.2, 0.4, "0.2..0.4 s", s.recovery_fast_swing_s, error)) return false;
  if (j.contains("surface_sink_m")) {
    const nlohmann::json& sink = j["surface_sink_m"];
    if (!sink.is_object()) {
      error = "\"surface_sink_m\" must be an object {GROUND: M}";
      return false;
    }
    for (const auto& [ground, value] : sink.items()) {
      double* out_m = ground == "carpet" ? &s.carpet_sink_m : ground == "floor" ? &s.floor_sink_m : nullptr;
      if (out_m == nullptr) {
        error = "\"surface_sink_m\": ground '" + ground + "' must be floor or carpet";
        return false;
      }
      if (!value.is_number() || !(value.get<double>() >= 0.0 && value.get<double>() <= estimator::kMaxStanceSink_m)) {
        char range[48];
        std::snprintf(range, sizeof range, " must be a number in 0..%g m", estimator::kMaxStanceSink_m);
        error = "\"surface_sink_m\"." + ground + range;
        return false;
      }
      *out_m = value.get<double>();
    }
  }
  if (!number(j, "duration_s", s.duration_s, error)) return false;
  if (!(s.duration_s >= 0.0 && s.duration_s <= sim::kMaxRunDuration_s)) {
    error = "\"duration_s\" must be 0..600 s (0: the motion's length)";
    return false;
  }
  if (j.contains("push")) {
    const nlohmann::json& p = j["push"];
    if (!p.is_object()) {
      error = "\"push\" must be an object";
      return false;
    }
    s.push.enabled = true;
    if (!number(p, "impulse_Ns", s.push.impulse_Ns, error) || !number(p, "duration_s", s.push.duration_s, error) ||
        !number(p, "start_after_s", s.push.start_after_s, error) || !number(p, "end_before_s", s.push.end_before_s, error)) {
      return false;
    }
    if (!(s.push.impulse_Ns > 0.0) || !(s.push.duration_s > 0.0) || s.push.start_after_s < 0.0 || s.push.end_before_s < 0.0) {
      error = "\"push\" needs impulse_Ns > 0, duration_s > 0 and non-negative start_after_s, end_before_s";
      return false;
    }
    // What `kuavo simulate --push` takes (sim/push_option.h), checked here once, not per run.
    if (!(s.push.duration_s <= sim::kPushMaxDuration_s && s.push.impulse_Ns / s.push.duration_s <= sim::kPushMaxForce_N &&
          s.push.start_after_s <= sim::kPushMaxStart_s)) {
      error = "\"push\" must stay a push: duration_s <= 10 s, impulse_Ns / duration_s <= 2000 N, start_after_s <= 600 s";
      return false;
    }
  }
  out = s;
  return true;
}

std::string motion_name(const std::string& entry) {
  std::string name = entry;
  const auto slash = name.find_last_of('/');
  if (slash != std::string::npos) name = name.substr(slash + 1);
  const auto dot = name.rfind('.');
  if (dot != std::string::npos && dot > 0) name = name.substr(0, dot);
  return name;
}

bool draw_push(const PushSpec& spec, std::uint64_t seed, double run_length_s, PushDraw& out) {
  const double lo = spec.start_after_s;
  const double hi = run_length_s - spec.end_before_s - spec.duration_s;
  if (!(hi >= lo)) return false;
  const std::uint64_t a = splitmix64(seed ^ 0x7075736800000000ULL);  // "push"
  const std::uint64_t b = splitmix64(a);
  // Whole milliseconds: the command line carries the time exactly.
  out.start_s = std::floor((lo + (hi - lo) * unit_from_bits(a)) * 1000.0) / 1000.0;
  out.direction_rad = 2.0 * 3.14159265358979323846 * unit_from_bits(b);
  out.force_N = spec.impulse_Ns / spec.duration_s;
  return true;
}

bool draw_show_push(std::uint64_t seed, double run_length_s, double impulse_Ns, PushDraw& out, PushSpec& spec_out) {
  if (!(impulse_Ns > 0.0) || !std::isfinite(impulse_Ns)) return false;
  CampaignSpec show;
  std::string error;
  if (!parse_campaign_spec(kShowConditionsSpec, show, error)) return false;
  spec_out = show.push;
  spec_out.impulse_Ns = impulse_Ns;
  return draw_push(spec_out, seed, run_length_s, out);
}

void wilson_interval_95(int falls, int runs, double& lo, double& hi) {
  lo = 0.0;
  hi = 1.0;
  if (runs <= 0) return;
  constexpr double z = 1.959963984540054;
  const double n = runs;
  const double p = falls / n;
  const double denom = 1.0 + z * z / n;
  const double centre = (p + z * z / (2.0 * n)) / denom;
  const double half = z * std::sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n)) / denom;
  // At 0 (or all) falls the bound is 0 (or 1) exactly; the subtraction leaves rounding.
  lo = falls == 0 ? 0.0 : std::max(0.0, centre - half);
  hi = falls == runs ? 1.0 : std::min(1.0, centre + half);
}

}  // namespace kuavo::cli
