// `kuavo campaign SPEC`: the spec (a JSON file), the run matrix it expands to, each run's
// deterministic push, and the fall-rate interval. Offline code (heap, exceptions-free
// parsing, no clocks); cmd_campaign.cpp runs the matrix.
//
// Spec keys (kShowConditionsSpec is the example):
//   "name"           label
//   "motions"        ["dance" (the built-in dance, retargeted once) | PATH.motion, ...]
//   "grounds"        ["floor" | "carpet", ...]
//   "perturbations"  [set name (none, show) | PATH.json, ...] (kuavo simulate --perturb)
//   "seeds"          runs per cell; "first_seed" (default 1)
//   "planner"        "mpc" | "kinematic" (default mpc)
//   "liftoff_hold"   true: kuavo simulate --liftoff-hold on (default false)
//   "plan_anchor"    true | false: kuavo simulate --plan-anchor on | off (absent: simulate's default)
//   "plan_anchor_home"  SHARE: --plan-anchor-home SHARE (absent: simulate's default)
//   "estimator_unloaded_foot_N"  N: --estimator-unloaded-foot N (absent: simulate's default, off)
//   "planner_sole_inset_m"  M: --planner-sole-inset M (absent: simulate's default, 0)
//   "recovery_fast_swing_s"  S: --recovery-fast-swing S (absent: simulate's default, off)
//   "surface_sink_m" {GROUND: M, ...}: --surface-sink M on that ground's runs, the stage
//                    surface's sink under the standing robot (absent: 0, a hard floor)
//   "lean_trim"      "off" | "opening" | "always": kuavo simulate --lean-trim MODE; true, false:
//                    "on" (always), "off" (absent: simulate's default)
//   "holdable_soles" false: kuavo simulate --holdable-soles off (default true)
//   "duration_s"     0 or absent: each motion's length plus the settling second
//   "push"           {"impulse_Ns", "duration_s", "start_after_s", "end_before_s"}: one
//                    horizontal push a run, direction uniform in [0, 2π) and start uniform
//                    in [start_after_s, run length − end_before_s], both drawn from the seed;
//                    absent: no push
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace kuavo::cli {

// The goal campaign (issue 20): carpet, the `show` set, one random 10 N·s push a run. The stage
// is set up as a show's is: the carpet's sink under the standing robot (1.5 cm,
// sim/ground_contact.h) is given to the estimator (--surface-sink).
inline constexpr const char* kShowConditionsSpec = R"({
  "name": "show conditions",
  "motions": ["dance"],
  "grounds": ["carpet"],
  "perturbations": ["show"],
  "seeds": 100,
  "first_seed": 1,
  "planner": "mpc",
  "surface_sink_m": {"carpet": 0.015},
  "push": {"impulse_Ns": 10.0, "duration_s": 0.1, "start_after_s": 1.0, "end_before_s": 1.0}
}
)";

struct PushSpec {
  bool enabled = false;
  double impulse_Ns = 0.0;
  double duration_s = 0.1;
  double start_after_s = 1.0;
  double end_before_s = 1.0;
};

struct CampaignSpec {
  std::string name;
  std::vector<std::string> motions, grounds, perturbations;
  int seeds = 0;
  std::uint64_t first_seed = 1;
  std::string planner = "mpc";
  bool liftoff_hold = false;
  std::optional<bool> plan_anchor;
  std::optional<double> plan_anchor_home;
  std::optional<double> estimator_unloaded_foot_N;
  std::optional<double> planner_sole_inset_m;
  std::optional<double> recovery_fast_swing_s;
  double carpet_sink_m = 0.0, floor_sink_m = 0.0;  // "surface_sink_m"
  std::optional<std::string> lean_trim;  // --lean-trim's value
  bool holdable_soles = true;
  double duration_s = 0.0;
  PushSpec push;
};

// false with a message for malformed JSON, unknown keys, empty lists or bad values.
bool parse_campaign_spec(const std::string& json_text, CampaignSpec& out, std::string& error);

// A motion entry's short name: "dance" stays, a path gives its file stem.
std::string motion_name(const std::string& entry);

struct PushDraw {
  double start_s = 0.0;
  double direction_rad = 0.0;
  double force_N = 0.0;  // impulse / duration, horizontal
};
// The push of run `seed` in a run of run_length_s: a pure function of its arguments.
// false when the window [start_after, length − end_before] is empty.
bool draw_push(const PushSpec& spec, std::uint64_t seed, double run_length_s, PushDraw& out);

// The show conditions' push (kShowConditionsSpec's "push") with impulse_Ns instead of its own,
// drawn for `seed` as draw_push draws it; its duration in spec_out. false when impulse_Ns is
// not positive or the window is empty. The closed-loop check of `kuavo retarget` pushes its
// model-error runs with it (--verify-show-push).
bool draw_show_push(std::uint64_t seed, double run_length_s, double impulse_Ns, PushDraw& out, PushSpec& spec_out);

// Wilson score interval for `falls` out of `runs` at 95 % (z = 1.959964): unlike the
// normal approximation it stays inside [0, 1] and is not [0, 0] at zero falls.
void wilson_interval_95(int falls, int runs, double& lo, double& hi);

}  // namespace kuavo::cli
