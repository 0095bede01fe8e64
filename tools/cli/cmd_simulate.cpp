// kuavo simulate --stand SECONDS | MOTION | --step-in-place STEPS
//                [--ground floor|carpet] [--push T:FX,FY,FZ:DURATION] [--seed N]
//                [--latency-ticks N] [--integrator cvode|rkm|euler] [--variant s45|s42] [--mass KG]
//                [--planner kinematic|mpc] [--state estimator|truth] [--sensors mti|ideal]
//                [--horizon SECONDS] [--plan-latency-ms MS|measured]
//                [--duration SECONDS] [--balance-filter on|off] [--perturb none|show|FILE.json [--perturb-seed N]]
//                --log run.csv --summary run.json
// --stand runs the standing controller; MOTION (a .motion file from `kuavo retarget`) and
// --step-in-place run the online stack (estimator, planner, WBC) following the motion.
// Defaults: the MPC planner, no balance filter (the motions of `kuavo retarget`'s dynamic
// stage are dynamically feasible; the filter, a cart-table ZMP preview, is kept for
// geometric-stage motions and the kinematic planner: --balance-filter on).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <string>

#include "sim/closed_loop.h"
#include "sim/motion_loop.h"
#include "tools/cli/args.h"
#include "tools/cli/commands.h"
#include "tools/cli/motion_input.h"
#include "tools/cli/perturb_option.h"
#include "tools/cli/progress.h"
#include "tools/mocap/motion_plan_io.h"

namespace kuavo::cli {
namespace {

// Longest simulated run: the longest motion the controller holds is 120 s
// (planner::kMaxMotionFrames at 100 Hz) plus settling; 600 s bounds the run's per-tick
// statistics (~300 k WBC ticks, a few MB) and its log, decided before anything runs.
constexpr double kMaxRunDuration_s = 600.0;

bool parse_double(const char* text, double& out) {
  return parse_number(text, -std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), out);
}

// The options that take a value (a missing value is named, not a generic usage).
constexpr const char* kValueOptions[] = {"--stand", "--step-in-place", "--duration", "--balance-filter", "--planner",
                                         "--state", "--horizon", "--sensors", "--plan-latency-ms", "--ground",
                                         "--push", "--seed", "--latency-ticks", "--integrator", "--rtol",
                                         "--variant", "--mass", "--perturb", "--perturb-seed", "--log", "--summary"};
// Those that only a MOTION or --step-in-place run reads (refused with --stand, not ignored).
constexpr const char* kMotionOnlyOptions[] = {"--duration", "--balance-filter", "--planner", "--state", "--horizon",
                                              "--sensors", "--plan-latency-ms", "--perturb", "--perturb-seed"};

bool is_one_of(const char* a, const auto& names) {
  for (const char* n : names)
    if (!std::strcmp(a, n)) return true;
  return false;
}

// "T:FX,FY,FZ:DURATION", e.g. 5:100,0,0:0.1 is a 10 N·s forward push at t = 5 s.
bool parse_push(const char* text, sim::Push& push) {
  double t, fx, fy, fz, d;
  char tail;
  if (std::sscanf(text, "%lf:%lf,%lf,%lf:%lf%c", &t, &fx, &fy, &fz, &d, &tail) != 5) return false;
  if (!(t >= 0.0) || !(d > 0.0) || !std::isfinite(fx + fy + fz)) return false;
  push.start_s = t;
  push.duration_s = d;
  push.force_N = sim::Vec3(fx, fy, fz);
  return true;
}

int usage() {
  std::fprintf(stderr,
               "usage: kuavo simulate --stand SECONDS | MOTION | --step-in-place STEPS\n"
               "                      [--ground floor|carpet] [--push T:FX,FY,FZ:DURATION]\n"
               "                      [--seed N] [--latency-ticks N] [--integrator euler|cvode|rkm]\n"
               "                      [--variant s45|s42] [--mass KG]\n"
               "                      [--planner kinematic|mpc] [--state estimator|truth] [--sensors mti|ideal]\n"
               "                      [--horizon SECONDS] [--plan-latency-ms MS|measured] [--duration SECONDS]\n"
               "                      [--balance-filter on|off] [--perturb none|show|FILE.json [--perturb-seed N]]\n"
               "                      --log run.csv --summary run.json\n");
  return 2;
}

}  // namespace

int run_simulate(int argc, char** argv) {
  sim::MotionRunConfig motion_cfg;
  motion_cfg.stack.planner = stack::PlannerKind::kMpc;
  sim::RunConfig& cfg = motion_cfg.run;
  std::string motion_path;
  int steps = -1;
  bool duration_given = false;
  bool balance_filter = false;
  model::Variant variant = model::Variant::kS45;
  double mass_kg = model::kDefaultTotalMass_kg;
  std::string summary_path;
  bool stand = false;
  sim::PerturbationSet perturb_set;  // model mismatch of the plant: none unless --perturb
  std::uint64_t perturb_seed = 0;
  bool perturb_seed_given = false;
  const char* motion_only = nullptr;  // the first motion-only option given
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    auto bad = [&](const char* what) {
      std::fprintf(stderr, "kuavo simulate: %s '%s'\n", what, v ? v : "");
      return 2;
    };
    if (is_one_of(a, kValueOptions) && v == nullptr) {
      std::fprintf(stderr, "kuavo simulate: option '%s' needs a value\n", a);
      return usage();
    }
    if (is_one_of(a, kMotionOnlyOptions) && motion_only == nullptr) motion_only = a;
    if (!std::strcmp(a, "--stand") && v) {
      if (!parse_double(v, cfg.duration_s) || cfg.duration_s <= 0.0 || cfg.duration_s > kMaxRunDuration_s)
        return bad(("--stand needs seconds in (0, " + std::to_string(static_cast<int>(kMaxRunDuration_s)) + "], got").c_str());
      stand = true;
    } else if (!std::strcmp(a, "--step-in-place") && v) {
      long long n = 0;
      if (!parse_integer(v, 1, 200, n)) return bad("--step-in-place needs 1..200 steps, got");
      steps = static_cast<int>(n);
    } else if (!std::strcmp(a, "--duration") && v) {
      if (!parse_double(v, cfg.duration_s) || cfg.duration_s <= 0.0 || cfg.duration_s > kMaxRunDuration_s)
        return bad(("--duration needs seconds in (0, " + std::to_string(static_cast<int>(kMaxRunDuration_s)) + "], got").c_str());
      duration_given = true;
    } else if (!std::strcmp(a, "--balance-filter") && v) {
      if (std::strcmp(v, "on") != 0 && std::strcmp(v, "off") != 0) return bad("--balance-filter must be on or off, got");
      balance_filter = std::strcmp(v, "on") == 0;
    } else if (!std::strcmp(a, "--planner") && v) {
      if (!stack::parse_planner(v, motion_cfg.stack.planner)) return bad("--planner must be kinematic or mpc, got");
    } else if (!std::strcmp(a, "--state") && v) {
      if (std::strcmp(v, "estimator") != 0 && std::strcmp(v, "truth") != 0) return bad("--state must be estimator or truth, got");
      motion_cfg.use_truth_state = std::strcmp(v, "truth") == 0;
    } else if (!std::strcmp(a, "--horizon") && v) {
      if (!parse_double(v, motion_cfg.stack.mpc.horizon_s)) return bad("--horizon needs seconds, got");
    } else if (!std::strcmp(a, "--sensors") && v) {
      if (std::strcmp(v, "ideal") != 0 && std::strcmp(v, "mti") != 0) return bad("--sensors must be mti or ideal, got");
      motion_cfg.ideal_sensors = std::strcmp(v, "ideal") == 0;
    } else if (!std::strcmp(a, "--plan-latency-ms") && v) {
      double ms = 0.0;
      if (!std::strcmp(v, "measured")) {
        motion_cfg.measured_plan_latency = true;
      } else if (!parse_double(v, ms) || ms < 0.0 || ms > 100.0) {
        return bad("--plan-latency-ms must be 0..100 or measured, got");
      } else {
        motion_cfg.plan_latency_s = ms * 1e-3;
      }
    } else if (!std::strcmp(a, "--ground") && v) {
      if (!sim::parse_ground(v, cfg.ground)) return bad("--ground must be floor or carpet, got");
    } else if (!std::strcmp(a, "--push") && v) {
      if (!parse_push(v, cfg.push)) return bad("--push must be T:FX,FY,FZ:DURATION (s, N, s), got");
    } else if (!std::strcmp(a, "--seed") && v) {
      if (!parse_uint64(v, cfg.seed)) return bad("--seed needs an integer in 0..2^64-1, got");
    } else if (!std::strcmp(a, "--latency-ticks") && v) {
      long long n = 0;
      if (!parse_integer(v, 0, 50, n)) return bad("--latency-ticks must be 0..50, got");
      cfg.command_latency_ticks = static_cast<int>(n);
    } else if (!std::strcmp(a, "--integrator") && v) {
      if (!sim::parse_integrator(v, cfg.integrator)) return bad("--integrator must be euler, cvode or rkm, got");
    } else if (!std::strcmp(a, "--rtol") && v) {
      if (!parse_double(v, cfg.relative_tolerance) || !(cfg.relative_tolerance > 0.0)) return bad("--rtol needs a positive number, got");
    } else if (!std::strcmp(a, "--variant") && v) {
      if (!model::parse_variant(v, variant)) return bad("--variant must be s45 or s42, got");
    } else if (!std::strcmp(a, "--mass") && v) {
      if (!parse_double(v, mass_kg)) return bad("--mass needs kg, got");
    } else if (!std::strcmp(a, "--perturb") && v) {
      std::string error;
      if (!load_perturbation_set(v, perturb_set, error)) return bad(error.c_str());
    } else if (!std::strcmp(a, "--perturb-seed") && v) {
      if (!parse_uint64(v, perturb_seed)) return bad("--perturb-seed needs an integer in 0..2^64-1, got");
      perturb_seed_given = true;
    } else if (!std::strcmp(a, "--log") && v) {
      cfg.log_path = v;
    } else if (!std::strcmp(a, "--summary") && v) {
      summary_path = v;
    } else if (a[0] != '-' && motion_path.empty()) {
      motion_path = a;
      continue;  // a positional argument takes no value
    } else {
      return usage();
    }
    ++i;
  }
  const int modes = (stand ? 1 : 0) + (motion_path.empty() ? 0 : 1) + (steps > 0 ? 1 : 0);
  if (modes != 1) {
    std::fprintf(stderr, "kuavo simulate: give exactly one of --stand SECONDS, a MOTION file or --step-in-place STEPS\n");
    return usage();
  }
  if (stand && motion_only != nullptr) {
    std::fprintf(stderr, "kuavo simulate: %s applies to MOTION and --step-in-place runs, not --stand\n", motion_only);
    return 2;
  }
  // Inputs and outputs checked before the run, not after it.
  std::string path_error;
  if ((!motion_path.empty() && !check_input_file(motion_path, path_error)) ||
      (!cfg.log_path.empty() && !check_output_file(cfg.log_path, path_error)) ||
      (!summary_path.empty() && !check_output_file(summary_path, path_error))) {
    std::fprintf(stderr, "kuavo simulate: %s\n", path_error.c_str());
    return 2;
  }
  if (!stand && !duration_given) cfg.duration_s = 0.0;  // the motion's length plus settling
  auto robot = std::make_unique<model::Model>();
  if (const auto err = model::build_model(variant, mass_kg, *robot); err != model::ModelError::kOk) {
    std::fprintf(stderr, "kuavo simulate: %s\n", model::to_string(err));
    return 2;
  }
  // The perturbation's own seed defaults to the run's --seed.
  motion_cfg.perturbation = sim::draw_perturbation(*robot, perturb_set, perturb_seed_given ? perturb_seed : cfg.seed);
  if (stand && motion_cfg.perturbation.active) {
    std::fprintf(stderr, "kuavo simulate: --perturb applies to MOTION and --step-in-place runs, not --stand\n");
    return 2;
  }
  sim::RunSummary s;
  std::string json;
  if (stand) {
    s = sim::run_standing(*robot, cfg);
    json = sim::summary_json(s);
  } else {
    auto plan = std::make_unique<planner::MotionPlan>();
    std::string error;
    const bool loaded = steps > 0 ? make_step_plan(*robot, steps, *plan, error)
                                  : mocap::load_motion_plan(motion_path, *robot, *plan, error);
    if (!loaded) {
      std::fprintf(stderr, "kuavo simulate: %s\n", error.c_str());
      return 2;
    }
    planner::BalanceFilterReport filter_report;
    if (balance_filter && !filter_motion_plan(*robot, *plan, filter_report, error)) {
      std::fprintf(stderr, "kuavo simulate: %s\n", error.c_str());
      return 2;
    }
    if (balance_filter) {
      std::fprintf(stderr, "balance filter: CoM corrected by up to %.3f m; cart-table ZMP outside the support up to %.3f m before, %.3f m after; %d frames in flight\n",
                   filter_report.max_correction_m, filter_report.zmp_outside_before_m, filter_report.zmp_outside_after_m,
                   filter_report.frames_in_flight);
    }
    if (const char* why = stack::stack_validate_config(motion_cfg.stack)) {
      std::fprintf(stderr, "kuavo simulate: %s\n", why);
      return 2;
    }
    // On a terminal: the share of the run simulated and the time left (stderr; never piped).
    Progress progress(false);
    progress.set_total(motion_cfg.run.duration_s > 0.0 ? motion_cfg.run.duration_s
                                                       : planner::motion_plan_duration_s(*plan) + motion_cfg.settle_s);
    if (progress.shown()) {
      motion_cfg.on_progress = [&](double t_s) { progress.update(t_s, "simulated " + std::to_string(static_cast<int>(t_s)) + " s"); };
    }
    const sim::MotionSummary ms = sim::run_motion(*robot, *plan, motion_cfg);
    progress.clear();
    s = ms.run;
    json = sim::motion_summary_json(ms);
  }
  if (!summary_path.empty()) {
    std::ofstream out(summary_path);
    out << json;
    if (!out) {
      std::fprintf(stderr, "kuavo simulate: cannot write %s\n", summary_path.c_str());
      return 1;
    }
  }
  std::fputs(json.c_str(), stdout);
  if (!s.ok) {
    std::fprintf(stderr, "kuavo simulate: %s\n", s.error.c_str());
    return 1;
  }
  return 0;
}

}  // namespace kuavo::cli
