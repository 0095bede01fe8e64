// kuavo demo [--out DIR] [--planner mpc|kinematic]: the main job. The built-in dance
// through the whole pipeline into the simulator, with a report folder:
//   1. the built-in human dance (BVH, generated) -> geometric retargeting -> contact
//      schedule -> feasibility repair -> dynamic retargeting -> dance.motion (+ CSV,
//      retarget_report.json, fig4_knee.svg, fig5_dynamics.svg); with --planner kinematic the
//      geometric stage only, then the balance filter;
//   2. the online stack (estimator, centroidal RTI-MPC at 50 Hz,
//      WBC at 500 Hz) dancing it on the Simbody plant: floor, and carpet with the MPC
//      horizon at 1.2 s and at 0.6 s — the paper's horizon experiment, with the knee
//      trajectories and foot placements of both (dance_*.csv/json/svg, horizon_*.svg);
//   3. 20 steps in place on the floor (steps_floor.*);
//   4. standing 10 s on floor and carpet with a 10 N·s push (stand_*.csv/json);
//   5. REPORT.md: a table of every run's figures and links to the plots.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "rtos_shim/args.h"
#include "sim/motion_loop.h"
#include "tools/cli/commands.h"
#include "tools/cli/motion_input.h"
#include "tools/mocap/motion_plan_io.h"
#include "tools/cli/motion_report.h"
#include "tools/report/svg_plot.h"

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
  sim::MotionTrace trace;
};

// Sole-centre positions at each touchdown (the foot's load rising through 100 N after it
// had been below 5 N), as dots: one point between NaN separators.
report::Series touchdowns(const std::string& name, const sim::MotionTrace& t, const std::string& color) {
  report::Series s;
  s.name = name;
  s.color = color;
  const double nan = std::nan("");
  std::array<bool, 2> up{false, false};
  for (std::size_t i = 0; i < t.foot_force_z_N.size(); ++i) {
    for (int foot = 0; foot < 2; ++foot) {
      const double f = t.foot_force_z_N[i][foot];
      if (f < 5.0) up[foot] = true;
      if (up[foot] && f > 100.0) {
        up[foot] = false;
        s.x.insert(s.x.end(), {nan, t.foot_xy_m[i][2 * foot]});
        s.y.insert(s.y.end(), {nan, t.foot_xy_m[i][2 * foot + 1]});
      }
    }
  }
  return s;
}

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
  std::string out = "demo_report", planner_name = "mpc";
  stack::PlannerKind planner_kind = stack::PlannerKind::kMpc;
  args::Parser p("kuavo demo");
  p.text("--out", "DIR", &out);
  p.choice("--planner", {"mpc", "kinematic"}, &planner_name);
  constexpr const char* kUsage = "usage: kuavo demo [--out DIR] [--planner mpc|kinematic]\n";
  switch (p.parse(argc, argv)) {
    case args::Parser::Result::kHelp:
      std::fputs(kUsage, stdout);
      return 0;
    case args::Parser::Result::kError:
      std::fprintf(stderr, "%s\n%s", p.error().c_str(), kUsage);
      return 2;
    case args::Parser::Result::kOk:
      break;
  }
  stack::parse_planner(planner_name.c_str(), planner_kind);  // one of the two names
  // The report folder: created (or already one) before the long run.
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (!std::filesystem::is_directory(out, ec)) {
    std::fprintf(stderr, "kuavo demo: --out %s: cannot create the directory\n", out.c_str());
    return 2;
  }
  std::printf("== 1/5 retargeting the built-in dance\n");
  const bool kinematic = planner_kind == stack::PlannerKind::kKinematic;
  std::vector<std::string> retarget_args = {"retarget", "-o", out + "/dance.motion", "--csv", out + "/dance.csv",
                                            "--dance-bvh", out + "/dance.bvh", "--report", out + "/retarget_report.json"};
  if (kinematic) retarget_args.insert(retarget_args.end(), {"--stage", "geometric"});
  if (const int rc = call(run_retarget, retarget_args); rc != 0) return rc;
  auto robot = std::make_unique<model::Model>();
  if (model::build_model(model::Variant::kS45, model::kDefaultTotalMass_kg, *robot) != model::ModelError::kOk) return 1;
  auto dance = std::make_unique<planner::MotionPlan>();
  auto steps = std::make_unique<planner::MotionPlan>();
  std::string error;
  planner::BalanceFilterReport filter;
  if (!mocap::load_motion_plan(out + "/dance.motion", *robot, *dance, error) ||
      (kinematic && !filter_motion_plan(*robot, *dance, filter, error)) || !make_step_plan(*robot, 20, *steps, error)) {
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
    Case c{name, description, {}, {}};
    c.summary = sim::run_motion(*robot, plan, cfg, &c.trace);
    std::ofstream(out + "/" + name + ".json") << sim::motion_summary_json(c.summary);
    if (!write_motion_plots(*robot, c.trace, out + "/" + name, name, error)) std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
    cases.push_back(std::move(c));
  };
  std::printf("== 2/5 the dance in the simulator (%s planner)\n", stack::to_string(planner_kind));
  sim::MotionRunConfig floor_cfg;
  run_case("dance_floor", "built-in dance, floor, estimator", *dance, floor_cfg);
  sim::MotionRunConfig carpet_cfg;
  carpet_cfg.run.ground = sim::kCarpet;
  carpet_cfg.run.push.start_s = 15.0;  // the disturbance: 10 N·s sideways on the torso
  carpet_cfg.run.push.duration_s = 0.1;
  carpet_cfg.run.push.force_N = sim::Vec3(0.0, 100.0, 0.0);
  carpet_cfg.stack.mpc.horizon_s = 1.2;
  run_case("dance_carpet", "built-in dance, carpet, 10 N·s push at 15 s, estimator, MPC horizon 1.2 s", *dance, carpet_cfg);
  carpet_cfg.stack.mpc.horizon_s = 0.6;
  run_case("dance_carpet_h06", "built-in dance, carpet, 10 N·s push at 15 s, estimator, MPC horizon 0.6 s", *dance, carpet_cfg);
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
     << "Pipeline: built-in human dance (BVH) → geometric retargeting → contact schedule → "
     << (kinematic ? "balance filter " : "feasibility repair → dynamic retargeting (trajectory optimization) ")
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
  // The horizon experiment: knee trajectories and foot placements, 1.2 s against 0.6 s.
  const Case& long_h = cases[1];
  const Case& short_h = cases[2];
  report::Plot knee;
  knee.title = "carpet: left knee, MPC horizon 1.2 s vs 0.6 s";
  knee.x_label = "time [s]";
  knee.y_label = "knee [rad]";
  auto knee_series = [&](const std::string& name, const sim::MotionTrace& t, bool plan, const std::string& color) {
    report::Series s;
    s.name = name;
    s.color = color;
    s.dashed = plan;
    s.x = t.time_s;
    for (std::size_t i = 0; i < t.q.size(); ++i) s.y.push_back((plan ? t.q_ref[i] : t.q[i])[model::kLeftLegFirst + 3]);
    return s;
  };
  knee.series = {knee_series("plan", long_h.trace, true, "#7f7f7f"), knee_series("horizon 1.2 s", long_h.trace, false, "#1f77b4"),
                 knee_series("horizon 0.6 s", short_h.trace, false, "#d62728")};
  report::Plot feet;
  feet.title = "carpet: touchdown positions (sole centres), top view";
  feet.x_label = "x [m]";
  feet.y_label = "y [m]";
  feet.equal_axes = true;
  feet.height_px = 420;
  feet.series = {touchdowns("horizon 1.2 s", long_h.trace, "#1f77b4"), touchdowns("horizon 0.6 s", short_h.trace, "#d62728")};
  if (!report::write_text_file(out + "/horizon_knee.svg", report::render_svg(knee), &error) ||
      !report::write_text_file(out + "/horizon_feet.svg", report::render_svg(feet), &error)) {
    std::fprintf(stderr, "kuavo demo: %s\n", error.c_str());
  }
  auto outcome = [](const Case& c) {
    return c.summary.run.fell ? "fell at " + std::to_string(c.summary.run.fell_at_s).substr(0, 5) + " s" : std::string("did not fall");
  };
  md << "## MPC horizon experiment (carpet, 10 N·s sideways push at 15 s)\n\n"
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
  md << "## Retargeting the built-in dance (`dance.motion`, `dance.csv`, `dance.bvh`)\n\n```json\n"
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
