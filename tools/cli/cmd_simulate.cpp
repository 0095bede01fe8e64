// kuavo simulate --stand SECONDS | MOTION | --step-in-place STEPS
//                [--ground floor|carpet] [--push T:FX,FY,FZ:DURATION] [--seed N]
//                [--latency-ticks N] [--integrator cvode|rkm|euler] [--variant s45|s42] [--mass KG]
//                [--engine simbody|mujoco|both]
//                [--planner kinematic|mpc] [--state estimator|truth] [--sensors mti|ideal]
//                [--estimator-unloaded-foot N] [--surface-sink M]
//                [--horizon SECONDS] [--plan-latency-ms MS|measured] [--recovery-step on|off]
//                [--planner-sole-inset M] [--recovery-fast-swing SECONDS]
//                [--early-touchdown on|off] [--holdable-soles on|off] [--liftoff-hold on|off] [--plan-anchor on|off]
//                [--plan-anchor-home SHARE]
//                [--duration SECONDS] [--balance-filter on|off] [--perturb none|show|FILE.json [--perturb-seed N]]
//                --log run.csv --summary run.json
// --stand runs the standing controller; MOTION (a .motion file from `kuavo retarget`) and
// --step-in-place run the online stack (estimator, planner, WBC) following the motion.
// --engine: the plant -- simbody (default: our tables, our contact model) or mujoco (Leju's
// MJCF, MuJoCo's contact; sim/mujoco_plant.h); the controller and the HAL are the same.
// --integrator, --rtol and --perturb belong to the simbody plant; mujoco models the floor only.
// both: the run on each (the MuJoCo log beside --log as NAME.mujoco.csv), one summary holding
// both and the disagreements in words (sim/engine_compare.h).
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
#include <vector>

#include "controllers/motion/load_motion.h"
#include "sim/closed_loop.h"
#include "sim/engine_compare.h"
#include "sim/motion_loop.h"
#include "sim/mujoco_plant.h"
#include "sim/push_option.h"
#include "tools/cli/args.h"
#include "tools/cli/commands.h"
#include "tools/cli/usage.h"
#include "tools/cli/motion_input.h"
#include "tools/cli/perturb_option.h"
#include "tools/cli/progress.h"

namespace kuavo::cli {
namespace {

using sim::kMaxRunDuration_s;  // the bound on --stand and --duration

// The three kinds of run; an option outside the kinds it applies to is refused.
constexpr args::ModeMask kStandRun = 1, kMotionRun = 2, kStepRun = 4;

}  // namespace

int run_simulate(int argc, char** argv) {
  sim::MotionRunConfig motion_cfg;
  motion_cfg.stack.planner = stack::PlannerKind::kMpc;
  sim::RunConfig& cfg = motion_cfg.run;
  std::vector<std::string> positionals;
  long long steps = 0, latency_ticks = cfg.command_latency_ticks;
  model::Variant variant = model::Variant::kS45;
  double mass_kg = model::kDefaultTotalMass_kg;
  std::string summary_path, balance = "off", recovery = "on", early_touchdown = "on", holdable = "on", liftoff_hold = "off", lean_trim = "off", anchor = "on", planner = "mpc", state = "estimator", sensors = "mti", ground = "floor";
  std::string integrator = "cvode", variant_name = "s45", perturb, engine = "simbody";
  sim::PerturbationSet perturb_set;  // model mismatch of the plant: none unless --perturb
  std::uint64_t perturb_seed = 0;
  bool quiet = false;  // no progress line on a terminal
  args::Parser p("kuavo simulate");
  p.positionals("MOTION", &positionals, 1);
  p.flag("--quiet", &quiet);
  p.number("--stand", "SECONDS", 0.0, kMaxRunDuration_s, "s", &cfg.duration_s, /*lo_open=*/true).modes = kStandRun;
  p.integer("--step-in-place", "STEPS", 1, 200, "steps", &steps).modes = kStepRun;
  p.number("--duration", "SECONDS", 0.0, kMaxRunDuration_s, "s", &cfg.duration_s, true).modes = kMotionRun | kStepRun;
  p.choice("--balance-filter", {"on", "off"}, &balance).modes = kMotionRun | kStepRun;
  p.choice("--planner", {"kinematic", "mpc"}, &planner).modes = kMotionRun | kStepRun;
  p.choice("--state", {"estimator", "truth"}, &state).modes = kMotionRun | kStepRun;
  // The MPC planner's recovery step (controllers/planner/recovery_step.h); off: the stack before it.
  p.choice("--recovery-step", {"on", "off"}, &recovery).modes = kMotionRun | kStepRun;
  // Its early touchdown: a swing that cannot catch the capture point lands sooner (same file).
  p.choice("--early-touchdown", {"on", "off"}, &early_touchdown).modes = kMotionRun | kStepRun;
  // Its trigger on the part of the soles the ankles hold (same file), opt-in; off: the soles.
  p.choice("--holdable-soles", {"on", "off"}, &holdable).modes = kMotionRun | kStepRun;
  // The MPC planner's lift-off hold (controllers/planner/liftoff_hold.h), opt-in; off: lift-offs on the motion's clock.
  p.choice("--liftoff-hold", {"on", "off"}, &liftoff_hold).modes = kMotionRun | kStepRun;
  // The MPC planner's plan anchor (controllers/planner/plan_anchor.h), on by default; off: the
  // motion's world footholds.
  p.choice("--plan-anchor", {"on", "off"}, &anchor).modes = kMotionRun | kStepRun;
  // Its homing: the share of the measured error it leaves for the MPC to pull back (plan_anchor.h, home_share).
  p.number("--plan-anchor-home", "SHARE", 0.0, 0.5, "", &motion_cfg.stack.anchor.home_share).modes = kMotionRun | kStepRun;
  // The online MPC's window: mpc_validate_config's range with plan output (checked again there).
  p.number("--horizon", "SECONDS", 0.6, 1.4, "s", &motion_cfg.stack.mpc.horizon_s).modes = kMotionRun | kStepRun;
  p.choice("--sensors", {"mti", "ideal"}, &sensors).modes = kMotionRun | kStepRun;
  // Opt-in: a foot the WBC loads with less than N newtons leaves the estimator's stance set
  // (controllers/stack/online_stack.h, estimator_unloaded_foot_N); 0 (default): off.
  p.number("--estimator-unloaded-foot", "N", 0.0, 1000.0, "N", &motion_cfg.stack.estimator_unloaded_foot_N).modes =
      kMotionRun | kStepRun;
  // The stage surface's sink under the standing robot, measured at set-up (0, the default: a
  // hard floor): the estimator puts loaded soles that deep (EstimatorConfig::stance_sink_m).
  p.number("--surface-sink", "M", 0.0, estimator::kMaxStanceSink_m, "m", &motion_cfg.stack.estimator.stance_sink_m)
      .modes = kMotionRun | kStepRun;
  // Opt-in: the MPC planner plans on soles this much narrower (online_stack.h,
  // planner_sole_inset_m); 0 (default): the whole soles.
  p.number("--planner-sole-inset", "M", 0.0, 0.04, "m", &motion_cfg.stack.planner_sole_inset_m).modes =
      kMotionRun | kStepRun;
  // Opt-in: a recovery step no 0.40 s swing captures is planned again with this shorter swing
  // (planner/recovery_step.h, fast_swing_s); absent: off.
  p.number("--recovery-fast-swing", "SECONDS", 0.2, 0.4, "s", &motion_cfg.stack.recovery.fast_swing_s).modes =
      kMotionRun | kStepRun;
  // The estimate's base tilt trimmed until the WBC's horizontal forces are the ones the CoM
  // obeys (controllers/stack/lean_trim.h): learned in the motion's opening stand and held
  // (opening), or in every quasi-static phase (always; on: its older name); off: the
  // estimator's tilt.
  p.choice("--lean-trim", {"off", "opening", "always", "on"}, &lean_trim).modes = kMotionRun | kStepRun;
  p.custom("--plan-latency-ms", "MS in 0..100 ms or measured", [&](const char* v) {
     double ms = 0.0;
     if (!std::strcmp(v, "measured")) return motion_cfg.measured_plan_latency = true;
     if (!parse_number(v, 0.0, 100.0, ms)) return false;
     motion_cfg.plan_latency_s = ms * 1e-3;
     return true;
   }).modes = kMotionRun | kStepRun;
  p.choice("--ground", {"floor", "carpet"}, &ground);
  p.custom("--push", sim::kPushValueName, [&](const char* v) { return sim::parse_push(v, cfg.push); });
  p.uint64("--seed", "N", &cfg.seed);
  p.integer("--latency-ticks", "TICKS", 0, 50, "ticks of 2 ms", &latency_ticks);
  p.choice("--integrator", {"euler", "cvode", "rkm"}, &integrator);
  p.number("--rtol", "TOLERANCE", 1e-12, 1e-1, "", &cfg.relative_tolerance);
  p.choice("--variant", {"s45", "s42"}, &variant_name);
  p.choice("--engine", {"simbody", "mujoco", "both"}, &engine);
  // The 55 kg robot scaled: build_model refuses a mass its torso cannot carry; this bounds the token.
  p.number("--mass", "KG", 1.0, 1000.0, "kg", &mass_kg);
  p.text("--perturb", "none|show|FILE.json", &perturb).modes = kMotionRun | kStepRun;
  p.uint64("--perturb-seed", "N", &perturb_seed).modes = kMotionRun | kStepRun;
  p.output_file("--log", "CSV", &cfg.log_path);
  p.output_file("--summary", "JSON", &summary_path);
  auto refuse = [&] {
    std::fprintf(stderr, "%s\n", p.error().c_str());
    return usage_error("simulate");
  };
  if (const int code = parse_command_line(p, argc, argv, "simulate"); code >= 0) return code;
  const bool stand = p.given("--stand");
  const std::string motion_path = positionals.empty() ? "" : positionals[0];
  const int modes = (stand ? 1 : 0) + (motion_path.empty() ? 0 : 1) + (steps > 0 ? 1 : 0);
  if (modes != 1) {
    std::fprintf(stderr, "kuavo simulate: give exactly one of --stand SECONDS, a MOTION file or --step-in-place STEPS\n");
    return usage_error("simulate");
  }
  if (!p.refuse_inapplicable(stand ? kStandRun : steps > 0 ? kStepRun : kMotionRun,
                             stand ? "a --stand run" : steps > 0 ? "a --step-in-place run" : "a MOTION run")) {
    return refuse();
  }
  if (!motion_path.empty()) {
    std::string path_error;
    if (!check_input_file(motion_path, path_error)) {
      std::fprintf(stderr, "kuavo simulate: %s\n", path_error.c_str());
      return 2;
    }
  }
  if (!perturb.empty()) {
    std::string error;
    if (!load_perturbation_set(perturb.c_str(), perturb_set, error)) {
      std::fprintf(stderr, "kuavo simulate: %s\n", error.c_str());
      return 2;
    }
  }
  // The parser allowed only these names.
  const bool balance_filter = balance == "on";
  motion_cfg.use_truth_state = state == "truth";
  motion_cfg.stack.recovery.enabled = recovery == "on";
  motion_cfg.stack.recovery.early_touchdown = early_touchdown == "on";
  planner::set_holdable_soles(motion_cfg.stack.recovery, holdable == "on");
  motion_cfg.stack.liftoff_hold.enabled = liftoff_hold == "on";
  motion_cfg.stack.lean_trim.enabled = lean_trim != "off";
  motion_cfg.stack.lean_trim.learn = lean_trim == "opening" ? stack::LeanTrimLearn::kOpening : stack::LeanTrimLearn::kAlways;
  motion_cfg.stack.anchor.enabled = anchor == "on";
  motion_cfg.ideal_sensors = sensors == "ideal";
  cfg.command_latency_ticks = static_cast<int>(latency_ticks);
  if (!stack::parse_planner(planner.c_str(), motion_cfg.stack.planner) || !sim::parse_ground(ground.c_str(), cfg.ground) ||
      !sim::parse_integrator(integrator.c_str(), cfg.integrator) || !model::parse_variant(variant_name.c_str(), variant) ||
      !(engine == "both" || sim::parse_engine(engine.c_str(), cfg.engine))) {
    return usage_error("simulate");
  }
  const bool both_engines = engine == "both";
  if (cfg.engine == sim::Engine::kMujoco || both_engines) {
    for (const char* simbody_only : {"--integrator", "--rtol", "--perturb", "--perturb-seed"}) {
      if (p.given(simbody_only)) {
        std::fprintf(stderr, "kuavo simulate: %s applies to the simbody engine, not --engine %s\n", simbody_only, engine.c_str());
        return 2;
      }
    }
    if (const char* why = sim::mujoco_ground_refusal(cfg.ground)) {
      std::fprintf(stderr, "kuavo simulate: %s\n", why);
      return 2;
    }
  }
  const bool duration_given = p.given("--duration");
  const bool perturb_seed_given = p.given("--perturb-seed");
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
  std::unique_ptr<planner::MotionPlan> plan;
  if (!stand) {
    plan = std::make_unique<planner::MotionPlan>();
    std::string error;
    planner::BalanceFilterReport filter_report;
    // A motion file through the firmware's own loader (the same checks, standing start and
    // filter); the step-in-place gait is made here and filtered on request.
    const bool loaded = steps > 0 ? make_step_plan(*robot, static_cast<int>(steps), *plan, error) &&
                                        (!balance_filter || filter_motion_plan(*robot, *plan, filter_report, error))
                                  : motion::load_motion(motion_path, *robot, {.balance_filter = balance_filter}, *plan,
                                                        filter_report, error);
    if (!loaded) {
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
  }
  // One run on one engine; its summary and JSON (a --stand run's summary is MotionSummary::run).
  auto run_on = [&](sim::Engine e, const std::string& log_path, sim::MotionSummary& ms) {
    sim::MotionRunConfig c = motion_cfg;
    c.run.engine = e;
    c.run.log_path = log_path;
    if (stand) {
      ms.run = sim::run_standing(*robot, c.run);
      return sim::summary_json(ms.run);
    }
    // On a terminal: the share of the run simulated and the time left (stderr; never piped).
    Progress progress(quiet);
    progress.set_total(c.run.duration_s > 0.0 ? c.run.duration_s : planner::motion_plan_duration_s(*plan) + c.settle_s);
    if (progress.shown()) {
      c.on_progress = [&](double t_s) {
        progress.update(t_s, std::string(sim::to_string(e)) + ": simulated " + std::to_string(static_cast<int>(t_s)) + " s");
      };
    }
    ms = sim::run_motion(*robot, *plan, c);
    progress.clear();
    return sim::motion_summary_json(ms);
  };
  sim::RunSummary s;
  std::string json;
  if (!both_engines) {
    sim::MotionSummary ms;
    json = run_on(cfg.engine, cfg.log_path, ms);
    s = ms.run;
  } else {
    // The MuJoCo run's log goes beside the Simbody one: run.csv -> run.mujoco.csv.
    std::string mujoco_log = cfg.log_path;
    if (!mujoco_log.empty()) {
      const std::size_t dot = mujoco_log.rfind('.'), slash = mujoco_log.rfind('/');
      const std::size_t at = dot != std::string::npos && (slash == std::string::npos || dot > slash) ? dot : mujoco_log.size();
      mujoco_log.insert(at, ".mujoco");
    }
    sim::MotionSummary on_simbody, on_mujoco;
    const std::string simbody_json = run_on(sim::Engine::kSimbody, cfg.log_path, on_simbody);
    const std::string mujoco_json = run_on(sim::Engine::kMujoco, mujoco_log, on_mujoco);
    const sim::EngineComparison cmp = sim::compare_engines(on_simbody, on_mujoco);
    json = sim::engine_comparison_json(cmp, simbody_json, mujoco_json);
    s = on_simbody.run.ok ? on_mujoco.run : on_simbody.run;  // exit 1 when either run failed
    for (const std::string& d : cmp.disagreements) std::fprintf(stderr, "kuavo simulate: the engines disagree: %s\n", d.c_str());
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
