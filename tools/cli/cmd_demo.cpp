// kuavo demo [IN.bvh] [--out DIR] [--planner mpc|kinematic] [--quiet]: the main job. A BVH
// dance (the built-in one without IN.bvh) through the whole pipeline into the simulator, with a
// report folder whose entry point is index.html (html_report.h; REPORT.md has the same tables):
//   1. the human dance (BVH; the built-in one is generated) -> geometric retargeting -> contact
//      schedule -> feasibility repair -> dynamic retargeting -> dance.motion (+ CSV,
//      retarget_report.json, fig4_knee.svg, fig5_dynamics.svg); with --planner kinematic the
//      geometric stage only, then the balance filter;
//   2. the online stack (estimator, centroidal RTI-MPC at 50 Hz,
//      WBC at 500 Hz) dancing it on the Simbody plant: floor, and carpet with the MPC
//      horizon at 1.2 s and at 0.6 s — the paper's horizon experiment, with the knee
//      trajectories and foot placements of both (dance_*.csv/json/svg, horizon_*.svg);
//   3. 20 steps in place on the floor (steps_floor.*);
//   4. standing 10 s on floor and carpet with a 10 N·s push (stand_*.csv/json);
//   5. REPORT.md: a table of every run's figures and links to the plots; index.html: the 3D
//      replay of every run with the human skeleton, plots, timeline (repairs, pushes, falls)
//      and the same tables.
// The carpet runs' push comes at 15 s in the built-in dance, mid-dance in another.

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "controllers/motion/load_motion.h"
#include "rtos_shim/clock.h"
#include "rtos_shim/args.h"
#include "sim/motion_loop.h"
#include "tools/cli/args.h"
#include "tools/cli/commands.h"
#include "tools/cli/html_report.h"
#include "tools/cli/progress.h"
#include "tools/cli/subcommand.h"
#include "tools/cli/usage.h"
#include "tools/cli/motion_input.h"
#include "tools/cli/motion_report.h"
#include "tools/report/svg_plot.h"

namespace kuavo::cli {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return s;
}

struct Case {
  std::string name, description;
  sim::MotionSummary summary;
  sim::MotionTrace trace;
};

std::string fell_text(const sim::RunSummary& r) {
  if (!r.ok) return "sim error";
  return r.fell ? "fell at " + std::to_string(r.fell_at_s).substr(0, 5) + " s" : "no";
}

// One row of the closed-loop table (REPORT.md and index.html show the same cells).
std::vector<std::string> cells(const Case& c) {
  const sim::MotionSummary& s = c.summary;
  auto f = [](const char* format, auto... v) {
    char buf[128];
    std::snprintf(buf, sizeof buf, format, v...);
    return std::string(buf);
  };
  return {c.name,
          c.description,
          s.run.fell ? "**" + fell_text(s.run) + "**" : fell_text(s.run),
          f("%.1f / %.1f", s.run.sim_time_s, s.motion_duration_s),
          f("%.3f / %.3f", s.tracking_rms_legs_rad, s.tracking_rms_arms_rad),
          f("%.3f", s.com_err_m_max),
          f("%.3f (%.2f s at edge)", s.zmp_margin_m_min, s.zmp_at_edge_s),
          f("%.3f", s.estimator_velocity_rms_m_s),
          f("%.0f / %.0f / %.0f", s.wbc_us.p50, s.wbc_us.p99, s.wbc_us.max),
          f("%.2f / %.2f", s.mpc_ms.p50, s.mpc_ms.p99),
          f("%llu", static_cast<unsigned long long>(s.deadline_misses))};
}

// The progress line counts wall seconds: those spent are measured, those to come estimated
// from the cost (wall seconds per simulated second) of the motion runs so far. Before the
// first run, these guesses (the development VM, Release build; MPC planner):
constexpr double kMotionRunCost = 0.33;  // a dance or stepping run on the online stack
constexpr double kStandRunCost = 0.12;   // the standing controller
constexpr double kReportCost_s = 2.0;    // SVG plots and the HTML report's data

}  // namespace

int run_demo(int argc, char** argv) {
  std::string out = "demo_report", planner_name = "mpc", input;
  std::vector<std::string> inputs;
  stack::PlannerKind planner_kind = stack::PlannerKind::kMpc;
  bool quiet = false;
  args::Parser p("kuavo demo");
  p.positionals("IN.bvh", &inputs, 1);
  p.text("--out", "DIR", &out);
  p.choice("--planner", {"mpc", "kinematic"}, &planner_name);
  p.flag("--quiet", &quiet);
  if (const int code = parse_command_line(p, argc, argv, "demo"); code >= 0) return code;
  stack::parse_planner(planner_name.c_str(), planner_kind);  // one of the two names
  if (!inputs.empty()) input = inputs.front();
  std::string error;
  if (!input.empty() && !check_input_file(input, error)) {
    std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
    return 2;
  }
  // The report folder: created (or already one) before the long run.
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (!std::filesystem::is_directory(out, ec)) {
    std::fprintf(stderr, "kuavo demo: --out %s: cannot create the directory\n", out.c_str());
    return 2;
  }
  Progress progress(quiet);
  progress.set_total(1.0);
  const rtos::TimeNs start_ns = rtos::now_ns();
  const auto wall_s = [&] { return 1e-9 * static_cast<double>(rtos::now_ns() - start_ns); };
  auto stage = [&](const char* text) {
    progress.clear();
    if (!quiet) std::printf("%s\n", text);
    std::fflush(stdout);
  };
  const std::string dance_name = input.empty() ? "built-in dance" : std::filesystem::path(input).filename().string();
  stage(("== 1/5 retargeting " + dance_name).c_str());
  progress.update(0.0, "retargeting " + dance_name);
  const bool kinematic = planner_kind == stack::PlannerKind::kKinematic;
  std::vector<std::string> retarget_args = {"retarget", "-o", out + "/dance.motion", "--csv", out + "/dance.csv",
                                            "--report", out + "/retarget_report.json", "--human-csv", out + "/human.csv"};
  if (input.empty()) {
    retarget_args.insert(retarget_args.end(), {"--dance-bvh", out + "/dance.bvh"});
  } else {
    retarget_args.insert(retarget_args.begin() + 1, input);
  }
  if (kinematic) retarget_args.insert(retarget_args.end(), {"--stage", "geometric"});
  {
    MuteStdout mute(quiet || progress.shown());
    if (const int rc = call_command(run_retarget, retarget_args); rc != 0) return rc;
  }
  auto robot = std::make_unique<model::Model>();
  if (model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, *robot) != model::ModelError::kOk) return 1;
  auto dance = std::make_unique<planner::MotionPlan>();
  auto steps = std::make_unique<planner::MotionPlan>();
  planner::BalanceFilterReport filter;
  if (!motion::load_motion(out + "/dance.motion", *robot, {.balance_filter = kinematic}, *dance, filter, error) ||
      !make_step_plan(*robot, 20, *steps, error)) {
    std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
    return 1;
  }
  // Simulated seconds still to run (motion runs settle 1 s after the motion), and their cost.
  const double dance_s = planner::motion_plan_duration_s(*dance);
  const double steps_s = planner::motion_plan_duration_s(*steps);
  double motion_left_s = 3.0 * (dance_s + 1.0) + steps_s + 1.0;
  double run_cost = kMotionRunCost;
  const auto estimate_total = [&] {
    progress.set_total(wall_s() + run_cost * motion_left_s + kStandRunCost * 20.0 + kReportCost_s);
  };
  estimate_total();
  double work_done = wall_s();

  std::vector<Case> cases;
  auto run_case = [&](const std::string& name, const std::string& description, const planner::MotionPlan& plan,
                      sim::MotionRunConfig cfg) {
    progress.clear();
    if (!quiet) std::printf("   %s: %s\n", name.c_str(), description.c_str());
    std::fflush(stdout);
    cfg.stack.planner = planner_kind;
    cfg.run.log_path = out + "/" + name + ".csv";
    const double before = work_done;
    cfg.on_progress = [&](double t_s) {
      progress.update(before + run_cost * t_s, name + ": simulating " + std::to_string(static_cast<int>(t_s)) + " s");
    };
    Case c{name, description, {}, {}};
    c.summary = sim::run_motion(*robot, plan, cfg, &c.trace);
    // A run that falls stops early: what it did not simulate is work not to come.
    motion_left_s -= planner::motion_plan_duration_s(plan) + cfg.settle_s;
    if (c.summary.run.sim_time_s > 0.0) run_cost = (wall_s() - before) / c.summary.run.sim_time_s;
    estimate_total();
    work_done = wall_s();
    std::ofstream(out + "/" + name + ".json") << sim::motion_summary_json(c.summary);
    if (!write_motion_plots(*robot, c.trace, out + "/" + name, name, error)) std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
    cases.push_back(std::move(c));
  };
  stage((std::string("== 2/5 the dance in the simulator (") + stack::to_string(planner_kind) + " planner)").c_str());
  sim::MotionRunConfig floor_cfg;
  run_case("dance_floor", dance_name + ", floor, estimator", *dance, floor_cfg);
  // The disturbance: 10 N·s sideways on the torso, at 15 s in the built-in dance (as the
  // paper's experiment), mid-dance in another one.
  const double push_at_s = input.empty() ? 15.0 : std::round(0.5 * dance_s);
  char push_text[96];
  std::snprintf(push_text, sizeof push_text, "carpet, 10 N·s push at %.0f s, estimator", push_at_s);
  sim::MotionRunConfig carpet_cfg;
  carpet_cfg.run.ground = sim::kCarpet;
  carpet_cfg.run.push.start_s = push_at_s;
  carpet_cfg.run.push.duration_s = 0.1;
  carpet_cfg.run.push.force_N = sim::Vec3(0.0, 100.0, 0.0);
  carpet_cfg.stack.mpc.horizon_s = 1.2;
  run_case("dance_carpet", dance_name + ", " + push_text + ", MPC horizon 1.2 s", *dance, carpet_cfg);
  carpet_cfg.stack.mpc.horizon_s = 0.6;
  run_case("dance_carpet_h06", dance_name + ", " + push_text + ", MPC horizon 0.6 s", *dance, carpet_cfg);
  stage("== 3/5 stepping in place");
  run_case("steps_floor", "20 steps in place, floor, estimator", *steps, sim::MotionRunConfig{});

  stage("== 4/5 standing in the simulator (floor, carpet; 10 N·s push at 5 s)");
  for (const char* ground : {"floor", "carpet"}) {
    progress.update(work_done, std::string("standing on ") + ground);
    const std::string base = out + "/stand_" + ground;
    MuteStdout mute(quiet || progress.shown());
    if (const int rc = call_command(run_simulate, {"simulate", "--stand", "10", "--ground", ground, "--push", "5:100,0,0:0.1",
                                           "--log", base + ".csv", "--summary", base + ".json"});
        rc != 0) {
      return rc;
    }
    work_done = wall_s();
  }

  stage("== 5/5 report");
  progress.update(work_done, "writing the report");
  HtmlTable runs_table;
  runs_table.title = "Closed-loop runs";
  runs_table.header = {"run", "what", "fell", "simulated / motion [s]", "tracking RMS legs / arms [rad]", "CoM error max [m]",
                       "ZMP margin min [m]", "estimator velocity RMS [m/s]", "WBC tick p50 / p99 / max [µs]",
                       "planner p50 / p99 [ms]", "deadline misses"};
  for (const Case& c : cases) runs_table.rows.push_back(cells(c));
  runs_table.note = "Compute times are wall-clock on this machine (shared, noisy); the logs are deterministic.";
  std::ofstream md(out + "/REPORT.md");
  md << "# Kuavo 4Pro demo report\n\n"
     << "Open `index.html` for the 3D replay of every run, with plots and the timeline.\n\n"
     << "Pipeline: " << (input.empty() ? "built-in human dance (BVH)" : "human dance " + input + " (BVH)")
     << " → geometric retargeting → contact schedule → "
     << (kinematic ? "balance filter " : "feasibility repair → dynamic retargeting (trajectory optimization) ")
     << "→ online stack in the Simbody simulator (state estimator, " << stack::to_string(planner_kind)
     << " planner at 50 Hz, whole-body control at 500 Hz, drive PD + feed-forward torque).\n\n"
     << "## Closed-loop runs\n\n" << markdown_table(runs_table);
  md << "\n" << runs_table.note << " "
     << "Each run has its CSV log (one row per 2 ms tick), summary JSON and three plots: "
     << "`<run>_tracking.svg` (joints against the plan), `<run>_com.svg` (CoM against the plan), "
     << "`<run>_zmp.svg` (ZMP against the support polygon, margin, top view).\n\n";
  for (const Case& c : cases) {
    md << "### " << c.name << "\n\n![tracking](" << c.name << "_tracking.svg)\n\n![CoM](" << c.name
       << "_com.svg)\n\n![ZMP](" << c.name << "_zmp.svg)\n\n";
  }
  // The horizon experiment: knee trajectories and foot placements, 1.2 s against 0.6 s.
  const Case& long_h = cases[1];
  const Case& short_h = cases[2];
  if (!write_horizon_plots(long_h.trace, short_h.trace, out + "/horizon", error)) std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
  auto outcome = [](const Case& c) {
    return c.summary.run.fell ? "fell at " + std::to_string(c.summary.run.fell_at_s).substr(0, 5) + " s" : std::string("did not fall");
  };
  md << "## MPC horizon experiment (carpet, 10 N·s sideways push at " << push_at_s << " s)\n\n"
     << "Horizon 1.2 s: " << outcome(long_h) << "; horizon 0.6 s: " << outcome(short_h)
     << ". Knee trajectories: `horizon_knee.svg`; foot placements: `horizon_feet.svg`.\n\n"
     << "![knee](horizon_knee.svg)\n\n![feet](horizon_feet.svg)\n\n";
  if (kinematic) {
    md << "## Balance filter on the dance\n\n"
       << "CoM corrected by up to " << filter.max_correction_m << " m; cart-table ZMP outside the support up to "
       << filter.zmp_outside_before_m << " m before, " << filter.zmp_outside_after_m << " m after; "
       << filter.frames_in_flight << " frames in flight.\n\n";
  } else {
    md << "## Dynamic retargeting (the paper's Figs. 4 and 5, geometric vs dynamic)\n\n"
       << "The numbers are in `retarget_report.json` → `dynamic` (RNEA oracle, repairs, expressiveness).\n\n"
       << "![Fig. 4](fig4_knee.svg)\n\n![Fig. 5](fig5_dynamics.svg)\n\n";
  }
  md << "## Retargeting the " << dance_name << " (`dance.motion`, `dance.csv`" << (input.empty() ? ", `dance.bvh`" : "")
     << ", `human.csv`)\n\n```json\n"
     << slurp(out + "/retarget_report.json") << "\n```\n\n"
     << "## Standing, 10 N·s forward push at t = 5 s\n\n";
  for (const char* ground : {"floor", "carpet"}) {
    md << "### " << ground << " (`stand_" << ground << ".csv`)\n\n```json\n"
       << slurp(out + "/stand_" + ground + ".json") << "```\n\n";
  }
  if (!md) {
    std::fprintf(stderr, "kuavo demo: cannot write %s/REPORT.md\n", out.c_str());
    return 1;
  }

  // index.html: the same tables, the runs replayed.
  HtmlReport page;
  page.title = "Kuavo 4Pro demo: " + dance_name;
  page.subtitle = std::string("BVH → geometric retargeting → contacts → ") +
                  (kinematic ? "balance filter" : "feasibility repair → dynamic retargeting") +
                  " → online stack (estimator, " + stack::to_string(planner_kind) + " planner 50 Hz, WBC 500 Hz) in the Simbody simulator.";
  if (!read_repairs(out + "/retarget_report.json", page.repairs, error)) std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
  page.human_csv = out + "/human.csv";
  for (const Case& c : cases) {
    ReplayRun r{c.name, c.description, out + "/" + c.name + ".csv", c.summary.run.fell, c.summary.run.fell_at_s,
                c.name.rfind("dance", 0) == 0, {}};
    if (c.name.rfind("dance_carpet", 0) == 0) r.marks.push_back({push_at_s, push_at_s + 0.1, "push", "10 N·s sideways push"});
    page.runs.push_back(r);
  }
  HtmlTable horizon{"MPC horizon experiment (carpet, 10 N·s sideways push)", {"MPC horizon", "outcome", "tracking RMS legs [rad]", "ZMP margin min [m]"}, {}, ""};
  for (const Case* c : {&long_h, &short_h}) {
    horizon.rows.push_back({c == &long_h ? "1.2 s" : "0.6 s", outcome(*c), cells(*c)[4], cells(*c)[6]});
  }
  HtmlTable stand_table{"Standing, 10 N·s forward push at t = 5 s", {"ground", "fell", "max tilt [deg]", "min base height [m]"}, {}, ""};
  for (const char* ground : {"floor", "carpet"}) {
    const std::string base = out + "/stand_" + ground;
    page.runs.push_back({std::string("stand_") + ground, std::string("standing 10 s, ") + ground + ", 10 N·s forward push at 5 s",
                         base + ".csv", false, -1.0, false, {{5.0, 5.1, "push", "10 N·s forward push"}}});
    const auto j = nlohmann::json::parse(slurp(base + ".json"), nullptr, false);
    if (j.is_object()) {
      ReplayRun& r = page.runs.back();
      r.fell = j.value("fell", false);
      r.fell_at_s = j.value("fell_at_s", -1.0);
      char tilt[32], height[32];
      std::snprintf(tilt, sizeof tilt, "%.2f", j.value("max_tilt_deg", 0.0));
      std::snprintf(height, sizeof height, "%.3f", j.value("min_base_height_m", 0.0));
      stand_table.rows.push_back({ground, r.fell ? "fell at " + std::to_string(r.fell_at_s).substr(0, 5) + " s" : "no", tilt, height});
    }
  }
  page.tables = {runs_table, horizon, stand_table};
  if (!kinematic) page.figures = {{"fig4_knee.svg", "Fig. 4: knee angle and torque, geometric vs dynamic retargeting"},
                                  {"fig5_dynamics.svg", "Fig. 5: swing-leg and arm speeds, stance-foot lateral force, ZMP"}};
  page.figures.push_back({"horizon_knee.svg", "carpet: left knee, MPC horizon 1.2 s vs 0.6 s"});
  page.figures.push_back({"horizon_feet.svg", "carpet: touchdown positions, MPC horizon 1.2 s vs 0.6 s"});
  for (const Case& c : cases) {
    for (const char* kind : {"tracking", "com", "zmp"}) page.figures.push_back({c.name + "_" + kind + ".svg", c.name + ": " + kind});
  }
  page.text_blocks = {{"Retargeting (retarget_report.json)", slurp(out + "/retarget_report.json")}};
  for (const char* ground : {"floor", "carpet"}) {
    page.text_blocks.push_back({std::string("Standing on ") + ground + " (stand_" + ground + ".json)", slurp(out + "/stand_" + ground + ".json")});
  }
  if (!write_html_report(*robot, page, out, error)) {
    progress.clear();
    std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
    return 1;
  }
  progress.clear();
  std::printf("report: %s/index.html (tables also in %s/REPORT.md)\n", out.c_str(), out.c_str());
  return 0;
}

}  // namespace kuavo::cli
