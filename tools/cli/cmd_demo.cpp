// kuavo demo [--out DIR] [--planner kinematic|mpc]: the main job. The built-in dance
// through the whole pipeline into the simulator, with a report folder:
//   1. the built-in human dance (BVH, generated) -> geometric retargeting -> contact
//      schedule -> dance.motion (+ CSV, retarget_report.json);
//   2. the balance filter, then the online stack (estimator, planner, 500 Hz WBC) dancing
//      it on the Simbody plant: floor and carpet with the estimator, and the floor once
//      more on the simulator's true state for comparison (dance_*.csv/json/svg);
//   3. 20 steps in place on the floor (steps_floor.*);
//   4. standing 10 s on floor and carpet with a 10 N·s push (stand_*.csv/json);
//   5. REPORT.md: a table of every run's figures and links to the plots.
#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "sim/motion_loop.h"
#include "tools/cli/commands.h"
#include "tools/cli/motion_input.h"
#include "tools/cli/motion_report.h"

namespace kuavo::cli {
namespace {

int call(int (*run)(int, char**), std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return run(static_cast<int>(args.size()), argv.data());
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return s;
}

struct Case {
  std::string name, description;
  sim::MotionSummary summary;
};

std::string row(const Case& c) {
  const sim::MotionSummary& s = c.summary;
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "| %s | %s | %s | %.1f / %.1f | %.3f / %.3f | %.3f | %.3f (%.2f s at edge) | %.3f | %.0f / %.0f / %.0f | %.2f / %.2f | %llu |\n",
                c.name.c_str(), c.description.c_str(),
                !s.run.ok ? "sim error" : (s.run.fell ? ("**fell at " + std::to_string(s.run.fell_at_s).substr(0, 5) + " s**").c_str() : "no"),
                s.run.sim_time_s, s.motion_duration_s, s.tracking_rms_legs_rad, s.tracking_rms_arms_rad, s.com_err_m_max,
                s.zmp_margin_m_min, s.zmp_at_edge_s, s.estimator_velocity_rms_m_s, s.wbc_us.p50, s.wbc_us.p99,
                s.wbc_us.max, s.mpc_ms.p50, s.mpc_ms.p99, static_cast<unsigned long long>(s.deadline_misses));
  return buf;
}

}  // namespace

int run_demo(int argc, char** argv) {
  std::string out = "demo_report";
  stack::PlannerKind planner_kind = stack::PlannerKind::kKinematic;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--out") && i + 1 < argc) {
      out = argv[++i];
    } else if (!std::strcmp(argv[i], "--planner") && i + 1 < argc && stack::parse_planner(argv[i + 1], planner_kind)) {
      ++i;
    } else {
      std::fprintf(stderr, "usage: kuavo demo [--out DIR] [--planner kinematic|mpc]\n");
      return 2;
    }
  }
  ::mkdir(out.c_str(), 0755);
  std::printf("== 1/5 retargeting the built-in dance\n");
  if (const int rc = call(run_retarget, {"retarget", "-o", out + "/dance.motion", "--csv", out + "/dance.csv",
                                         "--dance-bvh", out + "/dance.bvh", "--report", out + "/retarget_report.json"});
      rc != 0) {
    return rc;
  }
  auto robot = std::make_unique<model::Model>();
  if (model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, *robot) != model::ModelError::kOk) return 1;
  auto dance = std::make_unique<planner::MotionPlan>();
  auto steps = std::make_unique<planner::MotionPlan>();
  std::string error;
  planner::BalanceFilterReport filter;
  if (!load_motion_plan(out + "/dance.motion", *robot, *dance, error) || !filter_motion_plan(*robot, *dance, filter, error) ||
      !make_step_plan(*robot, 20, *steps, error)) {
    std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
    return 1;
  }

  std::vector<Case> cases;
  auto run_case = [&](const std::string& name, const std::string& description, const planner::MotionPlan& plan,
                      sim::MotionRunConfig cfg) {
    std::printf("   %s: %s\n", name.c_str(), description.c_str());
    std::fflush(stdout);
    cfg.stack.planner = planner_kind;
    cfg.run.log_path = out + "/" + name + ".csv";
    sim::MotionTrace trace;
    Case c{name, description, sim::run_motion(*robot, plan, cfg, &trace)};
    std::ofstream(out + "/" + name + ".json") << sim::motion_summary_json(c.summary);
    if (!write_motion_plots(*robot, trace, out + "/" + name, name, error)) std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
    cases.push_back(c);
  };
  std::printf("== 2/5 the dance in the simulator (%s planner)\n", stack::to_string(planner_kind));
  sim::MotionRunConfig floor_cfg;
  run_case("dance_floor", "built-in dance, floor, estimator", *dance, floor_cfg);
  sim::MotionRunConfig carpet_cfg;
  carpet_cfg.run.ground = sim::kCarpet;
  run_case("dance_carpet", "built-in dance, carpet, estimator", *dance, carpet_cfg);
  sim::MotionRunConfig truth_cfg;
  truth_cfg.use_truth_state = true;
  run_case("dance_floor_truth", "built-in dance, floor, true state (comparison)", *dance, truth_cfg);
  std::printf("== 3/5 stepping in place\n");
  run_case("steps_floor", "20 steps in place, floor, estimator", *steps, sim::MotionRunConfig{});

  std::printf("== 4/5 standing in the simulator (floor, carpet; 10 N·s push at 5 s)\n");
  for (const char* ground : {"floor", "carpet"}) {
    const std::string base = out + "/stand_" + ground;
    if (const int rc = call(run_simulate, {"simulate", "--stand", "10", "--ground", ground, "--push", "5:100,0,0:0.1",
                                           "--log", base + ".csv", "--summary", base + ".json"});
        rc != 0) {
      return rc;
    }
  }

  std::printf("== 5/5 report\n");
  std::ofstream md(out + "/REPORT.md");
  md << "# Kuavo 4Pro demo report\n\n"
     << "Pipeline: built-in human dance (BVH) → geometric retargeting → contact schedule → balance filter "
     << "→ online stack in the Simbody simulator (state estimator, " << stack::to_string(planner_kind)
     << " planner at 50 Hz, whole-body control at 500 Hz, drive PD + feed-forward torque).\n\n"
     << "## Closed-loop runs\n\n"
     << "| run | what | fell | simulated / motion [s] | tracking RMS legs / arms [rad] | CoM error max [m] "
     << "| ZMP margin min [m] | estimator velocity RMS [m/s] | WBC tick p50 / p99 / max [µs] | planner p50 / p99 [ms] | deadline misses |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Case& c : cases) md << row(c);
  md << "\nCompute times are wall-clock on this machine (shared, noisy); the logs are deterministic. "
     << "Each run has its CSV log (one row per 2 ms tick), summary JSON and three plots: "
     << "`<run>_tracking.svg` (joints against the plan), `<run>_com.svg` (CoM against the plan), "
     << "`<run>_zmp.svg` (ZMP against the support polygon, margin, top view).\n\n";
  for (const Case& c : cases) {
    md << "### " << c.name << "\n\n![tracking](" << c.name << "_tracking.svg)\n\n![CoM](" << c.name
       << "_com.svg)\n\n![ZMP](" << c.name << "_zmp.svg)\n\n";
  }
  md << "## Balance filter on the dance\n\n"
     << "CoM corrected by up to " << filter.max_correction_m << " m; cart-table ZMP outside the support up to "
     << filter.zmp_outside_before_m << " m before, " << filter.zmp_outside_after_m << " m after; "
     << filter.frames_in_flight << " frames in flight.\n\n"
     << "## Retargeting the built-in dance (`dance.motion`, `dance.csv`, `dance.bvh`)\n\n```json\n"
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
  std::printf("report: %s/REPORT.md\n", out.c_str());
  return 0;
}

}  // namespace kuavo::cli
